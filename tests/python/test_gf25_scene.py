"""The headline scene (paper 001, GF25 batch agglomeration of maltodextrin) through the Python API and the CLI,
and the published trends over the Table-1 design. Nothing here is tuned: the scene's defaults are the paper's
values and docs/paper001_decisions.md; a trend that did not hold would be reported, not forced."""
import math
import os

import numpy as np
import pytest
import yaml
from conftest import ROOT, SCENE, assert_bad_input, cli, run_bad_scene, scene_with, sha256, strict_json

import granuflow as gf
from granuflow import sweep

TABLE1 = os.path.join(ROOT, "flowsheets", "stoeckl_gf25_table1.yaml")
TABLE1_100C = os.path.join(ROOT, "flowsheets", "stoeckl_gf25_table1_100C.yaml")
SUMMARY_KEYS = ("scene", "t_end_s", "d10_um", "d50_um", "d90_um", "bed_moisture", "T_gas_out_K", "balance",
                "wall_time_s", "solver")


# ------------------------------------------------------------------------------------------------
# one run of the headline scene
# ------------------------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def headline():
    return gf.load(SCENE).simulate()


def test_python_run_of_the_headline_scene_is_physical(headline):
    res = headline
    s = res.summary
    assert s["t_end_s"] == 3600.0
    for key in ("d10_um", "d50_um", "bed_moisture", "bed_moisture_wet", "T_gas_out_K"):
        assert s[key] is not None and math.isfinite(s[key]), key
    assert all(v is not None and v <= 1e-6 for v in s["balance"].values()), s["balance"]
    # d90 lies in the top class of the paper's 10-class grid: a lower bound, the grid's end (issue 28)
    assert s["d90_um"] is None and s["d90_um_lower_bound"] == 1000.0
    assert s["d10_um"] < s["d50_um"] < s["d90_um_lower_bound"]
    t_min = res.t / 60.0

    def at(name, minutes):
        return float(np.interp(minutes, t_min, res[name]))

    # agglomeration: the mass median grows from the initial 200 um; growth slows down (equilibrium after ~25 min)
    d50 = res["bed.d50"] * 1e6
    assert d50[0] == pytest.approx(200.0, rel=0.05)
    assert s["d50_um"] > 1.5 * d50[0]
    assert np.all(np.diff(d50) > -1e-6 * d50[1:])  # no shrinking of the median in this scene
    assert at("bed.d50", 60) - at("bed.d50", 30) < 0.25 * (at("bed.d50", 30) - at("bed.d50", 0))
    # moisture rises after the spray starts and levels off (plateau after ~15 min)
    w = res["bed.moisture_wet"]
    assert w[0] == pytest.approx(0.03, rel=1e-3)  # 3 wt% wet basis initially (X0 = 0.0309)
    assert s["bed_moisture_wet"] > w[0]
    assert abs(at("bed.moisture_wet", 60) - at("bed.moisture_wet", 30)) < 0.25 * abs(
        at("bed.moisture_wet", 30) - at("bed.moisture_wet", 0))
    assert s["bed_moisture_wet"] == pytest.approx(s["bed_moisture"] / (1 + s["bed_moisture"]), rel=1e-9)
    # the evaporating spray cools the gas below the 60 degC inlet, and the bed is not colder than the spray liquid
    assert 283.15 < s["T_gas_out_K"] < 333.15
    assert 283.15 < res["bed.T"][-1] < 333.15
    # the PSD is a distribution of the 15 kg bed (dry solid 14.55 kg, plus water)
    psd = res.psd(3600.0)
    assert psd["mass_fraction"].sum() == pytest.approx(1.0)
    assert psd["d_um"].iloc[0] == pytest.approx(50.0) and psd["d_um"].iloc[-1] == pytest.approx(1000.0)
    # the spray is water (nozzle.w = 0) and aggregates past the top class are folded into it: the dry solid on the
    # grid is the initial 15 kg / (1 + X0) at every time, to the solids closure (was rel=0.02, which would pass a
    # 0.3 kg leak)
    assert gf.load(SCENE).get("nozzle.w") == 0.0
    assert psd["mass_kg"].sum() == pytest.approx(15.0 / 1.030928, rel=1e-9)
    assert res.psd(0.0)["mass_kg"].sum() == pytest.approx(psd["mass_kg"].sum(), rel=1e-12)
    # mass fractions and the cumulative distribution agree
    assert np.allclose(np.cumsum(psd["mass_fraction"]), psd["Q3"], atol=1e-12)


def test_cli_run_writes_summary_csv_and_plots(tmp_path, headline):
    out = tmp_path / "out"
    before = sha256(SCENE)
    p = cli("run", SCENE, "--out", out)
    assert p.returncode == 0, p.stderr
    assert sha256(SCENE) == before
    s = strict_json(out / "summary.json")
    for key in SUMMARY_KEYS:
        assert key in s, key
    assert s["scene"] == "stoeckl_gf25_batch" and s["t_end_s"] == 3600.0
    for key in ("d10_um", "d50_um", "bed_moisture", "T_gas_out_K"):
        assert isinstance(s[key], float) and math.isfinite(s[key]), key
    assert s["d90_um"] is None and s["d90_um_lower_bound"] == 1000.0  # d90 in the top class: the grid's end
    assert set(s["balance"]) == {"water_rel", "solids_rel", "energy_rel"}
    assert all(v is not None and 0 <= v <= 1e-6 for v in s["balance"].values()), s["balance"]
    assert set(s["solver"]) >= {"states", "steps", "residuals", "jacobians"}
    assert s["wall_time_s"] > 0
    # the CLI and the Python API give the same answer
    for key in ("d10_um", "d50_um", "d90_um_lower_bound", "bed_moisture", "bed_moisture_wet", "T_gas_out_K"):
        assert s[key] == pytest.approx(headline.summary[key], rel=1e-9), key
    import pandas as pd

    ts = pd.read_csv(out / "timeseries.csv", index_col=0)
    assert len(ts) == 121 and ts.index[-1] == 3600.0
    assert {"bed.d10 [um]", "bed.d50 [um]", "bed.d90 [um]", "bed.moisture_wet [kg/kg]", "gas.T [K]",
            "bed.T [K]"} <= set(ts.columns)
    assert np.isfinite(ts.to_numpy()).all()
    # sizes in µm in the CSV as in summary.json (the same number, not 5e-4 m in one file and 500 µm in the other)
    for d in ("d10", "d50"):
        assert ts[f"bed.{d} [um]"].iloc[-1] == pytest.approx(s[f"{d}_um"], rel=1e-9)
        assert s["units"][f"{d}_um"] == "um"
    assert not any(c.startswith("bed.d50 [m]") for c in ts.columns)
    # each quantity once: no output that repeats a state of its unit under another name
    assert "bed.M_0 [kg]" in ts.columns and not any(c.startswith("bed.psd_m_") for c in ts.columns)
    assert "bed.H [J]" in ts.columns and "bed.balance_energy_hold [J]" not in ts.columns
    cols = ts.to_numpy().T
    by_unit = {}
    for c, v in zip(ts.columns, cols):
        by_unit.setdefault(c.split(".")[0], []).append((c, v))
    for unit, cs in by_unit.items():
        for i, (a, va) in enumerate(cs):
            for b, vb in cs[i + 1:]:
                assert not (np.array_equal(va, vb) and np.ptp(va) > 0), (a, b)
    plots = yaml.safe_load(open(SCENE))["plots"]
    names = [spec["file"] for spec in plots]
    assert names == ["diameters.png", "moisture.png", "temperatures.png", "psd.png"]
    for name in names:
        assert (out / name).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n", name
        assert (out / name).stat().st_size > 5000, name


# ------------------------------------------------------------------------------------------------
# bad input: exit 2, one line naming the key, the value and what is allowed; the input is never modified
# ------------------------------------------------------------------------------------------------


with open(SCENE) as _f:
    _TEXT = _f.read()
UNITS_BLOCK = _TEXT[_TEXT.index("units:\n"):_TEXT.index("connections:")]  # every unit of the scene

BAD_SCENES = {
    # missing
    "missing t_end": ("t_end: 60 min\n", "", ["t_end", "missing required key"]),
    "missing unit type": ("    type: fluid_bed\n", "", ["units.bed.type", "missing required key"]),
    "missing connection": ("  - gas.out -> exhaust.in\n", "", ["gas.out", "not connected"]),
    # misspelt
    "misspelt parameter": ("bed_mass: 15 kg", "bed_mas: 15 kg",
                           ["units.bed.params.bed_mas", "unknown parameter 'bed.bed_mas'", "bed_mass, X0"]),
    "misspelt unit type": ("type: fluid_bed", "type: fluid_beds",
                           ["units.bed.type", "'fluid_beds'", "allowed:", "fluid_bed,"]),
    "misspelt top-level key": ("solver: {", "solvr: {", ["solvr: unknown key", "allowed:", "solver"]),
    "misspelt port": ("  - inlet.out -> gas.in\n", "  - inlet.out -> gas.inn\n", ["'inn'", "ports: in,"]),
    "misspelt setting value": ("    type: fluid_bed\n", "    type: fluid_bed\n    settings: {aggregation: sometimes}\n",
                               ["units.bed.settings.aggregation", "'sometimes'", "none, constant", "glass_transition"]),
    # mistyped
    "list for a number": ("bed_mass: 15 kg", "bed_mass: [15]",
                          ["units.bed.params.bed_mass", "expected a single value"]),
    "word for a number": ("bed_mass: 15 kg", "bed_mass: fifteen",
                          ["units.bed.params.bed_mass", "'fifteen'", "expected a number with an optional unit", "kg"]),
    "wrong unit": ("mdot: 90 g/min", "mdot: 90 degC", ["units.nozzle.params.mdot", "'degC'", "must be in kg/s"]),
    "word for an integer": ("settings: {classes: 10,", "settings: {classes: ten,",
                            ["particles.settings.classes", "'ten'", "integer in [3, 2000]"]),
    # out of range
    "inlet temperature": ("T: 60 degC", "T: 900 degC", ["units.inlet.params.T", "1173.15 K", "250 <= T <= 600"]),
    "size spread": ("sigma_0: 1.5", "sigma_0: 0.5", ["units.bed.params.sigma_0", "0.5", "1.01 <= sigma_0 <= 5"]),
    "class count": ("settings: {classes: 10,", "settings: {classes: 1,",
                    ["particles.settings.classes", "= 1", "3 <= classes <= 2000"]),
    "grid bounds": ("d_max: 1000e-6", "d_max: 10e-6", ["particles.settings.d_max", "1e-05 m", "d_max > d_min"]),
    "negative tolerance": ("rtol: 1e-6", "rtol: -1", ["rtol = -1", "0 < rtol < 1"]),
    # syntax, structure, non-finite values, times
    "YAML syntax error": ("T: 60 degC, Y: 5 g/kg}", "T: 60 degC, Y: 5 g/kg", ["not valid YAML"]),
    "no units": (UNITS_BLOCK, "units: {}\n", ["units", "non-empty"]),
    "key given twice": ("bed_mass: 15 kg,", "bed_mass: 15 kg, bed_mass: 30 kg,",
                        ["units.bed.params.bed_mass", "twice"]),
    "NaN parameter": ("bed_mass: 15 kg", "bed_mass: .nan",
                      ["units.bed.params.bed_mass", "'.nan'", "expected a number"]),
    "infinite parameter": ("bed_mass: 15 kg", "bed_mass: inf kg", ["units.bed.params.bed_mass", "'inf kg'",
                                                                   "expected a number"]),
    "zero end time": ("t_end: 60 min", "t_end: 0 min", ["t_end = 0", "t_end > 0"]),
    "negative end time": ("t_end: 60 min", "t_end: -5 min", ["t_end = -300", "t_end > 0"]),
    "output time past the end": ("output: {n: 121}", "output: {times: [0 s, 30 min, 90 min]}",
                                 ["t_out", "5400", "t_end"]),
    # connections
    "port connected twice": ("  - gas.out -> exhaust.in\n", "  - gas.out -> exhaust.in\n  - inlet.out -> exhaust.in\n",
                             ["exhaust.in", "connected twice"]),
    "stream kinds differ": ("  - gas.out -> exhaust.in\n", "  - gas.out -> spray_zone.liquid\n",
                            ["gas.out -> spray_zone.liquid", "gas vs liquid"]),
    "two particle systems": ("    type: spray_zone\n", "    type: spray_zone\n    settings: {particles: grid2}\n",
                             ["units.spray_zone.settings.particles", "'grid2'", "no particle system"]),
}


@pytest.mark.parametrize("case", list(BAD_SCENES))
def test_cli_bad_scene_exits_2_with_one_line(tmp_path, case):
    old, new, needles = BAD_SCENES[case]
    run_bad_scene(tmp_path, scene_with(tmp_path, old, new), *needles)


@pytest.mark.parametrize("args,needles", [
    (["--set", "nozzle.mdot=-5 g/min"], ["nozzle.mdot", "-8.33", "0 <= mdot <= 1"]),
    (["--set", "nozzle.mdott=5"], ["unknown parameter 'nozzle.mdott'", "mdot, T, w, t_on, t_off"]),
    (["--set", "inlet.T=60 m3/h"], ["inlet.T", "'m3/h'", "must be in K"]),
    (["--t-end", "an hour"], ["--t-end", "'an hour'", "60 min"]),
    (["--set", "nozzle.mdot=nan"], ["nozzle.mdot", "'nan'", "expected a number"]),
    (["--t-end", "0"], ["t_end = 0", "t_end > 0"]),
])
def test_cli_bad_options_exit_2_and_leave_the_scene_alone(tmp_path, args, needles):
    before = sha256(SCENE)
    p = cli("run", SCENE, "--out", tmp_path / "out", *args)
    assert_bad_input(p, *needles)
    assert sha256(SCENE) == before
    assert not (tmp_path / "out" / "summary.json").exists()


# ------------------------------------------------------------------------------------------------
# the Table-1 design: published trends with the default parameters
# ------------------------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def table1():
    df = sweep.load_sweep(TABLE1).run(workers=2, progress=False)
    effects = sweep.main_effects(df)
    print("\nTable-1 design (60 min):")
    print(df[["point", "V_air_m3h", "T_in_degC", "spray_g_min", "d50_um", "bed_moisture_wet", "T_gas_out_K",
              "status"]].to_string(index=False))
    print("main effects over the cube corners:")
    print(effects[["d50_um", "bed_moisture_wet", "T_gas_out_K"]].to_string())
    return df, effects


def test_table1_every_point_solves_and_the_centre_is_the_headline_run(table1, headline):
    df, _ = table1
    assert len(df) == 15 and list(df["kind"]).count("corner") == 8 and list(df["kind"]).count("face") == 6
    assert (df["status"] == "ok").all(), df.loc[df["status"] != "ok", ["point", "message"]]
    for out in sweep.DEFAULT_OUTPUTS:
        if out == "d90_um":  # null where d90 lies in the top class of the 10-class grid, and the point says so
            clipped = ~np.isfinite(df[out])
            assert 0 < clipped.sum() < len(df)
            assert df.loc[clipped, "message"].str.contains("d90 lies in the top size class").all()
            continue
        assert np.isfinite(df[out]).all(), out
    centre = df.set_index("point").loc["Z"]
    assert (centre["V_air_m3h"], centre["T_in_degC"], centre["spray_g_min"]) == (700, 60, 90)
    assert centre["d50_um"] == pytest.approx(headline.summary["d50_um"], rel=1e-9)


def test_table1_d50_increases_with_spray_rate_at_fixed_air_flow_and_temperature(table1):
    df, _ = table1
    groups = df.groupby(["V_air_m3h", "T_in_degC"])
    n = 0
    for (V, T), g in groups:
        if len(g) < 2:
            continue
        g = g.sort_values("spray_g_min")
        assert np.all(np.diff(g["d50_um"].to_numpy()) > 0), (V, T, g[["spray_g_min", "d50_um"]])
        n += 1
    assert n == 5  # four corner pairs and the centre line (F5, Z, F6)


def test_table1_spray_rate_has_by_far_the_strongest_effect_on_d50(table1):
    _, eff = table1
    d50 = eff["d50_um"]
    assert d50["spray_g_min"] > 0
    assert abs(d50["spray_g_min"]) > abs(d50["V_air_m3h"])
    assert abs(d50["spray_g_min"]) > abs(d50["T_in_degC"])


def test_table1_bed_ends_drier_at_higher_inlet_temperature(table1):
    _, eff = table1
    assert eff.loc["T_in_degC", "bed_moisture"] < 0
    assert eff.loc["T_in_degC", "bed_moisture_wet"] < 0
    # and, as the energy balance demands, the outlet gas is warmer and the bed wetter at a higher spray rate
    assert eff.loc["T_in_degC", "T_gas_out_K"] > 0
    assert eff.loc["spray_g_min", "bed_moisture_wet"] > 0


def test_table1_d50_decreases_with_inlet_temperature_and_air_flow_as_published(table1):
    """Paper 001, section 4.2: d50,3 decreases with inlet temperature; inlet flow and temperature have a similar,
    weaker effect than the spray rate. These main effects are small (a few um of ~500) in this model; they hold
    with the default parameters, so they are asserted (if a model change flips them, report, do not tune)."""
    _, eff = table1
    d50 = eff["d50_um"]
    print(f"\nmain effect on d50,3: inlet temperature {d50['T_in_degC']:+.2f} um, air flow {d50['V_air_m3h']:+.2f} um, "
          f"spray rate {d50['spray_g_min']:+.2f} um")
    assert d50["T_in_degC"] < 0
    assert d50["V_air_m3h"] < 0


# ------------------------------------------------------------------------------------------------
# the sweep command line, end to end
# ------------------------------------------------------------------------------------------------
def _two_point_sweep(tmp_path, scene=SCENE, extra=""):
    text = f"""
sweep: two_points
scene: {os.path.relpath(scene, tmp_path)}
variables:
  spray_g_min: {{param: nozzle.mdot, unit: g/min}}
  T_in_degC: {{param: inlet.T, unit: degC}}
points:
  - {{name: low, spray_g_min: 60, T_in_degC: 60}}
  - {{name: high, spray_g_min: "2 g/s", T_in_degC: "333.15 K"}}
outputs: [d50_um, bed_moisture_wet, T_gas_out_K]
t_end: 30 min
{extra}"""
    path = tmp_path / "two_points.yaml"
    path.write_text(text)
    return str(path)


def test_cli_sweep_two_points_end_to_end(tmp_path):
    path = _two_point_sweep(tmp_path)
    before = sha256(path)
    out = tmp_path / "out"
    p = cli("sweep", path, "--out", out, "--workers", 2, "--set", "inlet.V_dot=650 m3/h", "--no-progress")
    assert p.returncode == 0, p.stderr
    assert sha256(path) == before
    import pandas as pd

    df = pd.read_csv(out / "sweep.csv")
    assert list(df["point"]) == ["low", "high"]
    assert list(df["spray_g_min"]) == pytest.approx([60.0, 120.0]) and list(
        df["T_in_degC"]) == pytest.approx([60.0, 60.0])  # names that hold their unit keep it
    assert (df["status"] == "ok").all()
    assert df["d50_um"].iloc[1] > df["d50_um"].iloc[0]
    # every number carries its unit: in the header, or in the name itself (d50_um, T_gas_out_K, wall_time_s)
    assert {"wall_time_s", "message", "d50_um", "bed_moisture_wet [kg/kg]", "T_gas_out_K"} <= set(df.columns)
    js = strict_json(out / "sweep.json")
    assert js["units"]["d50_um"] == "um" and js["units"]["bed_moisture_wet"] == "kg/kg"
    assert js["sweep"] == "two_points" and js["n_points"] == 2 and js["n_failed"] == 0
    assert js["t_end_s"] == 1800.0 and js["overrides"] == {"inlet.V_dot": "650 m3/h"}
    assert js["variables"]["spray_g_min"] == {"param": "nozzle.mdot", "unit": "g/min", "levels": []}
    assert [r["point"] for r in js["points"]] == ["low", "high"]
    assert js["points"][1]["d50_um"] == pytest.approx(df["d50_um"].iloc[1], rel=1e-12)
    # the same point through the Python API and `granuflow run`
    fs = gf.load(SCENE).set("inlet.V_dot", "650 m3/h").set("nozzle.mdot", "120 g/min")
    assert fs.simulate(t_end=1800.0).summary["d50_um"] == pytest.approx(df["d50_um"].iloc[1], rel=1e-9)


def test_cli_sweep_exit_3_only_when_every_point_fails(tmp_path):
    scene = tmp_path / "gf25_few_steps.yaml"
    text = open(SCENE).read()
    scene.write_text(text.replace("\nsolver: {", "\nsolver: {max_steps: 5, "))
    path = _two_point_sweep(tmp_path, scene=str(scene))
    p = cli("sweep", path, "--out", tmp_path / "out", "--quiet")
    assert p.returncode == 3, p.stderr
    assert "2 of 2 points failed" in p.stderr and "failed at t = " in p.stderr
    js = strict_json(tmp_path / "out" / "sweep.json")
    assert js["n_failed"] == 2 and all(r["status"] == "failed" and r["d50_um"] is None for r in js["points"])


@pytest.mark.parametrize("old,new,needles", [
    ("outputs:", "outputz:", ["outputz: unknown key", "allowed:", "outputs"]),
    ("param: nozzle.mdot", "param: nozzle.mdt", ["variables.spray_g_min.param", "'nozzle.mdt'", "nozzle.mdot"]),
    ("unit: g/min", "unit: degC", ["variables.spray_g_min.unit", "'degC'", "kg/s"]),
    ("spray_g_min: 60,", "spray_g_min: -60,", ["points[0] (low).spray_g_min = -60", "0 <= mdot <= 1"]),
    ("spray_g_min: 60,", "spray_g_min: sixty,", ["points[0] (low).spray_g_min = 'sixty'", "expected a number"]),
    ("[d50_um,", "[d55_um,", ["outputs", "'d55_um'", "d50_um"]),
    ("name: high", "name: low", ["points[1] (low)", "duplicate point name 'low'"]),
    ("spray_g_min: 60,", "spray_g_min: .nan,", ["points[0] (low).spray_g_min = nan", "expected a number"]),
    ("t_end: 30 min", "t_end: .nan", ["t_end = nan", "expected seconds"]),
])
def test_cli_sweep_bad_file_exits_2(tmp_path, old, new, needles):
    good = _two_point_sweep(tmp_path)
    text = open(good).read()
    assert old in text
    path = tmp_path / "bad_sweep.yaml"
    path.write_text(text.replace(old, new, 1))
    before = sha256(path)
    p = cli("sweep", path, "--out", tmp_path / "out")
    assert_bad_input(p, *needles, path=path)
    assert sha256(path) == before
    assert not (tmp_path / "out").exists()


def test_table1_files_differ_only_in_the_upper_temperature_level():
    a, b = sweep.load_sweep(TABLE1), sweep.load_sweep(TABLE1_100C)
    assert [v.param for v in a.variables] == ["inlet.V_dot", "inlet.T", "nozzle.mdot"]
    assert a.variables[1].levels == [40, 60, 80] and b.variables[1].levels == [40, 60, 100]
    assert [v.levels for v in a.variables if v.name != "T_in_degC"] == [v.levels for v in b.variables
                                                                        if v.name != "T_in_degC"]
    for pa, pb in zip(a.points, b.points):
        assert pa["name"] == pb["name"] and pa["V_air_m3h"] == pb["V_air_m3h"]
        assert pb["T_in_degC"] == (100 if pa["T_in_degC"] == 80 else pa["T_in_degC"])
    levels = {(p["V_air_m3h"], p["T_in_degC"], p["spray_g_min"]) for p in a.points}
    assert len(levels) == 15  # 8 corners + 6 face centres + 1 centre of the 3x3x3 cube
    corners = {(V, T, S) for V in (600, 800) for T in (40, 80) for S in (60, 120)}
    faces = {(600, 60, 90), (800, 60, 90), (700, 40, 90), (700, 80, 90), (700, 60, 60), (700, 60, 120)}
    assert levels == corners | faces | {(700, 60, 90)}


def test_banded_solver_says_when_the_matrix_is_not_band_plus_low_rank():
    """Aggregation couples every class pair: `linear_solver: banded` factors each setup densely, gives the dense
    answer, and its name in the run's stats says how many setups fell back (never silently another solver)."""
    fs = gf.load(SCENE)
    dense, banded = fs.simulate(linear_solver="dense"), fs.simulate(linear_solver="banded")
    assert banded["bed.d50"][-1] == dense["bed.d50"][-1]
    n = banded.stats["linear_solver"].split("; ")[1].split()
    assert n[0] == n[2] and int(n[0]) > 0 and "setups dense LU (the matrix was not band + low rank" in \
        banded.stats["linear_solver"]
    assert "setups dense" not in dense.stats["linear_solver"]


def test_linear_solver_choice_follows_the_jacobian_fill():
    """At 200 classes (spray zone inlined) aggregation couples every class pair: `linear_solver: auto` takes the
    class-local Newton matrix (issue 32), which gives the dense run within the tolerance; the band + low-rank solver
    finds no band there and factors every setup densely, as the dense solver would, to the bit, and after two such
    setups in a row the next ones do not look for the form. A long chain of tanks (no size classes) is sparse."""
    from granuflow import bench

    fine = gf.load_text(bench.scene_variant_text(SCENE, 200), "gf25_200")
    res = fine.simulate(t_end=600, t_out=[0, 600], linear_solver="banded")
    n = res.stats["linear_solver"].split("; ")[1].split()
    assert res.stats["linear_solver"].startswith("banded") and n[0] == n[2] and int(n[0]) > 0
    assert "without looking, after it was not twice in a row" in res.stats["linear_solver"]
    dense = fine.simulate(t_end=600, t_out=[0, 600], linear_solver="dense")
    assert dense.stats["linear_solver"] == "dense (Eigen LU)"
    assert np.array_equal(res.y, dense.y) and res.stats["steps"] == dense.stats["steps"]
    auto = fine.simulate(t_end=600, t_out=[0, 600])
    assert auto.stats["linear_solver"].startswith("class_local")
    assert np.allclose(auto["bed.d50"], dense["bed.d50"], rtol=1e-5, atol=0)
    # explicit: the spray zone's 3 per class, T and tau at the 201 faces, ..., the droplets' flows and w (2 + 2)
    assert (res.stats["states"], res.stats["explicit_states"]) == (2 * 200 + 9, 3 * 200 + 1 + 201 + 4 + 3 + 4 + 1)
    assert all(v < res.rtol for v in res.summary["balance"].values())
    # a dense run starts each segment by the exact Newton on its algebraic states; a sparse one by IDACalcIC
    assert (res.stats["newton_starts"], res.stats["calcic_starts"]) == (1 + res.stats["reinits"], 0)
    chain = gf.load_text(bench.tank_chain_text(600), "chain")
    res = chain.simulate(method="ida")  # auto takes the (non-stiff) chain to an explicit method: no linear solver
    assert res.stats["states"] > 1000 and res.stats["linear_solver"].startswith("sparse")
    assert (res.stats["newton_starts"], res.stats["calcic_starts"]) == (0, 1 + res.stats["reinits"])


@pytest.mark.parametrize("scene, classes", [("two_zone_layering.yaml", 200), ("tanks_in_series_rtd.yaml", 30)])
def test_auto_factors_fine_layering_and_residence_grids_as_band_plus_low_rank(scene, classes):
    """Past dense_limit (400 unknowns) `auto` took dense LU (two zones at 200 classes: 0.23 s against 0.115 s banded)
    or KLU (30 classes in the tank chains: 0.92 s against 0.12 s, its LU filling in); it now takes the band + low-rank
    solver, which holds for every setup here and gives the dense run within the integrator's tolerance."""
    fs = gf.load(os.path.join(ROOT, "flowsheets", scene)).with_settings({"particles.classes": classes})
    auto = fs.simulate(linear_solver="auto", warn=False, grid_check=False, accuracy=False)
    dense = fs.simulate(linear_solver="dense", warn=False, grid_check=False, accuracy=False)
    assert auto.stats["states"] > 400 and auto.stats["linear_solver"].startswith("banded")
    assert "setups dense" not in auto.stats["linear_solver"]
    # every state at every output time within 100 x the tolerances (measured: 1.5e-8 and 1.2e-9 of each state's
    # largest value, against 1e-7 and 1e-5 allowed)
    scale = np.abs(dense.y).max(axis=0)
    assert np.all(np.abs(auto.y - dense.y).max(axis=0) <= 100 * (dense.rtol * scale + dense.atol))


def test_plots_say_when_the_size_grid_clips_a_curve(headline):
    """In the headline scene a fifth of the mass ends in the top class (1000 µm): d90 is capped by the grid, d50
    and d10 are not; the PSD plot and the series legend say so."""
    from granuflow.plots.series import CLIP_FRACTION, clipped_top_um

    top = headline.summary["top_class_fraction"]
    assert 0.1 < top < 0.5
    assert clipped_top_um(headline, "bed.d90", "m") == pytest.approx(1000.0, rel=1e-6)
    assert clipped_top_um(headline, "bed.d50", "m") is None
    assert clipped_top_um(headline, "bed.d10", "m") is None
    assert clipped_top_um(headline, "gas.T", "K") is None
    assert headline.psd(3600)["mass_fraction"].iloc[-1] > CLIP_FRACTION


def test_summary_names_the_integrator_that_ran(headline):
    """summary.json says which integrator ran and why: the headline scene has algebraic equations (IDAS); the
    constant-kernel verification scene is a non-stiff ODE (explicit Runge-Kutta under auto, BDF when asked)."""
    assert headline.summary["solver"]["method"].startswith("bdf (IDAS)")
    assert "DAE" in headline.summary["solver"]["method_reason"]
    ode = gf.load(os.path.join(ROOT, "flowsheets", "pbm_constant_kernel.yaml"))
    assert ode.simulate(warn=False).summary["solver"]["method"].startswith("erk")
    assert "CVODES" in ode.simulate(method="bdf", warn=False).summary["solver"]["method"]


def test_the_evaporated_share_of_no_spray_is_undefined():
    """droplets.evaporated_fraction is the evaporating rate over the sprayed rate (paper 001, Eq. (66)); once the
    nozzle stops there is no spray to take a share of: NaN in the time series, never 0 (which reads as "nothing
    evaporates in flight")."""
    fs = gf.load(SCENE).set("nozzle.t_off", 1800.0)
    r = fs.simulate(warn=False, grid_check=False, accuracy=False)
    f = r["droplets.evaporated_fraction"]
    spraying, stopped = r.t < 1800.0, r.t > 1800.0
    assert np.all(np.isfinite(f[spraying])) and np.all((f[spraying] > 0) & (f[spraying] < 1))
    assert stopped.sum() > 10 and np.all(np.isnan(f[stopped]))
