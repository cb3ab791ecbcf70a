"""Issue 10, calibration on a paper-003 scene: the two-compartment layering batch (flowsheets/two_zone_layering.yaml,
Table 7.7) calibrated against synthetic batches (flowsheets/calibration/synthetic_two_zone.yaml, written by
make_synthetic_two_zone.py) with the staged route of stages_two_zone.yaml: the truth is recovered within its standard
errors from noisy data and exactly from noise-free data, the sensitivities agree with central differences, and the
spray zone's own residence time is reported as not identifiable beside the drying zone's."""
import importlib.util
import math
import os

import numpy as np
import pytest
from conftest import ROOT

from granuflow import calibration as cal

CAL = os.path.join(ROOT, "flowsheets", "calibration")
EXPS = os.path.join(CAL, "synthetic_two_zone.yaml")
STAGES = os.path.join(CAL, "stages_two_zone.yaml")
TRUTH = {"spray.w_spray": 0.3, "drying.tau": 196.0}  # the scene's values, which generated the data


def generator():
    spec = importlib.util.spec_from_file_location("make_synthetic_two_zone",
                                                  os.path.join(CAL, "make_synthetic_two_zone.py"))
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


@pytest.fixture(scope="module")
def setup():
    exps = cal.load_experiments(EXPS)
    fs = exps.flowsheet()
    plan = cal.load_stages(STAGES, fs)
    return exps, fs, plan


@pytest.fixture(scope="module")
def staged(setup):
    exps, fs, plan = setup
    return cal.calibrate(fs, exps.calibration, plan.stages, start=plan.start, options=plan.options)


def test_fit_scene_is_the_two_zone_scene_and_the_truth_its_values(setup):
    """The calibration scene is derived from two_zone_layering.yaml (no hand copy that could drift from it)."""
    _, fs, _ = setup
    assert open(os.path.join(CAL, "two_zone_layering_fit.yaml")).read() == generator().fit_scene_text()
    for name, value in TRUTH.items():
        assert fs.get(name) == pytest.approx(value, rel=1e-12)


def test_staged_calibration_recovers_the_truth_within_its_standard_errors(setup, staged, tmp_path):
    exps, fs, plan = setup
    assert staged.status == "ok" and not staged.flagged
    assert [s["name"] for s in staged.stages] == ["growth", "broadening", "all"]
    for name, true in TRUTH.items():
        e = staged.estimate(name)
        assert abs(e["value"] - true) <= 2.5 * e["se"], (name, e["value"], e["se"])
        assert abs(plan.start[name] / true - 1) > 5 * e["rel_se"]  # the start was far outside the error bars
    # the data pin the solids reaching the particles to about 2 % and the drying-zone residence time to about 7 %
    assert staged.estimate("spray.w_spray")["rel_se"] < 0.03
    assert staged.estimate("drying.tau")["rel_se"] < 0.10
    # noise at the stated sigmas: a model that fits leaves chi2 / (n - p) near 1 (72 residuals)
    assert 0.6 < staged.final["chi2_reduced"] < 1.6
    rep = cal.report(fs, staged, exps.calibration, exps.validation, truth=TRUTH)
    assert (rep.recovery()["verdict"] == "recovered").all()
    fit = rep.fit
    # the Table 7.7 batch (validation) is predicted to within the noise: mean |rel. error| near the sigmas
    assert fit.loc[("validation", "drying.d50"), "mean_abs_rel"] < 0.02
    assert fit.loc[("validation", "drying.sigma"), "mean_abs_rel"] < 0.05
    # observables outside paper 001's groups get parity plots of their own
    written = sorted(os.path.basename(f) for f in rep.parity_plots(str(tmp_path)))
    assert written == ["parity_drying.d50.png", "parity_drying.sigma.png"]


def test_noise_free_data_give_the_truth(setup):
    """From data without noise the optimum is the truth itself: wrong sensitivities or a wrong loss would stop
    elsewhere (two calibration runs suffice for two parameters). Data and fit are integrated at rtol 1e-8: at the
    scene's 1e-6 the integration error alone moves drying.tau's optimum by about 1e-4."""
    exps, fs, plan = setup
    g = generator()
    pts = [p for p in g.points() if p["name"] in ("S75", "B5")]
    tight = {"rtol": 1e-8}
    clean = cal.synthetic_experiments(fs, pts, times=np.arange(10, 91, 10) * 60.0, observables=list(g.SIGMA),
                                      sigma=g.SIGMA, noise=False, options=tight)
    res = cal.calibrate(fs, clean.calibration, [plan.stages[-1]], start=plan.start, options={**plan.options, **tight})
    for name, true in TRUTH.items():
        assert res.estimate(name)["value"] == pytest.approx(true, rel=1e-5)
    assert res.cost < 1e-6


def test_sensitivities_agree_with_central_differences(setup):
    """Standard errors from IDAS forward sensitivities and from central differences of plain solves, at the truth:
    the same Jacobian gives the same covariance (to the truncation error of the differences)."""
    exps, fs, plan = setup
    out = {}
    for jac in ("sensitivities", "central_differences"):
        r = cal.calibrate(fs, exps.calibration, [plan.stages[-1]], start=TRUTH,
                          options={**plan.options, "jacobian": jac, "max_iterations": 1})
        out[jac] = {n: r.estimate(n)["se"] for n in TRUTH}
    for n in TRUTH:
        assert out["sensitivities"][n] == pytest.approx(out["central_differences"][n], rel=1e-2)


def fisher_rel_se(fs, exps, at, h=1e-3):
    """Relative standard errors from the Fisher information J^T J of the weighted residuals, J by central differences
    in ln p of plain predictions (cal.predict), the sigmas held at their values at ``at``: independent of the
    calibration's own Jacobian. The predictions are integrated at rtol 1e-8: a difference quotient over 2h = 2e-3
    amplifies the integration error 500-fold, and at the scene's 1e-6 that noise swamps the weak direction
    (spray.tau's relative SE came out between 1 and 3 depending on the solver's step sequence, against about 20)."""
    opts = {"rtol": 1e-8}
    sig = np.concatenate([p["sigma"] for p in cal.predict(fs, exps, at, options=opts)])

    def model(params):
        return np.concatenate([p["model"] for p in cal.predict(fs, exps, params, options=opts)]) / sig

    J = np.column_stack([(model({**at, n: at[n] * math.exp(h)}) - model({**at, n: at[n] * math.exp(-h)})) / (2 * h)
                         for n in at])
    return dict(zip(at, np.sqrt(np.diag(np.linalg.inv(J.T @ J)))))


def test_standard_errors_are_the_linearized_ones_and_spray_tau_is_not_identifiable(setup, staged):
    """At the estimates, the calibration's standard errors equal those of the Fisher information built from plain
    predictions. Adding the spray zone's own residence time: the width grows with the time between visits to the
    spray zone, and the 4 s spent in it change that by only tau_s / (tau_s + tau_d) = 2 %, so its relative standard
    error exceeds 1 (about 2000 per cent) while drying.tau's stays bounded."""
    exps, fs, plan = setup
    at = {n: staged.parameters[n] for n in TRUTH}
    rel = fisher_rel_se(fs, exps.calibration, at)
    for n in TRUTH:
        assert rel[n] == pytest.approx(staged.estimate(n)["rel_se"], rel=0.02)
    rel3 = fisher_rel_se(fs, exps.calibration, {**at, "spray.tau": 4.0})
    assert rel3["spray.tau"] > 10.0
    assert rel3["drying.tau"] < 0.1 * rel3["spray.tau"]


def test_synthetic_options_are_checked_by_name(setup):
    """Options for the synthetic runs go through the calibration's checks; a thread count there would silently
    override `workers`, so it is refused."""
    _, fs, _ = setup
    g = generator()
    pts = [p for p in g.points() if p["name"] == "S75"]
    kw = dict(times=np.array([600.0]), observables=list(g.SIGMA), sigma=g.SIGMA, noise=False)
    with pytest.raises(ValueError, match="rtoll"):
        cal.synthetic_experiments(fs, pts, options={"rtoll": 1e-8}, **kw)
    with pytest.raises(ValueError, match="workers"):
        cal.synthetic_experiments(fs, pts, options={"num_threads": 1}, **kw)
