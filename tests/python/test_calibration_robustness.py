"""Calibration that says when it cannot be trusted (issue 12): a start in a flat region of the loss is found and
left (the penetration depth below about 130 um, where d50 does not respond), starts that end above the best are
named, data that no stage uses is reported, and every warning reaches report.json, report.txt and stderr."""
import json
import os
import subprocess
import sys

import numpy as np
import pytest

from conftest import SCENE, cli, package_env, sha256

import granuflow as gf
from granuflow import calibration as cal

D = ["bed.d10", "bed.d50", "bed.d90"]


@pytest.fixture(scope="module")
def fs():
    return gf.load(SCENE)


@pytest.fixture(scope="module")
def corners(fs):
    """Four Table-1 corners of synthetic data (the scene's defaults as the truth, h_pen = 168 um), 30 min."""
    fs = fs.clone()
    fs.set_t_end(1800.0)
    return cal.synthetic_experiments(fs, cal.table1_points()[:4], seed=7, name="corners").experiments


def h_pen_stage():
    return cal.Stage("size", [cal.FreeParameter("spray_zone.h_pen", "log", 10e-6, 5e-3)], D)


def test_a_start_in_the_flat_region_is_left_for_the_optimum(fs, corners):
    truth = fs.get("spray_zone.h_pen")
    start = {"spray_zone.h_pen": 100e-6}  # d50 does not respond to it below about 130 um
    stuck = cal.calibrate(fs, corners, [h_pen_stage()], start=start,
                          options={"flat_scan_points": 0, "profile": False})
    assert stuck.parameters["spray_zone.h_pen"] == pytest.approx(100e-6, rel=1e-6)
    assert stuck.final["flat"] == ["spray_zone.h_pen"] and not stuck.final["moved"]
    assert any("the start lies in a flat region of the loss" in w for w in stuck.warnings)
    r = cal.calibrate(fs, corners, [h_pen_stage()], start=start, options={"profile": False})
    assert r.final["restarts"] >= 1 and r.final["flat"] == []
    assert r.parameters["spray_zone.h_pen"] == pytest.approx(truth, rel=0.05)
    delta_chi2 = 2 * (stuck.cost - r.cost)
    assert delta_chi2 > 4  # what the stuck start reported as success was far from the optimum
    assert any("restarted from there" in w and "spray_zone.h_pen" in w for w in r.warnings)
    # the gradient and curvature at the end say it: zero response at the stuck start, a sharp minimum after
    assert stuck.final["curvature"][0] < 1e-3 < r.final["curvature"][0]


def test_starts_that_end_above_the_best_are_named():
    def result(cost, label):
        raw = {"stages": [{"cost": cost}], "parameters": {}, "simulations": 1, "sensitivity_solves": 0,
               "wall_time_s": 0.0, "status": "ok", "message": "", "brief": "", "full_report": "", "warnings": []}
        return cal.CalibrationResult(raw, label=label)

    results = [result(100.0, "start 0"), result(124.0, "start 1"), result(101.0, "start 2"),
               gf.CalibrationError("stage 'size' failed: simulation failed")]
    notes = cal.compare_starts(results)
    assert notes[0].startswith("1 of 4 starts failed (start 3); first: stage 'size' failed")
    assert notes[1].startswith("1 of 3 starts ended more than Δχ² = 3.84 above the best: start 1 (Δχ² = 48)")
    best = cal.best(results)
    assert best.label == "start 0" and notes[1] in best.warnings
    assert cal.compare_starts([result(1.0, "a"), result(1.5, "b")]) == []  # within Δχ² = 1: no warning


EXPERIMENTS = f"""scene: {SCENE}
sigma: {{gas.T: {{abs: 2 K}}, bed.moisture_wet: {{abs: 0.01}}}}
runs:
  - name: A
    set: {{inlet.T: 60 degC}}
    t_end: 20 min
    data: {{units: {{t: min, gas.T: degC, bed.moisture_wet: kg/kg}}, t: [5, 10, 20], gas.T: [42.1, 38.9, 36.5],
            bed.moisture_wet: [0.04, 0.045, 0.05]}}
"""

STAGES = """name: wall
start: {wall.k_wall: 20}
options: {profile: false}
stages:
  - name: wall
    free: {wall.k_wall: {transform: log, lower: 1, upper: 200}}
    observables: [gas.T, bed.moisture]
"""


def test_data_no_stage_uses_is_reported_everywhere(tmp_path):
    exp, st = tmp_path / "exps.yaml", tmp_path / "stages.yaml"
    exp.write_text(EXPERIMENTS)
    st.write_text(STAGES)
    before = [sha256(exp), sha256(st), sha256(SCENE)]
    p = cli("calibrate", exp, "--stages", st, "--out", tmp_path / "out", "--no-progress", "--no-plots")
    assert p.returncode == 0, p.stderr
    # --no-plots: every table and the report, no parity PNG
    written = sorted(os.listdir(tmp_path / "out"))
    assert written == ["correlation.csv", "estimates.csv", "fit.csv", "history.csv", "predictions.csv",
                       "provenance.json", "report.json", "report.txt"], written
    warned = [line for line in p.stderr.splitlines() if line.startswith("granuflow: warning: ")]
    assert len(warned) == 1, p.stderr
    # the stage watches the dry basis, the experiment measured the wet basis
    assert "data that no stage uses: bed.moisture_wet (experiment A; 3 samples)" in warned[0]
    rep = json.loads((tmp_path / "out" / "report.json").read_text())
    assert rep["warnings"] == [warned[0][len("granuflow: warning: "):]]
    assert "warning: data that no stage uses" in (tmp_path / "out" / "report.txt").read_text()
    assert [sha256(exp), sha256(st), sha256(SCENE)] == before


def test_the_command_prints_its_fit_table_without_pandas(tmp_path):
    """`granuflow calibrate` prints the report and the fit table; importing pandas for that took 0.3-0.45 s, a fifth
    of the shipped calibration's wall time, so the command (with --no-plots) must not import it."""
    exp, st = tmp_path / "exps.yaml", tmp_path / "stages.yaml"
    exp.write_text(EXPERIMENTS)
    st.write_text(STAGES)
    code = ("import sys; from granuflow.cli import main\n"
            f"sys.argv = ['granuflow', 'calibrate', {str(exp)!r}, '--stages', {str(st)!r}, '--out', "
            f"{str(tmp_path / 'out')!r}, '--no-plots', '--no-progress']\n"
            "try:\n    main()\nexcept SystemExit as e:\n    assert not e.code, e.code\n"
            "print('pandas imported:', 'pandas' in sys.modules)")
    p = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120, env=package_env())
    assert p.returncode == 0, p.stderr
    assert p.stdout.rstrip().endswith("pandas imported: False"), p.stdout[-500:]
    # the printed table holds the rows of fit.csv: set (on its first row), output, n, r2, rmse, mean_abs_rel, unit
    lines = p.stdout.splitlines()
    head = next(i for i, line in enumerate(lines) if line.split()[:2] == ["set", "output"])
    assert lines[head].split() == ["set", "output", "n", "r2", "rmse", "mean_abs_rel", "unit"]
    import csv
    with open(tmp_path / "out" / "fit.csv") as f:
        rows = list(csv.DictReader(f))
    printed = [line.split() for line in lines[head + 1:head + 1 + len(rows)]]
    for k, (row, cells) in enumerate(zip(rows, printed)):
        expect = ([row["set"]] if k == 0 or rows[k - 1]["set"] != row["set"] else []) + [row["output"], row["n"]]
        expect += [f"{float(row[c]):.4g}" if row[c] else "NaN" for c in ("r2", "rmse", "mean_abs_rel")] + [row["unit"]]
        assert cells == expect, (cells, expect)


def test_fit_table_text_aligns_groups_numbers_and_missing_values():
    from granuflow.calibration.report import fit_table_text

    rows = [{"set": "calibration", "output": "gas.T", "n": 96, "r2": 0.967123, "rmse": 2.17812, "unit": "K"},
            {"set": "calibration", "output": "size", "n": 864, "r2": float("nan"), "rmse": 5.5661e-05, "unit": "m",
             "max_model_error_over_sigma": 0.0123},
            {"set": "validation", "output": "gas.T", "n": 84, "r2": 0.91591, "rmse": None, "unit": "K"}]
    lines = fit_table_text(rows).splitlines()
    assert lines[0].split() == ["set", "output", "n", "r2", "rmse", "unit", "max_model_error_over_sigma"]
    assert lines[1].split() == ["calibration", "gas.T", "96", "0.9671", "2.178", "K", "NaN"]
    assert lines[2].split() == ["size", "864", "NaN", "5.566e-05", "m", "0.0123"]  # the set named once
    assert lines[3].split() == ["validation", "gas.T", "84", "0.9159", "NaN", "K", "NaN"]
    assert len({len(line) for line in lines}) == 1  # numbers right-aligned to one column edge
    assert lines[2].index("size") == lines[1].index("gas.T")


def test_unused_observations_from_python(fs):
    e = cal.Experiment("A", {}, [cal.Observation("gas.T", np.array([60.0]), np.array([330.0]), sigma_abs=2.0),
                                 cal.Observation("bed.d50", np.array([60.0]), np.array([2e-4]), sigma_rel=0.07)])
    r = cal.calibrate(fs, [e], [cal.Stage("wall", [cal.FreeParameter("wall.k_wall", "log", 1, 200)], ["gas.T"])],
                      options={"profile": False})
    assert any(w.startswith("data that no stage uses: bed.d50 (experiment A; 1 samples)") for w in r.warnings)
