"""The catalogue of solid materials (docs/materials.md): a scene that names a material gets its published values as
the defaults of the parameters they describe, the scene's own params still win, what the material does not give is
said (never silently another material's value), and the command line lists the catalogue."""
import json
import os
import pathlib
import subprocess
import sys

import pytest

import granuflow as gf
from granuflow import materials

ROOT = pathlib.Path(__file__).resolve().parents[2]
HEADLINE = ROOT / "flowsheets" / "stoeckl_gf25_batch.yaml"


def headline_with(particles_extra: str, params: str = "") -> str:
    """The headline scene's text without its material, with `particles_extra` lines in its particles: section (and
    bed params added)."""
    lines = HEADLINE.read_text().splitlines(keepends=True)
    text = "".join(x for x in lines if not x.startswith("  material:"))
    assert "particles:\n  settings:" in text
    text = text.replace("particles:\n  settings:", "particles:\n" + particles_extra + "  settings:", 1)
    if params:
        text = text.replace("params: {bed_mass: 15 kg,", "params: {" + params + ", bed_mass: 15 kg,", 1)
    return text


def load(text: str, tmp_path: pathlib.Path) -> "gf.Flowsheet":
    tmp_path.mkdir(exist_ok=True)
    path = tmp_path / "scene.yaml"
    path.write_text(text)
    return gf.load(str(path))


def test_catalogue_holds_the_three_materials_with_sources():
    names = [m["name"] for m in materials.catalogue()]
    assert names == ["maltodextrin_de21", "gamma_alumina", "sodium_benzoate"]
    for m in materials.catalogue():
        assert m["citation"] and m["description"]
        for p in m["properties"]:
            assert p["source"], (m["name"], p["name"])
            assert p["value"] == p["value"] and p["value"] > 0


def test_maltodextrin_is_exactly_paper_001s_built_in_values(tmp_path):
    """Naming paper 001's material changes no value: the catalogue entry and the units' defaults agree, so the
    headline's answer is the same to the last bit; the sources now name the material."""
    plain = load(headline_with(""), tmp_path / "plain")
    named = load(headline_with("  material: maltodextrin_de21\n"), tmp_path)
    mat = materials.material("maltodextrin_de21")
    touched = 0
    for q in named.params:
        assert named.get(q) == plain.get(q), q
        if named.spec(q)["source"].startswith("material maltodextrin_de21: "):
            prop = q.split(".")[1].removeprefix("agg_")
            assert named.get(q) == next(p["value"] for p in mat["properties"] if p["name"] == prop)
            touched += 1
    assert touched >= 10  # particles (4), glass transition (4), sorption and drying (3)
    assert named.simulate(warn=False).summary["d50_um"] == plain.simulate(warn=False).summary["d50_um"]
    assert named.material == {"name": "maltodextrin_de21", "built_in": {}, "note": None}
    assert plain.material["name"] is None and "paper 001's maltodextrin" in plain.material["note"]


def test_a_material_changes_the_solid_and_what_it_lacks_is_said(tmp_path):
    """Sodium benzoate gives a density (1440 kg/m3) but no glass-transition or sorption data: the density is
    applied, the rest keeps the built-in values openly (describe's source, Flowsheet.material, summary.json)."""
    fs = load(headline_with("  material: sodium_benzoate\n"), tmp_path)
    assert fs.get("particles.rho_s") == 1440.0
    assert fs.spec("particles.rho_s")["source"].startswith("material sodium_benzoate: PubChem")
    assert fs.spec("particles.rho_s")["default"] == 1440.0
    built_in = fs.material["built_in"]
    for q in ("particles.cp_s", "particles.eps_intra", "bed.agg_Tg_solid", "bed.agg_gt_k", "bed.bet_mm"):
        assert q in built_in, q
        assert fs.spec(q)["source"].startswith("not given by material sodium_benzoate; built-in value from paper 001")
    assert "particles.rho_s" not in built_in
    assert "sodium_benzoate gives no value for" in fs.material["note"]
    # the denser solid makes the same 15 kg a smaller volume of particles: a different (physical) answer
    s = fs.simulate(warn=False).summary
    assert s["material"]["name"] == "sodium_benzoate"
    assert s["d50_um"] != gf.load(str(HEADLINE)).simulate(warn=False).summary["d50_um"]


def test_the_scene_overrides_any_material_value(tmp_path):
    text = headline_with("  material: sodium_benzoate\n  params: {rho_s: 1500 kg/m3, cp_s: 1300}\n",
                         "agg_Tg_solid: 150 degC")
    fs = load(text, tmp_path)
    assert fs.get("particles.rho_s") == 1500.0
    assert fs.get("particles.cp_s") == 1300.0
    assert fs.get("bed.agg_Tg_solid") == pytest.approx(423.15)
    assert "particles.cp_s" not in fs.material["built_in"] and "bed.agg_Tg_solid" not in fs.material["built_in"]
    assert "particles.eps_intra" in fs.material["built_in"]


def test_a_scene_without_particles_has_no_material():
    assert gf.load(str(ROOT / "flowsheets" / "demo_tanks.yaml")).material is None


def test_unknown_material_is_one_line_naming_the_catalogue(tmp_path):
    with pytest.raises(gf.ConfigError) as e:
        load(headline_with("  material: unobtainium\n"), tmp_path)
    msg = str(e.value)
    assert "particles.material" in msg and "unobtainium" in msg
    assert "maltodextrin_de21" in msg and "sodium_benzoate" in msg and "\n" not in msg


def test_material_is_only_a_key_of_the_particle_system(tmp_path):
    text = HEADLINE.read_text().replace("    type: spray_zone\n", "    type: spray_zone\n    material: x\n", 1)
    with pytest.raises(gf.ConfigError, match="units.spray_zone.*material"):
        load(text, tmp_path)


def run_cli(*args: str) -> subprocess.CompletedProcess:
    env = dict(os.environ)
    return subprocess.run([sys.executable, "-m", "granuflow", *args], capture_output=True, text=True, env=env)


def test_command_line_lists_and_shows_materials():
    r = run_cli("materials")
    assert r.returncode == 0, r.stderr
    for name in ("maltodextrin_de21", "gamma_alumina", "sodium_benzoate"):
        assert name in r.stdout
    r = run_cli("materials", "maltodextrin_de21")
    assert r.returncode == 0, r.stderr
    assert "`particles.rho_s`" in r.stdout and "paper 001, Table 6" in r.stdout and "1545" in r.stdout
    assert "`fluid_bed.agg_Tg_solid`" in r.stdout
    r = run_cli("materials", "nope")
    assert r.returncode == 2 and "known: maltodextrin_de21" in r.stderr


def test_summary_json_names_the_material(tmp_path):
    scene = tmp_path / "scene.yaml"
    scene.write_text(headline_with("  material: maltodextrin_de21\n"))
    r = run_cli("run", str(scene), "--out", str(tmp_path / "out"), "--no-plots", "--quiet")
    assert r.returncode == 0, r.stderr
    s = json.loads((tmp_path / "out" / "summary.json").read_text())
    assert s["material"]["name"] == "maltodextrin_de21"
