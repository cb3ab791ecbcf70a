"""Unit settings from the command line, in sweeps and in contour maps (issue 28, §4): a setting rebuilds the
flowsheet, checked as in a scene file; parameters carry over; a name both a parameter and a setting resolves by its
value."""
import json
import os

import pytest

from conftest import ROOT, SCENE, cli

import granuflow as gf
from granuflow import structure, sweep
from granuflow.design_space import contour_map

RTD = os.path.join(ROOT, "flowsheets", "tanks_in_series_rtd.yaml")


@pytest.fixture(scope="module")
def d50_by_classes():
    fs = gf.load(SCENE)
    return {n: fs.with_settings({"particles.classes": n}).simulate(warn=False).summary["d50_um"]
            for n in (10, 40, 160)}


def test_finer_grid_from_the_command_line_approaches_the_converged_d50(tmp_path, d50_by_classes):
    r = cli("run", SCENE, "--out", tmp_path, "--no-plots", "--quiet", "--set", "particles.classes=40")
    assert r.returncode == 0, r.stderr
    summary = json.load(open(tmp_path / "summary.json"))
    d50 = summary["d50_um"]
    assert d50 == d50_by_classes[40]
    # --quiet: nothing on stdout; on stderr the run's warnings, each once, and nothing else
    assert r.stdout == "" and summary["warnings"]
    assert r.stderr.splitlines() == [f"granuflow: warning: {w}" for w in summary["warnings"]]
    # a coarse grid smears mass to large sizes: 40 classes lie between the paper's 10 and the converged 160
    assert d50_by_classes[160] < d50 < d50_by_classes[10]
    assert abs(d50 - d50_by_classes[160]) < 0.2 * abs(d50_by_classes[10] - d50_by_classes[160])


def test_a_length_setting_takes_a_unit_at_the_edge_and_parameters_carry_over():
    fs = gf.load(SCENE).set("inlet.T", "50 degC")
    mm = fs.with_settings({"particles.d_max": "3 mm"})
    si = fs.with_settings({"particles.d_max": 0.003})
    assert mm.grid()["d_max"] == si.grid()["d_max"] and float(mm.grid()["d_max"]) == pytest.approx(3e-3)
    assert mm.get("inlet.T") == pytest.approx(323.15) and mm.t_end == fs.t_end
    a, b = mm.simulate(warn=False).summary["d50_um"], si.simulate(warn=False).summary["d50_um"]
    assert a == b and a != fs.simulate(warn=False).summary["d50_um"]
    assert fs.grid()["classes"] == "10"  # the original flowsheet is unchanged


def test_a_kernel_chosen_by_setting_changes_the_result():
    fs = gf.load(SCENE).set("bed.agg_ln_beta0", -30.0)  # a parameter the constant kernel does not have: dropped
    const = structure.apply(fs, {"bed.aggregation": "constant", "inlet.T": "70 degC"})
    assert const.unit_settings()["bed"][1]["aggregation"] == "constant"
    assert "bed.agg_ln_beta0" not in const.params and const.get("inlet.T") == pytest.approx(343.15)


@pytest.mark.parametrize("item, words", [
    ("particles.classes=5000", ["--set particles.classes=5000", "particles.settings.classes = 5000",
                                "3 <= classes <= 2000"]),
    ("particles.classes=4.5", ["particles.settings.classes = '4.5'", "expected an integer in [3, 2000]"]),
    ("particles.d_max=3 kg", ["particles.d_max = '3 kg'", "unit 'kg'", "SI unit m"]),
    ("bed.aggregation=kapurr", ["units.bed.settings.aggregation = 'kapurr'", "glass_transition", "kapur"]),
    ("particles.foo=1", ["unknown parameter 'particles.foo'", "rho_s", "settings of particles: grid, classes"]),
])
def test_a_bad_setting_is_one_line_naming_unit_value_and_what_is_allowed(tmp_path, item, words):
    r = cli("run", SCENE, "--out", tmp_path, "--no-plots", "--set", item)
    assert r.returncode == 2 and len(r.stderr.strip().splitlines()) == 1, r.stderr
    for w in words:
        assert w in r.stderr, (w, r.stderr)


def test_a_name_that_is_both_parameter_and_setting_resolves_by_its_value():
    fs = gf.load(RTD)
    assert structure.split(fs, {"tank_a1.bed_mass": "controlled"}) == ({"tank_a1.bed_mass": "controlled"}, {})
    assert structure.split(fs, {"tank_a1.bed_mass": "12 kg"}) == ({}, {"tank_a1.bed_mass": "12 kg"})
    with pytest.raises(gf.ConfigError, match="both a parameter .kg. and a setting .free, controlled."):
        structure.split(fs, {"tank_a1.bed_mass": "controled"})


def test_a_sweep_over_classes_builds_each_structure_once(tmp_path, d50_by_classes):
    p = tmp_path / "grid.yaml"
    p.write_text(f"""
scene: {SCENE}
variables:
  n: {{param: particles.classes, levels: [10, 40]}}
  T: {{param: inlet.T, unit: degC}}
points:
  - {{name: a, n: 10, T: 60}}
  - {{name: b, n: 40, T: 60}}
  - {{name: c, n: 10, T: 70}}
outputs: [d50_um]
""")
    sw = sweep.load_sweep(p)
    df = sw.run(progress=False, workers=1)
    assert df["n"].tolist() == [10, 40, 10] and (df["status"] == "ok").all()
    assert df["d50_um"].tolist()[:2] == [d50_by_classes[10], d50_by_classes[40]]
    assert df["d50_um"].iloc[2] != d50_by_classes[10]  # same structure, another parameter value
    bad = tmp_path / "bad.yaml"
    bad.write_text(p.read_text().replace("n: 40, T: 60", "n: 1, T: 60"))
    with pytest.raises(gf.ConfigError, match="particles.settings.classes = 1: violates 3 <= classes"):
        sweep.load_sweep(bad)


def test_a_contour_map_with_a_setting_and_a_categorical_axis():
    fs = gf.load(SCENE).set_t_end("10 min")
    grid = contour_map(fs, "particles.classes=10,20", "bed.aggregation=glass_transition,sum", ["d50_um"],
                       progress=False, workers=1)
    assert grid.ok.all() and grid.y.labels == ("glass_transition", "sum")
    df = grid.to_dataframe()
    assert df["bed.aggregation"].tolist() == ["glass_transition"] * 2 + ["sum"] * 2
    ref = fs.with_settings({"particles.classes": 20}).simulate(warn=False).summary["d50_um"]
    assert grid["d50_um"][0, 1] == ref and grid["d50_um"][1, 1] != ref
    with pytest.raises(gf.ConfigError, match="particles.settings.classes = 2: violates"):
        contour_map(fs, "particles.classes=2,10", "inlet.T:degC:60:60:1", ["d50_um"], progress=False)
