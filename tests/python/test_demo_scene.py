"""The Python API and the command line on the demo flowsheet, which has an exact answer."""
import math

import numpy as np
import pytest
from conftest import DEMO, assert_bad_input, cli, sha256, strict_json
from scipy.linalg import expm

import granuflow as gf


def exact_tank_temperatures(t, F=0.5, split=0.6, M1=100.0, M2=200.0, Q1=2e4, cp=4180.0, Ta=300.0, Tb=350.0, ts=100.0):
    r = 1 - split
    m = F / split
    A = np.array([[-m / M1, m * r / M1], [m / M2, -m / M2]])

    def advance(x, dt, tf):
        b = np.array([m * (1 - r) * tf / M1 + Q1 / (M1 * cp), 0.0])
        xs = -np.linalg.solve(A, b)
        return expm(A * dt) @ (x - xs) + xs

    x0 = np.array([Ta, Ta])
    return advance(x0, t, Ta) if t <= ts else advance(advance(x0, ts, Ta), t - ts, Tb)


def test_python_simulation_matches_analytic_solution():
    fs = gf.load(DEMO)
    res = fs.simulate(rtol=1e-10, atol=1e-12)
    for k in range(0, len(res.t), 20):
        T1, T2 = exact_tank_temperatures(res.t[k])
        assert res["tank1.T"][k] == pytest.approx(T1, rel=1e-6)
        assert res["tank2.T"][k] == pytest.approx(T2, rel=1e-6)
    df = res.timeseries
    assert df.shape == (len(res.t), len(res.state_names) + len(res.output_names))
    assert res.summary["balance"]["energy_rel"] < 1e-9


def test_parameter_change_without_reload_and_units_at_the_edge():
    fs = gf.load(DEMO)
    fs.set("tank1.Q", "30 kW")
    assert fs.get("tank1.Q") == 30000.0
    hot = fs.simulate()["tank2.T"][-1]
    fs.set("tank1.Q", 0.0)
    cold = fs.simulate()["tank2.T"][-1]
    t_end = fs.t_end
    assert hot == pytest.approx(exact_tank_temperatures(t_end, Q1=3e4)[1], rel=1e-6)
    assert cold == pytest.approx(exact_tank_temperatures(t_end, Q1=0.0)[1], rel=1e-6)


def test_later_runs_share_the_names_and_own_their_arrays():
    # The second run of a flowsheet takes its names, roles and units from the first (the core sends them once) and
    # its arrays from the core's buffers without a copy: each result must still be complete and independent.
    fs = gf.load(DEMO)
    first = fs.simulate(t_end=500.0)
    fs.set("tank1.Q", "30 kW")
    second = fs.simulate(t_end=500.0)
    assert second.state_names == first.state_names and second.output_names == first.output_names
    assert second.output_roles == first.output_roles and second.units == first.units
    assert second["tank2.T"][-1] > first["tank2.T"][-1] + 1.0  # more heat: its own values, not the first run's
    second.state_names.append("not a state")
    assert "not a state" not in first.state_names and "not a state" not in fs.simulate(t_end=500.0).state_names
    assert first.summary["balance"]["energy_rel"] < 1e-6
    y = first.y.copy()
    del second
    assert np.array_equal(first.y, y) and first.y.flags.writeable  # a buffer of its own, alive as long as it is
    first.y[0, 0] += 1.0
    assert first.y[0, 0] == y[0, 0] + 1.0


def test_sensitivity_from_python_equals_finite_difference():
    fs = gf.load(DEMO)
    res = fs.simulate(t_end=500, sensitivities=["tank1.Q"], rtol=1e-10, atol=1e-12)
    s = res.sensitivity("tank2.T", "tank1.Q")[-1]
    h = 50.0
    up = fs.clone().set("tank1.Q", 2e4 + h).simulate(t_end=500, rtol=1e-10, atol=1e-12)["tank2.T"][-1]
    dn = fs.clone().set("tank1.Q", 2e4 - h).simulate(t_end=500, rtol=1e-10, atol=1e-12)["tank2.T"][-1]
    assert s == pytest.approx((up - dn) / (2 * h), rel=1e-5)


def test_errors_are_typed_and_name_the_thing():
    fs = gf.load(DEMO)
    with pytest.raises(gf.ConfigError, match=r"tank1\.mass = -3 kg: violates"):
        fs.set("tank1.mass", -3)
    with pytest.raises(ValueError, match="parameters of tank1"):
        fs.set("tank1.volume", 1.0)
    with pytest.raises(gf.ConfigError, match="unit 'furlong' is m, but the value must be in kg"):
        fs.set("tank1.mass", "3 furlong")
    fs._scene  # noqa: B018 - the flowsheet stays usable after errors
    assert fs.simulate(t_end=10).t[-1] == 10


def _scene_with(tmp_path, old, new, name="bad.yaml"):
    text = open(DEMO).read()
    assert old in text
    p = tmp_path / name
    p.write_text(text.replace(old, new))
    return str(p)


@pytest.mark.parametrize("old,new,needle", [
    ("t_end: 2000 s\n", "", "t_end: missing required key"),                       # missing
    ("    params: {split: 0.6}", "    params: {splitt: 0.6}", "splitter.params.splitt"),  # misspelt
    ("    params: {split: 0.6}", "    params: {split: [0.6]}", "expected a single value"),  # mistyped
    ("    params: {split: 0.6}", "    params: {split: 1.6}", "split = 1.6: violates 0 <= split <= 1"),  # range
    ("scene: demo_tanks", "scene: demo_tanks\nspeed: 3", "speed: unknown key"),   # unknown key
    ("type: liquid_splitter", "type: liquid_spliter", "unknown unit type 'liquid_spliter'"),
    ("  - splitter.out2 -> mixer.in2\n", "", "mixer.in2 (liquid, in) is not connected"),
    ("mass: 100 kg", "mass: 100 degC", "unit 'degC' is K, but the value must be in kg"),
])
def test_cli_bad_input_exits_2_with_one_line(tmp_path, old, new, needle):
    path = _scene_with(tmp_path, old, new)
    before = sha256(path)
    p = cli("run", path, "--out", tmp_path / "out", timeout=60)
    assert_bad_input(p, needle, path=path)
    assert sha256(path) == before  # the input is never modified
    assert not (tmp_path / "out" / "summary.json").exists()


def test_cli_solver_failure_exits_3_naming_time_and_unit(tmp_path):
    path = _scene_with(tmp_path, "solver: {rtol: 1e-8, atol: 1e-10}", "solver: {rtol: 1e-8, atol: 1e-10, max_steps: 5}")
    p = cli("run", path, "--out", tmp_path / "out", timeout=60)
    assert p.returncode == 3, p.stderr
    assert len(p.stderr.strip().splitlines()) == 1 and "Traceback" not in p.stderr, p.stderr
    assert "failed at t = " in p.stderr and "unit '" in p.stderr
    assert not (tmp_path / "out" / "summary.json").exists()
    with pytest.raises(gf.SolverError) as e:
        gf.load(path).simulate()
    assert e.value.t > 0 and e.value.unit
    # the exit message names the same time and unit as the exception
    assert f"unit '{e.value.unit}'" in p.stderr


def test_cli_run_writes_summary_csv_and_plots(tmp_path):
    out = tmp_path / "out"
    p = cli("run", DEMO, "--out", out, "--set", "tank1.Q=25 kW", "--t-end", "10 min")
    assert p.returncode == 0, p.stderr
    s = strict_json(out / "summary.json")
    for key in ("scene", "t_end_s", "d10_um", "d50_um", "d90_um", "bed_moisture", "T_gas_out_K", "balance",
                "wall_time_s", "solver"):
        assert key in s
    assert s["scene"] == "demo_tanks" and s["t_end_s"] == 600.0
    # quantities the demo scene does not have are null, not made up
    for key in ("d10_um", "d50_um", "d90_um", "bed_moisture", "T_gas_out_K"):
        assert s[key] is None, key
    assert set(s["balance"]) == {"water_rel", "solids_rel", "energy_rel"}
    assert all(v is not None and v < 1e-9 for v in s["balance"].values())
    assert set(s["solver"]) >= {"states", "steps", "residuals", "jacobians"}
    # the override and the end time reached the solver: T_out = tank 2 at 600 s with Q1 = 25 kW, exactly
    # (scene tolerances rtol 1e-8)
    assert math.isfinite(s["T_out_K"])
    assert s["T_out_K"] == pytest.approx(exact_tank_temperatures(600.0, Q1=2.5e4)[1], rel=1e-6)
    assert (out / "timeseries.csv").stat().st_size > 1000
    import pandas as pd

    ts = pd.read_csv(out / "timeseries.csv", index_col=0)
    assert ts.index.name == "t [s]" and ts.index[0] == 0.0 and ts.index[-1] == 600.0
    assert ts["t [min]"].iloc[-1] == pytest.approx(10.0)
    # every column carries its unit in the header
    assert all(c.endswith("]") for c in ts.columns), [c for c in ts.columns if not c.endswith("]")]
    assert ts["tank2.T [K]"].iloc[-1] == pytest.approx(s["T_out_K"], rel=1e-9)
    assert s["units"]["T_out_K"] == "K"
    for t in (50.0, 150.0, 400.0):
        k = int(np.argmin(np.abs(ts.index.to_numpy() - t)))
        T1, T2 = exact_tank_temperatures(ts.index[k], Q1=2.5e4)
        assert ts["tank1.T [K]"].iloc[k] == pytest.approx(T1, rel=1e-6)
        assert ts["tank2.T [K]"].iloc[k] == pytest.approx(T2, rel=1e-6)
    assert (out / "plot_0.png").read_bytes()[:4] == b"\x89PNG"


def test_steady_state_of_the_recycle_loop_from_python():
    fs = gf.load(DEMO)
    s = fs.steady_state(t=200.0)  # after the feed-temperature step: T_feed = 350 K
    # both tanks at T_feed + Q1 / (cp F): the recycle does not change the steady outlet temperature
    assert s["y"]["tank1.T"] == pytest.approx(350.0 + 2e4 / (4180.0 * 0.5), rel=1e-10)
    assert s["y"]["tank2.T"] == pytest.approx(s["y"]["tank1.T"], rel=1e-12)
    assert s["y"]["mixer.mdot"] == pytest.approx(0.5 / 0.6, rel=1e-12)


def test_unit_settings_report_the_values_in_use():
    text = open(DEMO).read().replace("settings: {inlets: 2}", "settings: {inlets: 3}")
    text = text.replace("  - splitter.out2 -> mixer.in2\n",
                        "  - splitter.out2 -> mixer.in2\n  - feed2.out -> mixer.in3\n")
    text = text.replace("  product:\n", "  feed2:\n    type: liquid_feed\n    params: {mdot: 0.1 kg/s}\n  product:\n")
    fs = gf.load_text(text, "three_inlets")
    assert fs.unit_settings()["mixer"] == ("liquid_mixer", {"inlets": "3"})
