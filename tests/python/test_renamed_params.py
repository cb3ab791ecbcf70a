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


BED_PARAMS = "    params: {bed_mass: 15 kg,"


def _run_code(code):
    p = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120,
                       env=package_env(), cwd=PKG_PATH)
    return p, [line for line in p.stderr.splitlines() if "deprecated" in line]


def test_old_setting_spellings_read_the_same_setting_and_warn_once(tmp_path):
    """The fluid bed's kernel settings carry the family prefixes of every other unit (agg_beta0_basis, sel_size_unit);
    the bare and breakage_ spellings still select the same choice (per_m3 declares agg_V_vessel) and warn once."""
    old = tmp_path / "old.yaml"
    old.write_text(open(SCENE).read().replace(
        BED_PARAMS, "    settings: {beta0_basis: per_m3, breakage_size_unit: mm}\n" + BED_PARAMS, 1))
    code = ("import granuflow as gf\n"
            f"fs = gf.load({str(old)!r})\n"
            f"gf.load({str(old)!r})\n"
            "s = {x['name']: x['value'] for x in fs.setting_specs()['bed']}\n"
            "print(s['agg_beta0_basis'], s['sel_size_unit'], 'bed.agg_V_vessel' in fs.params)\n")
    p, warnings = _run_code(code)
    assert p.returncode == 0, p.stderr
    assert p.stdout.split() == ["per_m3", "mm", "True"]
    assert len(warnings) == 2, p.stderr  # once per process, though the scene is loaded twice
    assert "units.bed.settings.beta0_basis' is deprecated, it is now 'agg_beta0_basis'" in warnings[0]
    assert "units.bed.settings.breakage_size_unit' is deprecated, it is now 'sel_size_unit'" in warnings[1]
    assert not {"beta0_basis", "breakage_size_unit"} & {x["name"] for x in gf.load(SCENE).setting_specs()["bed"]}


def test_both_spellings_of_one_setting_are_refused(tmp_path):
    both = tmp_path / "both.yaml"
    both.write_text(open(SCENE).read().replace(
        BED_PARAMS, "    settings: {breakage_size_unit: mm, sel_size_unit: um}\n" + BED_PARAMS, 1))
    try:
        gf.load(str(both))
    except ValueError as e:
        assert "both 'breakage_size_unit' and its new name 'sel_size_unit' are given" in str(e)
    else:
        raise AssertionError("a setting given under both its names was accepted")


def test_an_event_and_a_controller_may_name_the_old_spelling(tmp_path):
    """An event that switches bed.breakage_size_unit switches sel_size_unit: the run is bit-identical to the one
    written with the new name. A PI controller driving bed.k_break drives bed.sel_k_break."""
    texts = {}
    for name in ("breakage_size_unit", "sel_size_unit"):
        path = tmp_path / f"{name}.yaml"
        path.write_text(open(SCENE).read().replace("\nsummary:", "\nevents:\n  - {name: mm, when: bed.d50 >= 300 um, "
                                                   f"do: {{set: {{bed.{name}: mm}}}}}}\nsummary:", 1))
        texts[name] = str(path)
    ctrl = tmp_path / "ctrl.yaml"
    ctrl.write_text(open(SCENE).read().replace("\nconnections:", "\n  ctrl:\n    type: pi_controller\n"
                                               "    settings: {measure: bed.d50, drive: bed.k_break}\n"
                                               "\nconnections:", 1))
    code = ("import granuflow as gf\n"
            f"a = gf.load({texts['breakage_size_unit']!r}).simulate()\n"
            f"b = gf.load({texts['sel_size_unit']!r}).simulate()\n"
            "print(a['bed.d50'][-1] == b['bed.d50'][-1], a['bed.d50'][-1])\n"
            f"fs = gf.load({str(ctrl)!r})\n"
            "print(fs.spec('ctrl.u0')['unit'], fs.get('ctrl.u0') == fs.get('bed.sel_k_break'))\n")
    p, warnings = _run_code(code)
    assert p.returncode == 0, p.stderr
    same, d50, unit, start = p.stdout.split()
    assert same == "True" and start == "True" and unit == "1/s"
    # the switch to mm changes Eq. (92)'s fit from then on: the run differs from the headline's 499.70 um
    assert abs(float(d50) * 1e6 - 499.701648945565) > 1.0
    assert "parameter 'bed.k_break' is deprecated, it is now 'bed.sel_k_break'" in "\n".join(warnings)
