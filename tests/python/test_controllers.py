"""The PI controller unit (docs/controllers.md): it holds the outlet gas temperature of the headline plant through a
set-point step and a spray disturbance, its limits hold and unwind, its gains have exact sensitivities, a contour map
runs over them, and a steady state says when it misses its set point."""
import csv
import os
import subprocess
import sys

import numpy as np
import pytest

import granuflow as gf
from granuflow.steady import steady_report

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
HEADLINE_PI = os.path.join(ROOT, "flowsheets", "stoeckl_gf25_batch_controlled.yaml")
LOOP_PI = os.path.join(ROOT, "flowsheets", "continuous_layering_sieve_mill_pi.yaml")
C = 273.15


def at(res, name, t):
    return float(np.interp(t, res.t, res[name]))


def test_the_outlet_gas_temperature_follows_its_set_point_and_rejects_the_spray_step():
    res = gf.load(HEADLINE_PI).simulate(warn=False)
    # before each change the gas is at the set point of the moment (the integral removes the offset)
    assert abs(at(res, "gas.T", 19.9 * 60) - (40 + C)) < 0.05
    assert abs(at(res, "gas.T", 39.9 * 60) - (42 + C)) < 0.05
    # more water to evaporate from 40 min: the controller heats the inlet air more and brings the gas back
    assert at(res, "tic.u", 59.9 * 60) > at(res, "tic.u", 39.9 * 60) + 1.0
    assert abs(at(res, "gas.T", 59.9 * 60) - (42 + C)) < 0.1
    assert min(res["gas.T"][res.t > 2400]) < 42 + C - 0.1  # the disturbance was felt
    u = res["tic.u"]
    assert u.min() > 30 + C and u.max() < 90 + C


def test_a_limited_output_stays_within_its_limits_and_does_not_wind_up():
    fs = gf.load(HEADLINE_PI)
    fs.set("tic.u_max", 65 + C)  # too little heat for 42 degC once the spray steps up
    res = fs.simulate(warn=False)
    u = res["tic.u"]
    assert u.max() <= 65 + C + 1e-3  # the clamp, to the solver's tolerance
    assert at(res, "tic.u", 59.9 * 60) > 65 + C - 0.05  # at its limit
    assert at(res, "gas.T", 59.9 * 60) < 42 + C - 0.3  # the set point is out of reach
    # back-calculation: the integral tracks the limit instead of growing with the error
    integral = res["tic.integral"][res.t > 45 * 60]
    assert np.ptp(integral) < 0.05


def test_sensitivities_to_the_gain_and_integral_time_match_finite_differences():
    fs = gf.load(HEADLINE_PI)
    t = [0.0, 25 * 60.0]
    tol = {"rtol": 1e-9, "atol": 1e-9}
    res = fs.simulate(t_out=t, sensitivities=["tic.Kp", "tic.Ti"], warn=False, **tol)
    for p, h in (("tic.Kp", 0.02), ("tic.Ti", 0.5)):
        vals = [gf.load(HEADLINE_PI).set(p, fs.get(p) + d).simulate(t_out=t, warn=False, **tol)["gas.T"][-1]
                for d in (-h, h)]
        fd = (vals[1] - vals[0]) / (2 * h)
        sens = res.sensitivity("gas.T", p)[-1]
        assert sens == pytest.approx(fd, rel=2e-3, abs=1e-7), (p, sens, fd)


def test_a_driven_parameter_cannot_be_set_and_names_its_controller():
    fs = gf.load(HEADLINE_PI)
    with pytest.raises(ValueError, match=r"inlet.T .*driven by tic.u \(setting tic.drive\)"):
        fs.set("inlet.T", 70 + C)


def test_a_contour_map_runs_over_the_controller_gain_and_set_point(tmp_path):
    out = tmp_path / "c"
    r = subprocess.run([sys.executable, "-m", "granuflow", "contour", HEADLINE_PI, "--x", "tic.Kp:-:1:4:2",
                        "--y", "tic.Ti:s:60:240:2", "--output", "T_gas_out_K", "--out", str(out), "--workers", "1"],
                       capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    rows = list(csv.reader((out / "contour.csv").read_text().splitlines()))[1:]
    assert len(rows) == 4 and all(r[3] == "ok" for r in rows), rows
    t_gas = {(float(r[0]), float(r[1])): float(r[2]) for r in rows}
    # with the slow integral, the higher gain ends nearer the set point (42 degC)
    assert abs(t_gas[4.0, 240.0] - (42 + C)) < abs(t_gas[1.0, 240.0] - (42 + C))


def test_a_pi_controller_at_its_limit_misses_its_set_point_at_the_steady_state():
    fs = gf.load(LOOP_PI)
    rep = steady_report(fs, stability=False)
    assert not any("set point" in w for w in rep["warnings"]), rep["warnings"]
    assert rep["bed_mass_kg"] == pytest.approx(100.0, rel=1e-4)
    # the discharge cannot close below twice what the set point needs: the bed runs low
    fs.update({"lic.u0": 2e-3, "lic.u_min": 2e-3})
    rep = steady_report(fs, stability=False)
    missed = [w for w in rep["warnings"] if "misses its set point" in w]
    assert len(missed) == 1 and "unit lic (pi_controller)" in missed[0], rep["warnings"]
    assert "lic.set_point = 100 kg" in missed[0] and "lic.measured = " in missed[0], missed[0]
    assert rep["bed_mass_kg"] < 95.0
    assert rep["k_discharge_1_s"] == pytest.approx(2e-3, rel=1e-2)


def test_sensitivities_through_a_measured_output_match_finite_differences():
    # the loop's controller measures an output (the bed mass, a sum over classes): the Jacobian and the sensitivities
    # carry the granulator's columns into the controller's equations
    text = open(LOOP_PI).read().replace("classes: 100,", "classes: 20,")
    fs = gf.load_text(text, "loop20")
    t, tol = [0.0, 1800.0], {"rtol": 1e-9, "atol": 1e-10}
    res = fs.simulate(t_out=t, sensitivities=["lic.Kp", "lic.Ti"], warn=False, **tol)
    for p, h in (("lic.Kp", 0.02), ("lic.Ti", 2.0)):
        vals = [gf.load_text(text, "loop20").set(p, fs.get(p) + d).simulate(t_out=t, warn=False, **tol)["gran.M_10"][-1]
                for d in (-h, h)]
        fd = (vals[1] - vals[0]) / (2 * h)
        assert res.sensitivity("gran.M_10", p)[-1] == pytest.approx(fd, rel=1e-4), p
