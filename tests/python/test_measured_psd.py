"""Issue 27, section 1: measured size distributions in, measured size distributions fitted (docs/measured_psd.md).

A measured table starts a bed, a feed or a pbm_batch with exactly the table's mass on the grid (and the measured
mass outside the grid reported and folded into the end classes); Python refuses bad tables with the core's one-line
messages; a scene naming a broken file exits 2 naming the setting, the file, the row and the value; the shipped
(made-up) example is what its generator writes; and a calibration fitting whole Q3 curves of it recovers the
aggregation rate the data were made with, with Q3 sensitivities that agree with central differences."""
import importlib.util
import math
import os

import numpy as np
import pytest
from conftest import ROOT, SCENE, cli

import granuflow as gf
from granuflow import calibration as cal
from granuflow import measured_psd as mp

CAL = os.path.join(ROOT, "flowsheets", "calibration")
SIEVE = os.path.join(ROOT, "flowsheets", "data", "gf25_example_sieve_start.csv")
MEASURED_SCENE = os.path.join(CAL, "gf25_measured_start.yaml")
EXPS = os.path.join(CAL, "gf25_example_q3.yaml")


def generator():
    spec = importlib.util.spec_from_file_location("make_psd_example", os.path.join(CAL, "make_psd_example.py"))
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def headline_with_bed_settings(settings: str) -> str:
    text = open(SCENE).read()
    old = "params: {bed_mass: 15 kg, X0: 0.030928, d50_0: 200 um, sigma_0: 1.5}"
    assert old in text
    return text.replace(old, "params: {bed_mass: 15 kg, X0: 0.030928}\n    settings: " + settings)


def test_shipped_example_is_what_its_generator_writes_and_says_it_is_made_up():
    g = generator()
    assert open(SIEVE).read() == g.sieve_text()
    assert open(MEASURED_SCENE).read() == g.scene_text()
    assert "MADE UP" in open(SIEVE).read()
    assert "MADE UP" in open(EXPS).read()


def test_a_measured_starting_bed_has_the_tables_mass_on_the_grid():
    fs = gf.load(MEASURED_SCENE)
    edges = np.array(fs.size_edges("bed"))
    assert len(edges) == 11
    mapped = mp.read(SIEVE).map_to_grid(edges)
    res = fs.simulate(t_end=1.0)
    dry = fs.get("bed.bed_mass") / (1 + fs.get("bed.X0"))
    m0 = np.array([res[f"bed.psd_m_{i}"][0] for i in range(10)])
    np.testing.assert_allclose(m0, dry * mapped["mass"], rtol=1e-12, atol=0)
    assert m0.sum() == pytest.approx(dry, rel=1e-14)
    # the pan lies just below 63 um and nothing is retained above 710 um: all inside the grid (41.8 to 1196 um)
    assert mapped["below"] == 0.0 and mapped["above"] == 0.0
    shifted = mp.table(mp.read(SIEVE).sizes_m * 2, mp.read(SIEVE).values, kind="retained").map_to_grid(edges)
    # twice the sizes: the 710 um sieve's class (1000 to 1420 um, 1.6 %) reaches 1.6 * ln(1420/1196) / ln(1420/1000)
    frac = 0.016 * math.log(1420 / (edges[-1] * 1e6)) / math.log(1420 / 1000)
    assert shifted["above"] == pytest.approx(frac, rel=1e-12) and shifted["below"] == 0.0
    assert res["bed.initial_psd_outside"][0] == pytest.approx(mapped["below"] + mapped["above"], rel=1e-15)


def test_table_from_python_arrays_is_the_same_as_the_file():
    t = mp.read(SIEVE)
    mp.set_table("test_sieve", mp.table(t.sizes_m, t.values, kind="retained", basis="mass"))
    assert "test_sieve" in mp.tables()
    fs = gf.load_text(headline_with_bed_settings("{initial_psd: table, initial_psd_table: test_sieve}"), "arrays")
    res = fs.simulate(t_end=1.0)
    ref = gf.load(MEASURED_SCENE).simulate(t_end=1.0)
    for i in range(10):
        assert res[f"bed.psd_m_{i}"][0] == ref[f"bed.psd_m_{i}"][0]


def test_the_lognormal_stays_the_default():
    fs = gf.load(SCENE)
    assert "bed.d50_0" in fs.params and "bed.initial_psd_outside" not in fs.output_names
    assert "bed.d50_0" not in gf.load(MEASURED_SCENE).params  # a table replaces the log-normal's parameters


@pytest.mark.parametrize("sizes, values, kind, part", [
    ([1e-4, 2e-4, 3e-4], [0.2, 0.6, 0.5], "Q", "row 3, column 2 (Q): Q decreases from 0.6 to 0.5"),
    ([1e-4, 2e-4, 4e-4], [0.2, -0.1, 0.9], "retained", "row 2, column 2 (retained): value -0.1 is negative"),
    ([1e-4, 1e-4, 4e-4], [0.2, 0.6, 1.0], "Q", "row 2, column 1 (size): size 0.0001 m does not increase"),
    ([1e-4, 2e-4, 4e-4], [0.2, 0.6, 0.97], "Q", "the last Q is 0.97: neither 1 nor 100 %"),
    ([1e-4, 2e-4, 4e-4], [0.2, math.nan, 1.0], "Q", "row 2, column 2 (Q): value nan is not a finite number"),
])
def test_bad_tables_from_arrays_are_refused_with_one_line(sizes, values, kind, part):
    with pytest.raises(ValueError) as e:
        mp.table(sizes, values, kind=kind)
    assert part in str(e.value) and "\n" not in str(e.value)


def test_a_scene_naming_a_bad_file_exits_2_naming_setting_file_row_and_value(tmp_path):
    bad = tmp_path / "bed.csv"
    bad.write_text("size_um,Q3\n100,0.2\n200,0.6\n300,0.5\n400,1\n")
    scene = tmp_path / "scene.yaml"
    scene.write_text(headline_with_bed_settings("{initial_psd: table, initial_psd_file: bed.csv}"))
    r = cli("run", scene, "--out", tmp_path / "out", "--no-plots")
    assert r.returncode == 2, r.stderr
    line = r.stderr.strip().splitlines()[-1]
    assert "units.bed.settings.initial_psd_file = 'bed.csv'" in line
    assert "bed.csv: row 4, column 2 (Q3): Q decreases from 0.6 to 0.5" in line


def test_solids_feed_and_pbm_batch_start_from_a_table():
    mp.set_table("test_q3", mp.table([100e-6, 200e-6, 400e-6, 800e-6], [0, 30, 80, 100], kind="Q", basis="volume"))
    fs = gf.load_text("""
scene: feed_table
t_end: 10 s
particles: {settings: {classes: 12, d_min: 50e-6, d_max: 1000e-6, water: false}}
units:
  feed: {type: solids_feed, settings: {psd: table, psd_table: test_q3}, params: {mdot: 2 g/s}}
  sink: {type: solids_product}
connections: [feed.out -> sink.in]
""", "feed")
    res = fs.simulate()
    edges = fs.size_edges("sink") or None
    flows = np.array([res[f"feed.mdot_{i}"][-1] for i in range(12)])
    assert flows.sum() == pytest.approx(2e-3, rel=1e-14)
    assert edges is None or len(edges) == 13
    pbm = gf.load_text("""
scene: pbm_table
t_end: 1 s
particles: {settings: {classes: 12, d_min: 50e-6, d_max: 1000e-6, water: false}}
units:
  pbm: {type: pbm_batch, settings: {initial: table, initial_psd_table: test_q3}, params: {mass0: 2 kg}}
""", "pbm")
    out = pbm.simulate()
    names = [n for n in pbm.output_names if n.startswith("pbm.")]
    assert names
    mass = [n for n in names if n.endswith(".mass")]
    if mass:
        assert out[mass[0]][0] == pytest.approx(2.0, rel=1e-12)


@pytest.fixture(scope="module")
def q3_fit():
    exps = cal.load_experiments(EXPS)
    fs = exps.flowsheet()
    stage = cal.Stage("aggregation", [cal.FreeParameter("bed.agg_ln_beta0", lower=-19.0, upper=-15.0)], [])
    fit = cal.calibrate(fs, exps.calibration, [stage],
                        options={"profile": False, "flat_scan_points": 0, "max_iterations": 20})
    return exps, fs, fit


def test_calibration_on_whole_q3_curves_recovers_the_aggregation_rate(q3_fit):
    exps, fs, fit = q3_fit
    names = [o.name for o in exps.calibration[0].observations]
    assert len(names) == 8 and all(n.startswith("bed.Q3(") for n in names)
    e = fit.estimate("bed.agg_ln_beta0")
    true = generator().TRUE_LN_BETA0
    assert fit.status == "ok"
    assert abs(e["value"] - true) <= 2.5 * e["se"], (e["value"], e["se"])
    assert abs(fs.get("bed.agg_ln_beta0") - true) > 10 * e["se"]  # the start (Table 9) was far off
    # 16 samples of noise 0.01 around the truth: chi2/dof near 1
    assert 0.3 < fit.final["chi2_reduced"] < 2.5
    print(f"bed.agg_ln_beta0: true {true}, fitted {e['value']:.4f} +- {e['se']:.4f}; "
          f"chi2/dof {fit.final['chi2_reduced']:.3f}")
