"""A kernel's parameter has one name in every unit: aggregation, breakage selection and fragment parameters carry
agg_, sel_ and frag_ in the fluid bed as in pbm_batch and the other units (docs/scene_format.md). The fluid bed's bare
names of earlier versions (bed.ln_beta0 ...) are deprecated aliases: they set the same parameter and warn once per
process, naming the new name. No simulation runs here."""
import os
import subprocess
import sys

import granuflow as gf
from conftest import PKG_PATH, ROOT, SCENE, package_env

PBM = os.path.join(ROOT, "flowsheets", "pbm_constant_kernel.yaml")


def load_text(tmp_path, text, name):
    path = tmp_path / name
    path.write_text(text)
    return gf.load(str(path))


def test_one_kernel_has_the_same_parameter_names_in_the_fluid_bed_and_in_pbm_batch(tmp_path):
    pbm = open(PBM).read().replace("{aggregation: constant,", "{aggregation: eke,").replace(", agg_beta0: 1 1/s", "")
    bed = open(SCENE).read().replace("    params: {bed_mass: 15 kg,",
                                     "    settings: {aggregation: eke}\n    params: {bed_mass: 15 kg,", 1)
    in_pbm = {p.split(".", 1)[1] for p in load_text(tmp_path, pbm, "pbm.yaml").params if p.startswith("pbm.")}
    in_bed = {p.split(".", 1)[1] for p in load_text(tmp_path, bed, "bed.yaml").params if p.startswith("bed.")}
    assert {"agg_ln_beta0", "agg_tau_spray"} <= in_pbm & in_bed
    assert not {"ln_beta0", "tau_spray"} & (in_pbm | in_bed)
    # the paper-001 defaults: glass-transition aggregation, Vogel-Peukert breakage, tanh power-law fragments
    headline = set(gf.load(SCENE).params)
    assert {"bed.agg_ln_beta0", "bed.agg_Tg_solid", "bed.sel_k_break", "bed.frag_q_frag"} <= headline
    assert not {"bed.ln_beta0", "bed.Tg_solid", "bed.k_break", "bed.q_frag"} & headline


def test_old_spellings_set_the_same_parameter_and_warn_once(tmp_path):
    scene = tmp_path / "old.yaml"
    scene.write_text(open(SCENE).read().replace("params: {bed_mass: 15 kg,",
                                                "params: {ln_beta0: -16.5, k_break: 2.0e-3, bed_mass: 15 kg,", 1))
    code = ("import granuflow as gf\n"
            f"fs = gf.load({str(scene)!r})\n"
            "print(fs.get('bed.agg_ln_beta0'), fs.get('bed.ln_beta0'), fs.get('bed.sel_k_break'))\n"
            "fs.set('bed.ln_beta0', -17.5)\n"
            "print(fs.get('bed.agg_ln_beta0'))\n")
    p = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120,
                       env=package_env(), cwd=PKG_PATH)
    assert p.returncode == 0, p.stderr
    assert p.stdout.split() == ["-16.5", "-16.5", "0.002", "-17.5"]
    warnings = [line for line in p.stderr.splitlines() if "deprecated" in line]
    assert warnings == [
        "granuflow: warning: parameter 'bed.ln_beta0' is deprecated, it is now 'bed.agg_ln_beta0' "
        "(a kernel's parameter has one name in every unit)",
        "granuflow: warning: parameter 'bed.k_break' is deprecated, it is now 'bed.sel_k_break' "
        "(a kernel's parameter has one name in every unit)"]
