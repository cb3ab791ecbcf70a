"""Bad input on the command line (run, calibrate, contour): exit 2 and one line naming the file, the key, the value
and what is allowed; no traceback, no silent fallback, clipping or dropping; the input files are never modified."""
import json
import math

import pytest
from conftest import SCENE, assert_bad_input, cli, run_bad_scene, scene_with, sha256

import granuflow as gf
from granuflow import calibration as cal

with open(SCENE) as _f:
    SCENE_TEXT = _f.read()
DIAMETER_PLOT = ("{title: Characteristic diameters, y: [bed.d10, bed.d50, bed.d90], unit: um, ylabel: d_x3, "
                 "file: diameters.png}")
PSD_PLOT = "{kind: psd, times_min: [0, 5, 15, 30, 60], file: psd.png}"
assert DIAMETER_PLOT in SCENE_TEXT and PSD_PLOT in SCENE_TEXT


# ------------------------------------------------------------------------------------------------ run: plots
@pytest.mark.parametrize("unit, needles", [
    ("blorp", ["plots[0].unit", "'blorp'", "allowed", "um"]),
    ("degC", ["plots[0].unit", "'degC'", "bed.d10", "allowed: m, mm, um"]),
])
def test_plot_unit_unknown_or_of_the_wrong_dimension(tmp_path, unit, needles):
    path = scene_with(tmp_path, DIAMETER_PLOT, DIAMETER_PLOT.replace("unit: um", f"unit: {unit}"))
    run_bad_scene(tmp_path, path, *needles)
    assert not (tmp_path / "out").exists()  # rejected before the run


def test_display_conversion_refuses_unknown_units():
    from granuflow import quantity

    with pytest.raises(ValueError, match="blorp"):
        quantity.convert([1.0], "blorp", "m")
    with pytest.raises(ValueError, match="degC"):
        quantity.convert([1.0], "degC", "m")
    assert quantity.convert([300.0], "degC", "K")[0] == pytest.approx(26.85)
    assert quantity.convert([2e-4], "um", "m")[0] == pytest.approx(200.0)
    assert quantity.from_si(0.05, "wt%", "kg/kg") == pytest.approx(5.0)
    assert quantity.difference_to_si("2 degC", "K", "sigma") == pytest.approx(2.0)


@pytest.mark.parametrize("times, bad", [("[-5, 5, 60]", "-5"), ("[0, 30, 90]", "90")])
def test_psd_times_outside_the_run(tmp_path, times, bad):
    path = scene_with(tmp_path, PSD_PLOT, PSD_PLOT.replace("[0, 5, 15, 30, 60]", times))
    run_bad_scene(tmp_path, path, "plots[3].times_min", f"= {bad}", "[0, 60]")


def test_psd_times_after_a_shorter_command_line_end_are_left_out_and_said(tmp_path):
    """The scene's plot times are checked against its own t_end; `--t-end 30 min` is a valid shorter run whose
    PSD plot leaves out the 60-min curve and says so."""
    path = tmp_path / "scene.yaml"
    path.write_text(SCENE_TEXT)
    p = cli("run", path, "--out", tmp_path / "out", "--t-end", "30 min")
    assert p.returncode == 0, p.stderr
    assert "psd.png (times after the run's end left out: 60 min)" in p.stdout
    assert (tmp_path / "out" / "psd.png").stat().st_size > 0
    assert json.loads((tmp_path / "out" / "summary.json").read_text())["t_end_s"] == 1800.0


@pytest.mark.parametrize("file, needles", [
    ("../../escape.png", ["plots[0].file", "'../../escape.png'", "plain file name"]),
    ("sub/d.png", ["plots[0].file", "'sub/d.png'", "plain file name"]),
    ("psd.docx", ["plots[0].file", "'psd.docx'", "docx", "allowed:", "png"]),
])
def test_plot_file_must_be_an_image_inside_the_output_folder(tmp_path, file, needles):
    path = scene_with(tmp_path, DIAMETER_PLOT, DIAMETER_PLOT.replace("file: diameters.png", f"file: '{file}'"))
    run_bad_scene(tmp_path, path, *needles)
    assert not (tmp_path / "out").exists()
    assert not (tmp_path.parent.parent / "escape.png").exists()


def test_psd_file_extension_checked_before_the_run(tmp_path):
    path = scene_with(tmp_path, PSD_PLOT, PSD_PLOT.replace("psd.png", "psd.docx"))
    run_bad_scene(tmp_path, path, "plots[3].file", "psd.docx", "allowed:")
    assert not (tmp_path / "out" / "summary.json").exists()


def test_out_is_an_existing_file(tmp_path):
    afile = tmp_path / "afile"
    afile.write_text("keep me")
    p = cli("run", SCENE, "--out", afile)
    assert_bad_input(p, "--out", str(afile), "existing file")
    assert afile.read_text() == "keep me"
    p = cli("run", SCENE, "--out", afile / "sub")
    assert_bad_input(p, "--out", "is a file")


# ------------------------------------------------------------------------------------------------ calibrate
STAGES_OK = """name: small
start: {wall.k_wall: 20}
stages:
  - name: wall
    free:
      wall.k_wall: {transform: log, lower: 1, upper: 200}
    observables: [gas.T]
"""


def experiments(run_extra="", data="{units: {t: min, gas.T: degC}, t: [5, 10], gas.T: [36.0, 35.0]}",
                set_="{inlet.T: 60 degC}", sigma="{gas.T: {abs: 2 K}, bed.d50: {rel: 0.07}}"):
    return (f"scene: {SCENE}\nsigma: {sigma}\nruns:\n  - name: A\n    set: {set_}\n{run_extra}"
            f"    data: {data}\n")


def calibrate_bad(tmp_path, exp_text, stage_text, *needles, blame="exp"):
    exp = tmp_path / "exps.yaml"
    exp.write_text(exp_text)
    st = tmp_path / "stages.yaml"
    st.write_text(stage_text)
    files = [exp, st] + sorted(tmp_path.glob("*.csv"))
    before = [sha256(f) for f in files]
    p = cli("calibrate", exp, "--stages", st, "--out", tmp_path / "out", "--no-progress", timeout=120)
    assert_bad_input(p, *needles, path=exp if blame == "exp" else st)
    assert [sha256(f) for f in files] == before
    assert not (tmp_path / "out").exists()
    return p


def test_valid_small_files_load(tmp_path):
    exp = tmp_path / "exps.yaml"
    exp.write_text(experiments())
    st = tmp_path / "stages.yaml"
    st.write_text(STAGES_OK)
    es = cal.load_experiments(exp)
    plan = cal.load_stages(st, es.flowsheet())
    cal.check_stage_data(plan, es.calibration, str(st), str(exp))
    assert es.experiments[0].observation("gas.T").value[0] == pytest.approx(309.15)
    assert plan.start["wall.k_wall"] == 20


@pytest.mark.parametrize("t_end, needles", [
    ("0 min", ["run A.t_end", "'0 min'", "0 < t_end"]),
    ("-5 min", ["run A.t_end", "'-5 min'", "0 < t_end"]),
    (".nan", ["run A.t_end", "nan", "0 < t_end"]),
])
def test_experiment_t_end_must_be_positive(tmp_path, t_end, needles):
    calibrate_bad(tmp_path, experiments(f"    t_end: {t_end}\n"), STAGES_OK, *needles)


def test_data_after_t_end(tmp_path):
    data = "{units: {t: min, gas.T: degC}, t: [5, 20], gas.T: [36.0, 35.0]}"
    calibrate_bad(tmp_path, experiments("    t_end: 10 min\n", data), STAGES_OK,
                  "run A.data.t[1] = 20", "t_end = '10 min'", "0 <= t <= t_end")


@pytest.mark.parametrize("value", [".inf", "-.inf", ".nan"])
def test_inline_inf_or_nan_is_not_missing_data(tmp_path, value):
    data = f"{{units: {{t: min, gas.T: degC}}, t: [5, 10], gas.T: [36.0, {value}]}}"
    calibrate_bad(tmp_path, experiments(data=data), STAGES_OK, "run A.data.gas.T[1]", "t = 10 min",
                  "not a finite number", "null: not measured")


@pytest.mark.parametrize("value", ["inf", "nan", "-Infinity"])
def test_csv_inf_or_nan_is_not_missing_data(tmp_path, value):
    (tmp_path / "A.csv").write_text(f"t [min],gas.T [degC]\n5,36.0\n10,{value}\n")
    calibrate_bad(tmp_path, experiments(data="A.csv"), STAGES_OK, "run A.data", "A.csv:3", "gas.T",
                  "t = 10 min", "not a finite number", "empty")


def test_csv_empty_field_is_not_measured(tmp_path):
    (tmp_path / "A.csv").write_text("t [min],gas.T [degC]\n5,36.0\n10,\n")
    exp = tmp_path / "exps.yaml"
    exp.write_text(experiments(data="A.csv"))
    o = cal.load_experiments(exp).experiments[0].observation("gas.T")
    assert len(o.t) == 1 and o.t[0] == 300.0


def test_all_data_missing(tmp_path):
    data = "{units: {t: min, gas.T: degC}, t: [5, 10], gas.T: [null, null]}"
    calibrate_bad(tmp_path, experiments(data=data), STAGES_OK, "run A.data", "no measured value")
    (tmp_path / "A.csv").write_text("t [min],gas.T [degC]\n")
    calibrate_bad(tmp_path, experiments(data="A.csv"), STAGES_OK, "run A.data", "no measured value")


def test_stage_observes_nothing_measured(tmp_path):
    stages = STAGES_OK.replace("observables: [gas.T]", "observables: [bed.d50]")
    calibrate_bad(tmp_path, experiments(), stages, "stages[0] 'wall'.observables = [bed.d50]",
                  "no calibration run", "measured: gas.T", blame="stages")


def test_start_outside_the_stage_bounds(tmp_path):
    stages = STAGES_OK.replace("start: {wall.k_wall: 20}", "start: {wall.k_wall: 500}")
    calibrate_bad(tmp_path, experiments(), stages, "start.wall.k_wall = 500", "1 <= wall.k_wall <= 200",
                  "stage 'wall'", blame="stages")


@pytest.mark.parametrize("set_, needles", [
    ("{inlet.TT: 60 degC}", ["run A.set.inlet.TT", "unknown parameter 'inlet.TT'", "allowed:"]),
    ("{inlet.T: 5000 degC}", ["run A.set.inlet.T", "'5000 degC'", "declared bounds"]),
    ("{inlet.T: 60 furlong}", ["run A.set.inlet.T", "furlong"]),
])
def test_experiment_set_errors_name_the_file_and_key(tmp_path, set_, needles):
    calibrate_bad(tmp_path, experiments(set_=set_), STAGES_OK, *needles)


@pytest.mark.parametrize("times, needles", [
    ("[5, 5]", ["run A.data.t[1] = 5", "increasing"]),
    ("[-1, 5]", ["run A.data.t[0] = -1", ">= 0"]),
    ("[5, .nan]", ["run A.data.t[1] = nan", "finite"]),
])
def test_bad_data_times(tmp_path, times, needles):
    data = f"{{units: {{t: min, gas.T: degC}}, t: {times}, gas.T: [36.0, 35.0]}}"
    calibrate_bad(tmp_path, experiments(data=data), STAGES_OK, *needles)


def test_unknown_observable_names_the_file_and_key(tmp_path):
    data = "{units: {t: min}, t: [5, 10], bed.dd50: [1, 2]}"
    calibrate_bad(tmp_path, experiments(data=data), STAGES_OK, "run A.data.bed.dd50", "'bed.dd50'")
    stages = STAGES_OK.replace("observables: [gas.T]", "observables: [gas.TT]")
    calibrate_bad(tmp_path, experiments(), stages, "stages[0].observables[0]", "'gas.TT'", blame="stages")


@pytest.mark.parametrize("free, needles", [
    ("{transform: ln, lower: 1, upper: 200}", ["stages[0].free.wall.k_wall.transform = 'ln'", "none, log"]),
    ("{transform: log, lower: 300, upper: 200}", ["stages[0].free.wall.k_wall.upper = 200", "upper > lower"]),
    ("{transform: log, lower: .nan, upper: 200}", ["stages[0].free.wall.k_wall.lower = nan", "not a number"]),
    ("{transform: log, lower: 0, upper: 200}", ["stages[0].free.wall.k_wall.lower = 0", "lower > 0"]),
    ("{transform: log, lower: 1, upper: 5000}", ["stages[0].free.wall.k_wall.upper = 5000", "declared upper"]),
    ("{lower: 1, uper: 200}", ["stages[0].free.wall.k_wall", "unknown key 'uper'"]),
])
def test_bad_bounds_and_transform(tmp_path, free, needles):
    stages = STAGES_OK.replace("{transform: log, lower: 1, upper: 200}", free)
    calibrate_bad(tmp_path, experiments(), stages, *needles, blame="stages")


def test_unknown_or_no_free_parameters(tmp_path):
    stages = STAGES_OK.replace("wall.k_wall: {transform", "wall.k_wal: {transform")
    calibrate_bad(tmp_path, experiments(), stages, "stages[0].free.wall.k_wal", "unknown parameter", blame="stages")
    stages = STAGES_OK.replace("      wall.k_wall: {transform: log, lower: 1, upper: 200}\n", "").replace(
        "free:\n", "free: {}\n")
    calibrate_bad(tmp_path, experiments(), stages, "stages[0].free", "empty", blame="stages")


# ------------------------------------------------------------------------------------------------ core checks
@pytest.fixture(scope="module")
def fs():
    return gf.load(SCENE)


def _exp(values, t=(300.0, 600.0), t_end=None):
    return cal.Experiment("A", {}, [cal.Observation("gas.T", list(t), list(values), 2.0, 0.0)], t_end)


def test_core_rejects_inf_and_data_after_t_end(fs):
    stage = [cal.Stage("wall", [cal.FreeParameter("wall.k_wall", "log", 1.0, 200.0)], ["gas.T"])]
    with pytest.raises(gf.ConfigError, match=r"experiment 'A': observation gas.T.value\[1\] at t = 600"):
        cal.calibrate(fs, [_exp([300.0, math.inf])], stage)
    with pytest.raises(gf.ConfigError, match=r"gas.T.t\[1\].*t <= t_end"):
        cal.calibrate(fs, [_exp([300.0, 301.0], t_end=400.0)], stage)
    with pytest.raises(gf.ConfigError, match="no experiment has data for its observables \\(gas.T\\)"):
        cal.calibrate(fs, [_exp([math.nan, math.nan])], stage)
    with pytest.raises(gf.ConfigError, match=r"start.wall.k_wall = 500.*1 <= wall.k_wall <= 200.*stage 'wall'"):
        cal.calibrate(fs, [_exp([300.0, 301.0])], stage, start={"wall.k_wall": 500.0})
    with pytest.raises(gf.ConfigError, match=r"free parameter wall.k_wall.lower = nan"):
        cal.calibrate(fs, [_exp([300.0, 301.0])],
                      [cal.Stage("wall", [cal.FreeParameter("wall.k_wall", "log", math.nan, 200.0)], ["gas.T"])])
    with pytest.raises(gf.ConfigError, match=r"free parameter wall.k_wall: transform 'ln'"):
        cal.calibrate(fs, [_exp([300.0, 301.0])],
                      [cal.Stage("wall", [cal.FreeParameter("wall.k_wall", "ln", 1.0, 200.0)], ["gas.T"])])
    # the binding no longer checks on its own: the core names the experiment and observation
    with pytest.raises(gf.ConfigError, match=r"experiment 'A': observation gas.T: 2 times but 1 values"):
        cal.predict(fs, [cal.Experiment("A", {}, [cal.Observation("gas.T", [1.0, 2.0], [300.0], 2.0, 0.0)])])
    with pytest.raises(gf.ConfigError, match=r"experiment 'A': observation gas.T.t\[1\]"):
        cal.predict(fs, [_exp([300.0, 301.0], t=(600.0, 300.0))])


# ------------------------------------------------------------------------------------------------ contour
def test_contour_names_the_constraint(tmp_path):
    p = cli("contour", SCENE, "--x", "inlet.T:degC:50:70:3", "--y", "nozzle.mdot:g/min:60:120:3",
            "--constraint", "d55_um>=400", "--out", tmp_path / "out")
    assert_bad_input(p, "--constraint 'd55_um>=400'", "'d55_um'", "allowed:")
    assert not (tmp_path / "out").exists()


def test_contour_caps_the_axis_points(tmp_path):
    p = cli("contour", SCENE, "--x", "inlet.T:degC:50:70:100000", "--y", "nozzle.mdot:g/min:60:120:3",
            "--out", tmp_path / "out", timeout=60)
    assert_bad_input(p, "--x", "100000", "n <= 401")
    h = cli("contour", "--help")
    assert "401" in h.stdout


def test_contour_out_is_an_existing_file(tmp_path):
    afile = tmp_path / "afile"
    afile.write_text("keep")
    p = cli("contour", SCENE, "--x", "inlet.T:degC:50:70:3", "--y", "nozzle.mdot:g/min:60:120:3", "--out", afile)
    assert_bad_input(p, "--out", "existing file")
    assert afile.read_text() == "keep"


def test_stage_file_options_name_the_file(tmp_path):
    stages = STAGES_OK.replace("stages:\n", "options: {max_iterations: 0}\nstages:\n")
    calibrate_bad(tmp_path, experiments(), stages, "options", "max_iterations", ">= 1", blame="stages")
    stages = STAGES_OK.replace("stages:\n", "options: {max_iteration: 5}\nstages:\n")
    calibrate_bad(tmp_path, experiments(), stages, "options", "'max_iteration'", "allowed:", blame="stages")


def test_multi_start_stays_within_every_stage(fs):
    plan = cal.StagePlan("p", [cal.Stage("a", [cal.FreeParameter("wall.k_wall", "log", 1.0, 200.0)]),
                               cal.Stage("b", [cal.FreeParameter("wall.k_wall", "log", 5.0, 50.0)])])
    for s in cal.random_starts(plan, 20, center={"wall.k_wall": 20.0}, spread=3.0, flowsheet=fs):
        assert 5.0 <= s["wall.k_wall"] <= 50.0
