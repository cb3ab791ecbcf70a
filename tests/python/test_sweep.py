"""granuflow.sweep: the sweep-file loader, the generic runner and its executors, main effects."""
import importlib.util
import math
import os
import threading

import numpy as np
import pandas as pd
import pytest

from conftest import DEMO, ROOT, SCENE

import granuflow as gf
from granuflow import sweep

TABLE1 = os.path.join(ROOT, "flowsheets", "stoeckl_gf25_table1.yaml")


def test_run_sweep_generic_points_in_order_with_si_columns():
    fs = gf.load(SCENE)
    points = [{"nozzle.mdot": "120 g/min"}, {"nozzle.mdot": 0.001, "inlet.T": "80 degC"}, {}]
    df = sweep.run_sweep(fs, points, ["d50_um", "bed.T"], names=["a", "b", "c"], workers=2, progress=False,
                         t_end=600.0)
    assert list(df.columns) == ["point", "nozzle.mdot", "inlet.T", "d50_um", "bed.T", "wall_time_s",
                                "solve_time_s", "status", "message"]
    assert list(df["point"]) == ["a", "b", "c"]
    assert df["nozzle.mdot"].tolist() == pytest.approx([0.002, 0.001, 0.0015])
    # parameters a point does not name keep the flowsheet's value, also on a worker that ran another point
    assert df["inlet.T"].tolist() == pytest.approx([333.15, 353.15, 333.15])
    assert (df["status"] == "ok").all() and (df["message"] == "").all()
    ref = gf.load(SCENE).set("inlet.T", "80 degC").set("nozzle.mdot", 0.001).simulate(t_end=600.0)
    assert df["d50_um"][1] == pytest.approx(ref.summary["d50_um"], rel=1e-12)
    assert df["bed.T"][1] == pytest.approx(ref["bed.T"][-1], rel=1e-12)
    assert fs.get("nozzle.mdot") == 0.0015  # the template flowsheet is untouched


def test_final_values_are_the_summary_numbers_nulls_included():
    # the sweep reads the summary's numbers without building the whole summary; a d90 in the top size class of the
    # headline scene after 60 min is null there (NaN in a sweep), not the grid's end
    res = gf.load(SCENE).simulate(warn=False)
    keys = gf.load(SCENE).summary_keys()
    s, v = res.summary, sweep.final_values(res, keys + ["bed.T"])
    assert any(s[k] is None for k in keys) and any(s[k] is not None for k in keys)
    for k in keys:
        assert (math.isnan(v[k]) if s[k] is None else v[k] == s[k]), k
    assert v["bed.T"] == res["bed.T"][-1]


def test_threads_and_serial_give_identical_results():
    sw = sweep.load_sweep(TABLE1)
    a = sw.run(workers=2, progress=False, executor="threads")
    b = sw.run(progress=False, executor="serial")
    cols = list(sweep.DEFAULT_OUTPUTS)
    np.testing.assert_array_equal(a[cols].to_numpy(), b[cols].to_numpy())


def test_a_custom_executor_plugs_in():
    calls = []

    class Recording:
        def map_unordered(self, evaluate, flowsheet, items):
            for item in reversed(list(items)):  # any order: the runner sorts the rows back
                calls.append(threading.current_thread().name)
                yield evaluate(flowsheet.clone(), item)

    df = sweep.run_sweep(gf.load(DEMO), [{"tank1.Q": "10 kW"}, {"tank1.Q": "30 kW"}], ["T_out_K"],
                         executor=Recording(), progress=False)
    assert len(calls) == 2 and df["tank1.Q"].tolist() == [1e4, 3e4]
    assert df["T_out_K"][1] > df["T_out_K"][0]
    with pytest.raises(gf.ConfigError, match="executor = 'dask': unknown"):
        sweep.run_sweep(gf.load(DEMO), [{}], ["T_out_K"], executor="dask")


def test_failed_points_are_rows_unless_asked_to_raise(tmp_path):
    fs = gf.load(SCENE)
    df = sweep.run_sweep(fs, [{"inlet.T": "900 degC"}, {"inlet.T": "70 degC"}], ["d50_um"], progress=False)
    assert df["status"].tolist() == ["failed", "ok"]
    assert "250 <= T <= 500 (bed.T0 in [250, 500] follows it by a link)" in df["message"][0]
    assert math.isnan(df["d50_um"][0])
    assert df["inlet.T"][0] == pytest.approx(1173.15)
    text = open(SCENE).read().replace("\nsolver: {", "\nsolver: {max_steps: 5, ")
    few = gf.load_text(text, "few_steps")
    df = sweep.run_sweep(few, [{}, {"nozzle.mdot": "60 g/min"}], ["d50_um"], workers=2, progress=False)
    assert (df["status"] == "failed").all() and df["message"].str.contains("failed at t = ").all()
    with pytest.raises(gf.SolverError):
        sweep.run_sweep(few, [{}], ["d50_um"], progress=False, raise_errors=True)


def test_progress_bar_is_optional(capsys):
    capsys.readouterr()
    df = sweep.run_sweep(gf.load(DEMO), [{}, {}], ["T_out_K"], progress=True, workers=1)
    assert (df["status"] == "ok").all()
    err = capsys.readouterr().err
    if importlib.util.find_spec("tqdm"):  # optional: Debian python3-tqdm
        assert "/2 [" in err, err  # a bar over the 2 runs, on stderr (tqdm may not redraw fast runs: 0/2 is fine)
    else:
        assert err == ""
    quiet = sweep.run_sweep(gf.load(DEMO), [{}], ["T_out_K"], progress=False)
    assert (quiet["status"] == "ok").all()
    assert capsys.readouterr().err == ""  # no bar, nothing on stderr
    # the bar does not change the result: both equal a direct run of the scene
    direct = gf.load(DEMO).simulate().summary["T_out_K"]
    assert df["T_out_K"].tolist() == pytest.approx([direct, direct], rel=1e-12)
    assert quiet["T_out_K"][0] == pytest.approx(direct, rel=1e-12)


def test_unknown_parameter_or_output_is_a_config_error():
    fs = gf.load(SCENE)
    with pytest.raises(gf.ConfigError, match="unknown parameter 'inlet.Tx'"):
        sweep.run_sweep(fs, [{"inlet.Tx": 1.0}], ["d50_um"])
    with pytest.raises(gf.ConfigError, match="'d55_um' is neither a summary key.*allowed: d10_um, d50_um"):
        sweep.run_sweep(fs, [{}], ["d55_um"])


def test_sweep_file_values_with_units_are_shown_in_the_variable_unit(tmp_path):
    p = tmp_path / "s.yaml"
    p.write_text(f"""
scene: {SCENE}
variables:
  T: {{param: inlet.T, unit: degC}}
  V: {{param: inlet.V_dot, unit: m3/h}}
points:
  - {{name: a, T: "313.15 K", V: "0.2 m3/s"}}
  - {{name: b, T: 50, V: 600}}
outputs: [d50_um]
set: {{bed.bed_mass: 12 kg}}
t_end: 5 min
""")
    sw = sweep.load_sweep(p)
    assert sw.name == "s" and sw.t_end == 300.0 and sw.set == {"bed.bed_mass": "12 kg"}
    assert sw.points[0]["T"] == pytest.approx(40.0) and sw.points[0]["V"] == pytest.approx(720.0)
    assert sw.param_points()[1] == {"inlet.T": "50.0 degC", "inlet.V_dot": "600.0 m3/h"}
    df = sw.run(progress=False)
    assert df["T"].tolist() == pytest.approx([40.0, 50.0]) and (df["status"] == "ok").all()
    assert df.attrs["variables"]["T"] == {"param": "inlet.T", "unit": "degC", "levels": []}
    fs = sw.flowsheet()
    assert fs.get("bed.bed_mass") == 12.0 and fs.t_end == 300.0
    with pytest.raises(gf.ConfigError, match="inlet.T is a variable of sweep"):
        sw.flowsheet({"inlet.T": "50 degC"})


@pytest.mark.parametrize("body,needle", [
    ("variables: {T: {param: inlet.T, unit: degC}}\npoints: [{T: 40}]\nspeed: 3",
     "speed: unknown key (allowed: sweep,"),
    ("points: [{T: 40}]", "variables: missing required key"),
    ("variables: {T: {param: inlet.T, unit: degC, step: 5}}\npoints: [{T: 40}]", "variables.T.step: unknown key"),
    ("variables: {T: {param: inlet.T, unit: kg}}\npoints: [{T: 40}]", "variables.T.unit: 'kg' does not fit inlet.T"),
    ("variables: {T: {param: inlet.T, unit: degC}}\npoints: [{T: 40, X: 1}]",
     "points[0] (P1).X: unknown key (allowed: name, kind, T)"),
    ("variables: {T: {param: inlet.T, unit: degC}}\npoints: [{T: 400}]",
     "points[0] (P1).T = 400: inlet.T = 673.15 K: violates"),
    ("variables: {T: {param: inlet.T, unit: degC}}\npoints: [{T: 40}]\nset: {inlet.T: 50}",
     "set.inlet.T: is also a sweep variable"),
    ("variables: {T: {param: inlet.T, unit: degC}}\npoints: [{T: 40}]\nt_end: soon", "t_end = 'soon'"),
    ("variables: {T: {param: inlet.T, unit: degC}}\npoints: []", "points: expected a non-empty list"),
    ("variables: {T: {param: inlet.T, unit: degC, levels: [a, b]}}\npoints: [{T: 40}]",
     "variables.T.levels: expected a list of numbers"),
])
def test_sweep_file_errors_name_file_key_value_and_allowed(tmp_path, body, needle):
    p = tmp_path / "bad.yaml"
    p.write_text(f"scene: {os.path.relpath(SCENE, tmp_path)}\n{body}\n")
    with pytest.raises(gf.ConfigError) as e:
        sweep.load_sweep(p)
    assert str(p) in str(e.value) and needle in str(e.value), str(e.value)


def test_main_effects_of_a_known_linear_response():
    rows = []
    for a in (0.0, 1.0, 2.0):
        for b in (10.0, 20.0, 30.0):
            rows.append({"a": a, "b": b, "y": 3.0 * a - 0.5 * b + 0.1 * a * b, "status": "ok"})
    df = pd.DataFrame(rows)
    df.loc[(df["a"] == 1.0) & (df["b"] == 20.0), "status"] = "failed"  # not a corner: ignored anyway
    eff = sweep.main_effects(df, ["a", "b"], ["y"])
    # corners (0,10) (0,30) (2,10) (2,30): y = -5, -15, 3, -3
    assert eff.loc["a", "y"] == pytest.approx(((3 - 3) / 2) - ((-5 - 15) / 2))
    assert eff.loc["b", "y"] == pytest.approx(((-15 - 3) / 2) - ((-5 + 3) / 2))
    assert eff.attrs["levels"] == {"a": (0.0, 2.0), "b": (10.0, 30.0)} and eff.attrs["n_corners"] == 4
    assert sweep.corner_points(df, ["a", "b"]).sum() == 4
    df.loc[(df["a"] == 2.0), "status"] = "failed"
    eff = sweep.main_effects(df, ["a", "b"], ["y"])
    assert math.isnan(eff.loc["a", "y"])  # no successful corner at the high level of a
