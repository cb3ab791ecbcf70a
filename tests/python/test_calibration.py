"""Calibration against synthetic Table-1 experiments of the headline scene (issue 5, calibration).

Synthetic experiments at the 15 operating points of paper 001, Table 1 with the scene's default parameters as the
truth and noise at the Table 5 standard deviations (fixed seed); calibrate in the three stages of Fig. 10 on the 8
corners, validate on the other 7; every parameter is recovered within two standard errors or flagged as not
identifiable. The staged route is compared with fitting all six parameters at once from the same start.
"""
import os
import time

import numpy as np
import pytest
from conftest import ROOT, SCENE, assert_bad_input, cli, strict_json

import granuflow as gf
from granuflow import calibration as cal

STAGES = os.path.join(ROOT, "flowsheets", "calibration", "stages_paper001.yaml")
EXPERIMENTS = os.path.join(ROOT, "flowsheets", "calibration", "synthetic_gf25_table1.yaml")
PARAMS = ["wall.k_wall", "droplets.k_evap", "bed.X_cr", "bed.agg_ln_beta0", "spray_zone.h_pen", "bed.sel_k_break"]


@pytest.fixture(scope="module")
def fs():
    return gf.load(SCENE)


@pytest.fixture(scope="module")
def truth(fs):
    return {p: fs.get(p) for p in PARAMS}


@pytest.fixture(scope="module")
def synthetic(fs):
    # seed 2024: the same data as flowsheets/calibration/synthetic_gf25_table1.yaml (make_synthetic.py)
    return cal.synthetic_experiments(fs, cal.table1_points(), seed=2024, name="test_synthetic")


@pytest.fixture(scope="module")
def plan(fs):
    return cal.load_stages(STAGES, fs)


@pytest.fixture(scope="module")
def staged(fs, synthetic, plan):
    t0 = time.perf_counter()
    res = cal.calibrate(fs, synthetic.calibration, plan, label="staged (Fig. 10)")
    return res, time.perf_counter() - t0


def test_table1_design_has_8_corners_for_calibration_and_7_for_validation(synthetic):
    assert len(synthetic) == 15
    assert [e.name for e in synthetic.calibration] == [f"C{i}" for i in range(1, 9)]
    assert len(synthetic.validation) == 7
    e = synthetic.experiments[0]
    assert {o.name for o in e.observations} == {"gas.T", "bed.moisture", *cal.D_VALUES}
    assert e.observation("gas.T").sigma_abs == 2.0 and e.observation("bed.d95").sigma_rel == 0.11


def test_staged_calibration_recovers_the_truth_or_flags_it(fs, synthetic, truth, staged):
    res, wall = staged
    assert res.status == "ok", res.message
    assert [s["name"] for s in res.stages] == ["heat_and_mass_transfer", "size", "all"]
    assert all(s["jacobian_method"] == "sensitivities" for s in res.stages)
    final = res.final
    assert final["chi2_reduced"] == pytest.approx(1.0, abs=0.15)  # noise at the weights' sigmas
    for e in final["estimates"]:
        if e["identifiable"]:
            assert abs(e["value"] - truth[e["name"]]) <= 2 * e["se"], (e["name"], e["value"], e["se"])
        else:
            assert e["flag"], e["name"]
    # a flagged parameter was profiled, and its profile (not its linear error) says why
    for p in res.profiles:
        assert p["verdict"] in ("identifiable", "nonlinear", "unidentifiable")
        assert len(p["values"]) == len(p["delta_chi2"]) >= 2
    rep = cal.report(fs, res, synthetic.calibration, synthetic.validation, truth=truth)
    fit = rep.fit
    for group in ("size", "moisture", "T_gas_out"):
        assert fit.loc[("calibration", group), "r2"] > 0.5
        assert fit.loc[("validation", group), "r2"] > 0.5
    rec = rep.recovery()
    print("\n" + res.full_report())
    stages_wall = sum(s["wall_time_s"] for s in res.stages)
    print(f"\nstaged calibration: {stages_wall:.2f} s wall for the 3 stages "
          f"({sum(s['simulations'] for s in res.stages)} simulations, "
          f"{sum(s['sensitivity_solves'] for s in res.stages)} sensitivity solves); with the profiles of "
          f"{[p['name'] for p in res.profiles]}: {wall:.2f} s, {res.simulations} simulations, "
          f"{res.sensitivity_solves} sensitivity solves")
    print(rec.to_string())
    print(fit.to_string())
    assert set(rec["verdict"]) <= {"recovered", "flagged unidentifiable"}


def test_simultaneous_fit_reaches_the_staged_minimum(fs, synthetic, plan, staged):
    res, wall = staged
    t0 = time.perf_counter()
    sim = cal.calibrate(fs, synthetic.calibration, plan.simultaneous(), start=plan.start, options=plan.options,
                        label="simultaneous")
    wall_sim = time.perf_counter() - t0
    print(f"\nstaged: cost {res.cost:.3f}, {res.simulations} simulations ({res.sensitivity_solves} sensitivity "
          f"solves), {wall:.2f} s;  simultaneous: cost {sim.cost:.3f}, {sim.simulations} simulations "
          f"({sim.sensitivity_solves} sensitivity solves), {wall_sim:.2f} s")
    after2 = res.stages[1]
    print("stages 1+2 alone:", {e["name"]: e["value"] for e in res.stages[0]["estimates"] + after2["estimates"]})
    assert sim.cost == pytest.approx(res.cost, rel=2e-3)
    for e in sim.final["estimates"]:
        if e["identifiable"] and res.estimate(e["name"])["identifiable"]:
            assert abs(e["value"] - res.estimate(e["name"])["value"]) <= 0.5 * e["se"]


def test_sigma_on_the_data_biases_the_size_low(fs, synthetic, staged):
    """Relative sigmas applied to the noisy measurement weight the low readings more: the fitted d-values drop by
    about 2 sigma_rel^2 (about 1 %) against the model-based weights."""
    res, _ = staged
    size = cal.Stage("size", [cal.FreeParameter("bed.agg_ln_beta0", "none", -25, -10)], list(cal.D_VALUES))
    start = dict(res.parameters)
    kw = dict(start=start, options={"profile": False})
    model = cal.calibrate(fs, synthetic.calibration, [size], **kw)
    data = cal.calibrate(fs, synthetic.calibration, [size], start=start,
                         options={"profile": False, "sigma_basis": "data"})
    pm = cal.predict(fs, synthetic.calibration, model.parameters)
    pd_ = cal.predict(fs, synthetic.calibration, data.parameters)
    ratio = np.mean([np.mean(np.asarray(b["model"]) / np.asarray(a["model"])) for a, b in zip(pm, pd_)
                     if a["observable"] == "bed.d50"])
    print(f"\nln_beta0: model-sigma {model.parameters['bed.agg_ln_beta0']:.4f}, data-sigma "
          f"{data.parameters['bed.agg_ln_beta0']:.4f}; d50 ratio data/model {ratio:.4f}")
    assert ratio < 0.998
    assert data.parameters["bed.agg_ln_beta0"] < model.parameters["bed.agg_ln_beta0"]


def test_experiment_file_round_trip_and_errors(fs, synthetic, tmp_path):
    path = tmp_path / "exps.yaml"
    cal.save_experiments(synthetic, str(path), csv_dir="data")
    back = cal.load_experiments(str(path), fs)
    assert [e.name for e in back.experiments] == [e.name for e in synthetic.experiments]
    a, b = synthetic.experiments[3], back.experiments[3]
    assert b.settings["inlet.T"] == pytest.approx(a.settings["inlet.T"])
    np.testing.assert_allclose(b.observation("bed.d50").value, a.observation("bed.d50").value, rtol=1e-5)
    np.testing.assert_allclose(b.observation("gas.T").value, a.observation("gas.T").value, rtol=1e-6)
    assert b.observation("gas.T").sigma_abs == pytest.approx(2.0)
    bad = tmp_path / "bad.yaml"
    bad.write_text("scene: %s\nruns:\n  - {name: A, set: {inlet.T: 60 degC}, data: {t: [1], bed.dd50: [1]}}\n" % SCENE)
    with pytest.raises(gf.ConfigError, match="bed.dd50"):
        cal.load_experiments(str(bad))
    bad.write_text("scene: %s\nrunz: []\n" % SCENE)
    with pytest.raises(gf.ConfigError, match="unknown key 'runz'"):
        cal.load_experiments(str(bad))
    with pytest.raises(gf.ConfigError, match="max_iterations"):
        cal.calibrate(fs, synthetic.calibration[:1], cal.paper001_stages().stages[:1], options={"max_iterations": 0})
    with pytest.raises(gf.ConfigError, match="unknown"):
        cal.calibrate(fs, synthetic.calibration[:1], cal.paper001_stages().stages[:1], options={"max_iter": 3})


def test_shipped_experiment_file_and_cli(tmp_path, truth, staged):
    out = tmp_path / "cal"
    r = cli("calibrate", EXPERIMENTS, "--stages", STAGES, "--out", out, "--no-progress", timeout=300)
    assert r.returncode == 0, r.stderr
    for f in ("report.json", "report.txt", "estimates.csv", "correlation.csv", "history.csv", "fit.csv",
              "predictions.csv", "parity_size.png", "parity_moisture.png", "parity_T_gas_out.png"):
        assert (out / f).exists(), f
    import pandas as pd

    # units in the tables: each estimate's SI unit, and the unit of each RMSE
    est = pd.read_csv(out / "estimates.csv", index_col=0)
    fs = gf.load(SCENE)
    assert {n: est.loc[n, "unit"] for n in est.index} == {n: fs.spec(n)["unit"] for n in est.index}
    fit = pd.read_csv(out / "fit.csv")
    units = dict(zip(fit["output"], fit["unit"]))
    assert units["gas.T"] == "K" and units["size"] == "m" and units["bed.moisture"] == "kg/kg"
    # the shipped file holds the seed-2024 synthetic data of the `synthetic` fixture: the command line reaches the
    # truth (the scene defaults) within two standard errors or flags the parameter, as the Python route does
    rep = strict_json(out / "report.json")["result"]
    assert rep["status"] == "ok", rep.get("message")
    estimates = {e["name"]: e for e in rep["stages"][-1]["estimates"]}  # the final stage
    assert set(estimates) == set(PARAMS)
    for name, e in estimates.items():
        if e["identifiable"]:
            assert abs(e["value"] - truth[name]) <= 2 * e["se"], (name, e["value"], e["se"], truth[name])
            ref = staged[0].estimate(name)
            if ref["identifiable"]:  # same data up to the file's rounding: the same minimum
                assert abs(e["value"] - ref["value"]) <= 0.1 * e["se"], (name, e["value"], ref["value"], e["se"])
        else:
            assert e["flag"], name
    missing = "/nonexistent.yaml"
    r = cli("calibrate", EXPERIMENTS, "--stages", missing, "--out", out, timeout=60)
    assert_bad_input(r, path=missing)


def test_multi_start_runs_in_threads(fs, synthetic, plan):
    stage = [cal.Stage("hmt", plan.stages[0].free[:2], ["gas.T", "bed.moisture"])]
    starts = cal.random_starts(stage, 2, center=plan.start, spread=0.5, seed=1)
    results = cal.multi_start(fs, synthetic.calibration[:4], stage, starts, workers=2, progress=False,
                              options={"profile": False})
    assert all(isinstance(r, cal.CalibrationResult) for r in results)
    costs = [r.cost for r in results]
    assert max(costs) - min(costs) < 0.05 * min(costs) + 1.0
    assert cal.best(results).cost == min(costs)


def test_tables_are_the_csv_pandas_writes(tmp_path):
    """The report writes its tables without pandas (write_table): byte for byte what DataFrame.to_csv writes, with NaN,
    inf, booleans, tiny and huge floats, a text holding a comma and a quote, and a column some rows lack."""
    import pandas as pd

    from granuflow.calibration.report import write_table

    rows = [{"set": "calibration", "output": "gas.T", "n": 96, "r2": 0.9670788352518543, "se": float("inf"),
             "at_bound": False, "flag": "", "x": 1e-05},
            {"set": "validation", "output": "bed.d5", "n": 84, "r2": float("nan"), "se": 2.0615202699458425e-06,
             "at_bound": True, "flag": 'rse 0.388 > 0.3; "open", below', "x": 1.5e300, "only_here": -17.26327183198716}]
    write_table(str(tmp_path / "ours.csv"), ("set", "output"), rows)
    pd.DataFrame(rows).set_index(["set", "output"]).to_csv(tmp_path / "pandas.csv")
    assert (tmp_path / "ours.csv").read_text() == (tmp_path / "pandas.csv").read_text()


def test_progress_names_the_stage_and_iteration_and_changes_nothing(fs, synthetic, capsys):
    stages = cal.paper001_stages().stages[:2]
    kw = dict(options={"profile": False, "max_iterations": 3, "max_restarts": 0}, start=cal.paper001_stages().start)
    quiet = cal.calibrate(fs, synthetic.calibration[:2], stages, progress=False, **kw)
    assert capsys.readouterr().err == ""
    shown = cal.calibrate(fs, synthetic.calibration[:2], stages, progress=True, **kw)
    err = capsys.readouterr().err
    assert shown.parameters == quiet.parameters
    for s in stages:  # the bar names each stage with its iterations
        assert f"{s.name}: iteration 1, ½χ² " in err, err[-400:]


def test_an_interrupt_in_the_progress_callback_ends_the_calibration(fs, synthetic):
    # Ctrl-C arriving while the callback runs raises KeyboardInterrupt there: it must end the calibration at once
    # (not be taken for a failed evaluation) and stay a KeyboardInterrupt
    from granuflow.calibration.fit import _core_list, _options

    calls = []

    def progress(stage, iteration, cost, simulations, sensitivity_solves):
        calls.append(iteration)
        if len(calls) == 2:
            raise KeyboardInterrupt

    stages = cal.paper001_stages().stages[:1]
    with pytest.raises(KeyboardInterrupt):
        fs.calibrate_raw(_core_list(synthetic.calibration[:2]), [s.to_core() for s in stages],
                         _options({"profile": False}), cal.paper001_stages().start, progress)
    assert calls == [0, 1]  # no iteration after the interrupted one


def test_an_interrupted_multi_start_closes_its_bar(fs, synthetic, plan, monkeypatch):
    """Ctrl-C in one start ends the multi-start with KeyboardInterrupt and leaves no tqdm bar open: an open bar keeps
    its line, and tqdm draws the next bar (say, of the user's next calibration) one line further down."""
    from tqdm import tqdm

    from granuflow.calibration import fit

    stage = [cal.Stage("hmt", plan.stages[0].free[:2], ["gas.T", "bed.moisture"])]
    starts = cal.random_starts(stage, 2, center=plan.start, spread=0.5, seed=1)

    def interrupted(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(fit, "calibrate", interrupted)
    before = len(tqdm._instances)
    with pytest.raises(KeyboardInterrupt):
        cal.multi_start(fs, synthetic.calibration[:2], stage, starts, workers=2, progress=True)
    assert len(tqdm._instances) == before
