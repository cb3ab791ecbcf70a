"""A table of bad inputs to the Python layer (issue 12): the files it reads itself (sweep, experiment and stage files
in YAML, CSV data), the options of the command line, and the Python API. Each case asserts the exit code 2 (or the
exception type), one line, the names the message must contain (the file, the key, the value, what is allowed) and
that no input file changed. tests/python/test_bad_input_table.py holds the scene loader's cases.

The command-line cases call granuflow's main() in this process (the code of the launcher, without starting Python a
hundred times); a few run the real launcher for the process exit code and the absence of a traceback.
"""
import math
import os
import random
import time

import numpy as np
import pytest

from conftest import DEMO, SCENE, cli, sha256

import granuflow as gf
from granuflow import calibration as cal
from granuflow import cli as gcli
from granuflow import design_space as ds
from granuflow import sweep, textfile

SWEEP = f"""sweep: small
scene: {SCENE}
variables:
  T: {{param: inlet.T, unit: degC}}
points:
  - {{name: a, T: 50}}
outputs: [d50_um]
"""

EXPERIMENTS = f"""scene: {SCENE}
sigma: {{gas.T: {{abs: 2 K}}}}
runs:
  - name: A
    set: {{inlet.T: 60 degC}}
    data: {{units: {{t: min, gas.T: degC}}, t: [5, 10], gas.T: [36.0, 35.0]}}
"""

CSV_RUN = f"""scene: {SCENE}
sigma: {{gas.T: {{abs: 2 K}}}}
runs:
  - name: A
    set: {{inlet.T: 60 degC}}
    data: A.csv
"""

CSV_OK = "t [min],gas.T [degC]\n5,36.0\n10,35.0\n"

STAGES = """name: small
stages:
  - name: wall
    free:
      wall.k_wall: {transform: log, lower: 1, upper: 200}
    observables: [gas.T]
"""

HEATED_TANK = """scene: heated_tank_without_flow
t_end: 1 h
units:
  feed: {type: liquid_feed, params: {mdot: 0 kg/s}}
  tank: {type: stirred_tank, params: {mass: 100 kg, Q: 10 kW}}
  product: {type: liquid_product}
connections: [feed.out -> tank.in, tank.out -> product.in]
"""

with open(DEMO) as _f:
    DEMO_TEXT = _f.read()

UNWRITABLE = "/sys/granuflow-out"  # sysfs refuses new files, even to root (chmod does not stop root)


def sub(text, old, new):
    assert old in text, old
    return text.replace(old, new, 1)


def alias_bomb(levels=9):
    lines = ["a0: &a0 [1,1,1,1,1,1,1,1,1,1]"]
    for k in range(1, levels):
        lines.append(f"a{k}: &a{k} [" + ",".join([f"*a{k - 1}"] * 10) + "]")
    return "\n".join(lines) + f"\nnotes: [*a{levels - 1}]\n"


def deep_block(levels):
    return "notes:\n" + "".join("  " * (k + 1) + "- \n" for k in range(levels - 1)) + "  " * levels + "- x\n"


RANDOM_BYTES = bytes(random.Random(7).randrange(256) for _ in range(3000))


# -- how each case lays out its files ---------------------------------------------------------------------------
def _write(path, content):
    if isinstance(content, bytes):
        path.write_bytes(content)
    else:
        path.write_text(content)
    return path


def _make(tmp_path, name, content):
    """A file, a directory (content "dir"), a fifo (content "fifo") or nothing (content "missing") at name."""
    path = tmp_path / name
    if content == "dir":
        path.mkdir()
    elif content == "fifo":
        os.mkfifo(path)
    elif content != "missing":
        _write(path, content)
    return path


def sweep_case(content, *extra):
    """``granuflow sweep FILE``: the sweep file is the one named."""
    def setup(tmp_path):
        path = _make(tmp_path, "sweep.yaml", content)
        return ["sweep", path, *extra], [path], None if extra else path  # an option's message names the option
    return setup


def experiment_case(content, *extra, csv=None):
    """``granuflow calibrate EXP --stages STAGES``: the experiment file (or its CSV data file) is the one named."""
    def setup(tmp_path):
        exp = _make(tmp_path, "exps.yaml", content)
        st = _write(tmp_path / "stages.yaml", STAGES)
        files = [exp, st]
        named = exp
        if csv is not None:
            named = _make(tmp_path, "A.csv", csv)
            files.append(named)
        return ["calibrate", exp, "--stages", st, "--no-progress", *extra], files, named
    return setup


def stage_case(content):
    def setup(tmp_path):
        exp = _write(tmp_path / "exps.yaml", EXPERIMENTS)
        st = _make(tmp_path, "stages.yaml", content)
        return ["calibrate", exp, "--stages", st, "--no-progress"], [exp, st], st
    return setup


def scene_case(command, *args, scene=SCENE):
    """A command on a shipped scene with bad options: the scene must stay as it is."""
    def setup(tmp_path):
        return [command, scene, *args], [scene], None
    return setup


def scene_file_case(content, command="run", *args):
    def setup(tmp_path):
        path = _make(tmp_path, "scene.yaml", content)
        return [command, path, *args], [path], path
    return setup


# id -> (setup, words the one line must contain)
CLI_CASES = {
    # sweep files: encoding, what stands where the file should, YAML the Python side parses itself
    "sweep_latin1": (sweep_case(SWEEP.encode() + b"notes: caf\xe9\n"),
                     ["line 8, column 11", "byte 0xe9 is not UTF-8", "a sweep file is text in UTF-8"]),
    "sweep_nul_byte": (sweep_case(b"sweep: x\x00\n"), ["line 1, column 9", "control byte 0x00", "not a binary file"]),
    "sweep_utf16": (sweep_case(SWEEP.encode("utf-16")), ["line 1, column 1", "byte 0xff is not UTF-8"]),
    "sweep_random_bytes": (sweep_case(RANDOM_BYTES), ["line 1, column", "a sweep file"]),
    "sweep_directory": (sweep_case("dir"), ["is a directory; expected a sweep file"]),
    "sweep_fifo": (sweep_case("fifo"), ["not a regular file", "expected a sweep file"]),
    "sweep_missing": (sweep_case("missing"), ["No such file or directory", "expected a sweep file"]),
    "sweep_over_1_mib": (sweep_case("# " + "x" * (1 << 20) + "\n" + SWEEP),
                         ["bytes; a sweep file is at most 1048576 bytes"]),
    "sweep_alias_bomb": (sweep_case(SWEEP + alias_bomb()), ["line 13", "more than 200000 values", "alias bomb"]),
    "sweep_alias_cycle": (sweep_case(SWEEP + "notes: &n [1, *n]\n"), ["line 8", "alias *n inside the node it names"]),
    "sweep_undefined_alias": (sweep_case(SWEEP + "notes: *nothing\n"),
                              ["line 8, column 8", "*nothing names no anchor"]),
    "sweep_deep_flow_nesting": (sweep_case(SWEEP + "notes: " + "[" * 5000 + "]" * 5000 + "\n"),
                                ["line 8", "nested deeper than 64 levels"]),
    "sweep_deep_block_nesting": (sweep_case(SWEEP + deep_block(100)), ["nested deeper than 64 levels"]),
    "sweep_python_tag": (sweep_case(SWEEP + "notes: !!python/object/apply:os.system [ls]\n"),
                         ["line 8, column 8", "YAML tag '!!python/object/apply:os.system' is not allowed"]),
    "sweep_include_tag": (sweep_case(SWEEP + "notes: !include other.yaml\n"), ["YAML tag '!include'"]),
    "sweep_binary_tag": (sweep_case(SWEEP + "notes: !!binary aGVsbG8=\n"), ["YAML tag '!!binary'"]),
    "sweep_two_documents": (sweep_case(SWEEP + "---\nsweep: b\n"), ["line 8", "more than one YAML document"]),
    "sweep_key_twice": (sweep_case(SWEEP + "outputs: [d10_um]\n"), ["line 8, column 1", "key 'outputs' given twice"]),
    "sweep_key_twice_nested": (sweep_case(sub(SWEEP, "{param: inlet.T, unit: degC}",
                                              "{param: inlet.T, param: nozzle.mdot, unit: degC}")),
                               ["line 4", "key 'param' given twice"]),
    "sweep_list_as_key": (sweep_case(SWEEP + "? [a, b]\n: 1\n"), ["a key must be a plain name"]),
    "sweep_not_yaml": (sweep_case(SWEEP + "notes: [1, 2\n"), ["not valid YAML"]),
    "sweep_top_level_list": (sweep_case("- sweep: x\n"), ["expected a mapping with keys", "got [{'sweep': 'x'}]"]),
    "sweep_scene_directory": (sweep_case(sub(SWEEP, f"scene: {SCENE}", "scene: .")), ["scene: '.': no such file"]),
    "sweep_scene_not_a_path": (sweep_case(sub(SWEEP, f"scene: {SCENE}", "scene: [a, b]")),
                               ["scene: expected a path", "['a', 'b']"]),
    "sweep_variable_driven_by_an_input": (
        sweep_case(sub(sub(SWEEP, f"scene: {SCENE}", f"scene: {DEMO}"), "param: inlet.T, unit: degC",
                       "param: feed.T, unit: K").replace("T: 50}", "T: 300}")),
        ["variables.T.param", "feed.T is driven by a time-dependent input", "inputs: feed.T"]),
    "sweep_variable_is_a_link_target": (sweep_case(sub(SWEEP, "param: inlet.T", "param: bed.T0")),
                                        ["points[0] (a).T", "follows inlet.T by a link"]),
    "sweep_t_end_zero": (sweep_case(SWEEP + "t_end: 0 min\n"), ["t_end: '0 min'", "an end time > 0"]),
    "sweep_point_shown_short": (sweep_case(sub(SWEEP, "  - {name: a, T: 50}", "  - " + str(list(range(20000))))),
                                ["points[0]", "got [0, 1, 2, 3, 4, 5, ...]"]),
    "sweep_cli_t_end_empty": (sweep_case(SWEEP, "--t-end", ""), ["--t-end = ''", "expected seconds"]),
    "sweep_cli_t_end_zero": (sweep_case(SWEEP, "--t-end", "0 s"), ["--t-end = '0 s'", "t_end > 0"]),
    "sweep_cli_set_bool_word": (sweep_case(SWEEP, "--set", "bed.X0=true"), ["bed.X0", "'true'"]),
    # experiment files and their CSV data
    "experiments_latin1": (experiment_case(EXPERIMENTS.encode() + b"description: caf\xe9\n"),
                           ["line 7, column 17", "byte 0xe9 is not UTF-8", "an experiment file"]),
    "experiments_nul_byte": (experiment_case(b"runs: \x00\n"), ["control byte 0x00", "an experiment file"]),
    "experiments_directory": (experiment_case("dir"), ["is a directory; expected an experiment file"]),
    "experiments_fifo": (experiment_case("fifo"), ["not a regular file"]),
    "experiments_alias_bomb": (experiment_case(EXPERIMENTS + alias_bomb().replace("notes", "description")),
                               ["more than 200000 values", "an experiment file"]),
    "experiments_python_tag": (experiment_case(EXPERIMENTS + "description: !!python/name:os.system x\n"),
                               ["line 7, column 14", "YAML tag '!!python/name:os.system'"]),
    "experiments_key_twice": (experiment_case(EXPERIMENTS + "sigma: {gas.T: {abs: 5 K}}\n"),
                              ["line 7, column 1", "key 'sigma' given twice"]),
    "experiments_deep_nesting": (experiment_case(EXPERIMENTS + "description: " + "{a: " * 200 + "1" + "}" * 200),
                                 ["nested deeper than 64 levels"]),
    "experiments_scene_directory": (experiment_case(sub(EXPERIMENTS, f"scene: {SCENE}", "scene: .")),
                                    ["scene = '.': a directory", "expected a scene file"]),
    "experiments_scene_missing": (experiment_case(sub(EXPERIMENTS, f"scene: {SCENE}", "scene: nowhere.yaml")),
                                  ["scene = 'nowhere.yaml': no such file"]),
    "experiments_scene_not_a_path": (experiment_case(sub(EXPERIMENTS, f"scene: {SCENE}", "scene: {a: 1}")),
                                     ["scene = {'a': 1}", "expected the path of a scene file"]),
    "experiments_column_not_a_name": (experiment_case(sub(EXPERIMENTS, "gas.T: [36.0, 35.0]", "1: [36.0, 35.0]")),
                                      ["run A.data: column name 1", "expected a state or output name"]),
    "experiments_long_value_shown_short": (
        experiment_case(sub(EXPERIMENTS, "gas.T: [36.0, 35.0]", "gas.T: '" + "9" * 5000 + "'")),
        ["run A.data.gas.T: expected a list of numbers", "..."]),
    "csv_latin1": (experiment_case(CSV_RUN, csv=b"t [min],gas.T [degC]\n5,36\n10,35 \xb0C\n"),
                   ["run A.data", "line 3, column 7", "byte 0xb0 is not UTF-8", "a CSV data file"]),
    "csv_nul_byte": (experiment_case(CSV_RUN, csv=CSV_OK.encode() + b"15,\x0034\n"),
                     ["line 4, column 4", "control byte 0x00"]),
    "csv_utf16": (experiment_case(CSV_RUN, csv=CSV_OK.encode("utf-16")), ["byte 0xff is not UTF-8"]),
    "csv_directory": (experiment_case(CSV_RUN, csv="dir"), ["is a directory; expected a CSV data file"]),
    "csv_fifo": (experiment_case(CSV_RUN, csv="fifo"), ["not a regular file"]),
    "csv_missing": (experiment_case(CSV_RUN, csv="missing"), ["No such file or directory", "a CSV data file"]),
    "csv_field_beyond_the_csv_limit": (experiment_case(CSV_RUN, csv=CSV_OK + "15," + "3" * 200000 + "\n"),
                                       ["not a CSV table", "field larger than field limit"]),
    "csv_random_bytes": (experiment_case(CSV_RUN, csv=RANDOM_BYTES), ["line 1, column", "a CSV data file"]),
    # stage files
    "stages_latin1": (stage_case(STAGES.encode() + b"description: caf\xe9\n"),
                      ["byte 0xe9 is not UTF-8", "a stage file"]),
    "stages_directory": (stage_case("dir"), ["is a directory; expected a stage file"]),
    "stages_python_tag": (stage_case(STAGES + "description: !!python/object:x {}\n"), ["YAML tag '!!python/object:x'"]),
    "stages_alias_bomb": (stage_case(STAGES + alias_bomb().replace("notes", "description")),
                          ["more than 200000 values", "a stage file"]),
    "stages_key_twice": (stage_case(sub(STAGES, "transform: log,", "transform: log, transform: none,")),
                         ["line 5", "key 'transform' given twice"]),
    "stages_option_bool_for_a_count": (stage_case(STAGES + "options: {num_threads: true}\n"),
                                       ["options: calibration option num_threads = True", "a whole number"]),
    "stages_option_count_for_a_flag": (stage_case(STAGES + "options: {profile: 3}\n"),
                                       ["calibration option profile = 3", "expected true or false"]),
    "stages_option_name_not_a_name": (stage_case(STAGES + "options: {1: 2}\n"),
                                      ["calibration option 1", "expected an option name"]),
    "stages_option_fraction_for_a_count": (stage_case(STAGES + "options: {max_iterations: 2.5}\n"),
                                           ["max_iterations = 2.5", "a whole number"]),
    "stages_option_word_for_a_method": (stage_case(STAGES + "options: {jacobian: [fd]}\n"),
                                        ["jacobian = ['fd']", "sensitivities or central_differences"]),
    # options of the command line
    "run_t_end_empty": (scene_case("run", "--t-end", ""), ["--t-end = ''", "expected seconds"]),
    "run_t_end_zero": (scene_case("run", "--t-end", "0"), ["--t-end = '0'", "t_end = 0 s violates t_end > 0"]),
    "run_t_end_negative": (scene_case("run", "--t-end", "-5 min"), ["--t-end = '-5 min'", "t_end = -300 s"]),
    "run_t_end_nan": (scene_case("run", "--t-end", "nan"), ["--t-end = 'nan'", "t_end > 0"]),
    "run_t_end_1e-300": (scene_case("run", "--t-end", "1e-300"), ["t_end = 1e-300 s", "t_end >= 1e-09 s"]),
    "run_t_end_word": (scene_case("run", "--t-end", "soon"), ["--t-end = 'soon'", "expected seconds"]),
    "run_out_unwritable": (lambda tmp_path: (["run", SCENE, "--out", UNWRITABLE], [SCENE], None),
                           ["--out = '/sys/granuflow-out'", "cannot write there", "Permission denied"]),
    "run_out_empty": (lambda tmp_path: (["run", SCENE, "--out", ""], [SCENE], None),
                      ["--out = ''", "expected a folder"]),
    "run_scene_is_a_directory": (scene_file_case("dir"), ["is a directory; expected a scene file"]),
    # the keys of a scene the core keeps as YAML for the Python side (plots, notes): an alias bomb there expanded
    # in the message about a bad plot entry
    "run_scene_plots_alias_bomb": (scene_file_case(sub(DEMO_TEXT, DEMO_TEXT[DEMO_TEXT.index("plots:"):],
                                                       "notes:\n" + "".join("  " + line + "\n" for line in
                                                                            alias_bomb().splitlines()[:-1])
                                                       + "plots: [*a8]\n")),
                                   ["more than 200000 values", "alias"]),  # the core's loader may find it first
    "run_scene_is_a_fifo": (scene_file_case("fifo"), ["not a regular file"]),
    "contour_axis_is_a_link_target": (scene_case("contour", "--x", "bed.T0:degC:50:70:3", "--y",
                                                 "nozzle.mdot:g/min:60:120:3"),
                                      ["--x: bed.T0 = 50 degC", "follows inlet.T by a link"]),
    "contour_axis_driven_by_an_input": (scene_case("contour", "--x", "feed.T:K:300:320:3", "--y", "tank1.Q:kW:1:3:3",
                                                   "--output", "tank1.T", scene=DEMO),
                                        ["--x: feed.T is driven by a time-dependent input", "inputs: feed.T"]),
    "contour_t_end_empty": (scene_case("contour", "--x", "inlet.T:degC:50:70:3", "--y", "nozzle.mdot:g/min:60:120:3",
                                       "--t-end", ""), ["--t-end = ''"]),
    "contour_t_end_zero": (scene_case("contour", "--x", "inlet.T:degC:50:70:3", "--y", "nozzle.mdot:g/min:60:120:3",
                                      "--t-end", "0 h"), ["--t-end = '0 h'", "t_end > 0"]),
    "contour_out_unwritable": (scene_case("contour", "--x", "inlet.T:degC:50:70:3", "--y",
                                          "nozzle.mdot:g/min:60:120:3", "--out", UNWRITABLE),
                               ["--out = '/sys/granuflow-out'", "cannot write there"]),
}


def run_main(capsys, argv):
    """granuflow's main() in this process: its return code and its stderr."""
    capsys.readouterr()
    code = gcli.main([str(a) for a in argv])
    return code, capsys.readouterr().err


def assert_one_line_exit_2(code, err, needles, named=None):
    assert code == 2, (code, err)
    assert "Traceback" not in err, err
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    assert lines[0].startswith("granuflow: bad input: "), lines[0]
    assert len(lines[0]) < 700, lines[0]  # capped: no expanded structure, no file content
    if named is not None:
        assert str(named) in lines[0], (named, lines[0])
    for n in needles:
        assert n in lines[0], (n, lines[0])


def _digest(path):
    path = str(path)
    if not os.path.exists(path):
        return "missing"
    return sha256(path) if os.path.isfile(path) else os.stat(path).st_mode


@pytest.mark.parametrize("case", sorted(CLI_CASES))
def test_bad_input_on_the_command_line_exits_2_with_one_line(tmp_path, capsys, case):
    if "unwritable" in case and not os.path.isdir("/sys/kernel"):
        pytest.skip("no sysfs to stand for an unwritable folder")
    setup, needles = CLI_CASES[case]
    argv, files, named = setup(tmp_path)
    if "--out" not in [str(a) for a in argv]:
        argv = [*argv, "--out", tmp_path / "out"]
    before = [_digest(f) for f in files]
    t0 = time.perf_counter()
    code, err = run_main(capsys, argv)
    assert time.perf_counter() - t0 < 30  # refused before any long run; never a hang
    assert_one_line_exit_2(code, err, needles, named)
    assert [_digest(f) for f in files] == before
    assert not (tmp_path / "out").exists()


# -- the Python API ------------------------------------------------------------------------------------------------
def _headline():
    return gf.load(SCENE)


def _demo():
    return gf.load(DEMO)


def _short_run():
    return _demo().simulate(t_end=60.0, n_out=4)


def _fifo(tmp_path):
    path = tmp_path / "scene.yaml"
    os.mkfifo(path)
    return path


def _python_file(tmp_path, name, content):
    return _write(tmp_path / name, content)


# id -> (call(tmp_path), exception type, words)
API_CASES = {
    "set_bool": (lambda p: _headline().set("bed.X0", True), gf.ConfigError,
                 ["parameter bed.X0 = True", "not a bool"]),
    "set_numpy_bool": (lambda p: _headline().set("bed.X0", np.bool_(False)), gf.ConfigError,
                       ["bed.X0 = False", "not a bool"]),
    "update_not_a_mapping": (lambda p: _headline().update([("bed.X0", 0.1)]), gf.ConfigError,
                             ["update([('bed.X0', 0.1)])", "expected a mapping"]),
    "simulate_empty_t_out": (lambda p: _demo().simulate(t_out=[]), gf.ConfigError,
                             ["simulate(): t_out = []", "non-empty list"]),
    "simulate_t_out_text": (lambda p: _demo().simulate(t_out="0, 10"), gf.ConfigError,
                            ["simulate(): t_out = '0, 10'", "a list of times"]),
    "simulate_t_out_nan": (lambda p: _demo().simulate(t_out=[0.0, math.nan]), gf.ConfigError,
                           ["simulate(): t_out[1] = nan", "a finite number"]),
    "simulate_n_out_bool": (lambda p: _demo().simulate(n_out=True), gf.ConfigError,
                            ["simulate(): n_out = True", "a whole number"]),
    "simulate_n_out_fraction": (lambda p: _demo().simulate(n_out=2.5), gf.ConfigError,
                                ["simulate(): n_out = 2.5", "a whole number"]),
    "simulate_rtol_text": (lambda p: _demo().simulate(rtol="1e-6"), gf.ConfigError,
                           ["simulate(): rtol = '1e-6'", "a finite number"]),
    "simulate_t_end_word": (lambda p: _demo().simulate(t_end="soon"), gf.ConfigError,
                            ["simulate(): t_end = 'soon'", "a time unit"]),
    "simulate_t_end_zero": (lambda p: _demo().simulate(t_end=0), gf.ConfigError,
                            ["simulate(): t_end = 0 s", "t_end > 0"]),
    "simulate_sensitivities_text": (lambda p: _demo().simulate(sensitivities="feed.mdot"), gf.ConfigError,
                                    ["sensitivities = 'feed.mdot'", "a list of parameter names"]),
    "psd_nan": (lambda p: _headline().simulate(t_end=60.0, n_out=3).psd(math.nan), gf.ConfigError,
                ["psd: t = nan", "within the run, 0 to 60 s"]),
    "psd_after_the_end": (lambda p: _headline().simulate(t_end=60.0, n_out=3).psd(3600.0), gf.ConfigError,
                          ["psd: t = 3600 s", "outside the run, 0 to 60 s"]),
    "psd_text": (lambda p: _headline().simulate(t_end=60.0, n_out=3).psd("5 min"), gf.ConfigError,
                 ["psd: t = '5 min'", "a time in s"]),
    "set_t_end_empty": (lambda p: _demo().set_t_end(""), gf.ConfigError, ["set_t_end(): t_end = ''"]),
    "set_t_end_negative": (lambda p: _demo().set_t_end("-1 h"), gf.ConfigError,
                           ["set_t_end(): t_end = -3600 s", "t_end > 0"]),
    "set_input_times_text": (lambda p: _demo().set_input("feed.T", ["0 s", "10 s"], [300, 310]), gf.ConfigError,
                             ["set_input('feed.T'): times[0] = '0 s'", "a finite number (s)"]),
    "output_sensitivities_after_the_end": (
        lambda p: _demo().output_sensitivities(["feed.mdot"], t_end=10.0, times=[20.0]), gf.ConfigError,
        ["output_sensitivities(): times[0] = 20 s", "t_end = 10 s"]),
    "load_directory": (lambda p: gf.load(p), gf.ConfigError, ["is a directory; expected a scene file"]),
    "load_fifo": (lambda p: gf.load(_fifo(p)), gf.ConfigError, ["scene.yaml: not a regular file"]),
    "load_missing": (lambda p: gf.load(p / "nowhere.yaml"), gf.ConfigError,
                     ["nowhere.yaml: No such file or directory"]),
    "load_not_a_path": (lambda p: gf.load(42), gf.ConfigError, ["load(42)", "the path of a scene file"]),
    "load_text_not_text": (lambda p: gf.load_text(["scene: x"], "list.yaml"), gf.ConfigError,
                           ["list.yaml", "given as text (str), got list"]),
    "steady_state_at_nan": (lambda p: _demo().steady_state(t=float("nan")), gf.ConfigError,
                            ["steady_state(): t = nan s", "t >= 0, finite"]),
    "steady_state_before_the_start": (lambda p: _demo().steady_state(t=-1.0), gf.ConfigError,
                                      ["steady_state(): t = -1 s"]),
    "steady_state_there_is_none": (lambda p: gf.load_text(HEATED_TANK, "tank.yaml").steady_state(), gf.SolverError,
                                   ["has no steady state", "tank (T)", "constant rate"]),
    "axis_is_a_link_target": (lambda p: ds.make_axis(_headline(), ("bed.T0", "degC", 50, 70, 3), "x"),
                              gf.ConfigError, ["x: bed.T0 = 50 degC", "follows inlet.T by a link"]),
    "axis_driven_by_an_input": (lambda p: ds.make_axis(_demo(), ("feed.T", "K", 300, 320, 3), "y"), gf.ConfigError,
                                ["y: feed.T is driven by a time-dependent input"]),
    "contour_map_over_a_link_target": (
        lambda p: ds.contour_map(_headline(), ("bed.T0", "degC", 50, 70, 3), ("nozzle.mdot", "g/min", 60, 90, 2)),
        gf.ConfigError, ["x: bed.T0", "follows inlet.T by a link"]),
    "load_sweep_latin1": (lambda p: sweep.load_sweep(_python_file(p, "s.yaml", b"sweep: caf\xe9\n")), gf.ConfigError,
                          ["s.yaml: line 1, column 11", "byte 0xe9 is not UTF-8"]),
    "load_experiments_directory": (lambda p: cal.load_experiments(p), gf.ConfigError,
                                   ["is a directory; expected an experiment file"]),
    "load_stages_tag": (lambda p: cal.load_stages(_python_file(p, "st.yaml", "name: !!set {a: null}\n"), _headline()),
                        gf.ConfigError, ["st.yaml: line 1, column 7", "YAML tag '!!set'"]),
    "check_yaml_alias_bomb_is_quick": (lambda p: textfile.check_yaml(alias_bomb(12), "b.yaml", "sweep file"),
                                       gf.ConfigError, ["b.yaml", "more than 200000 values"]),
}


@pytest.mark.parametrize("case", sorted(API_CASES))
def test_bad_input_to_the_python_api_raises_one_line(tmp_path, case):
    call, kind, needles = API_CASES[case]
    before = [sha256(SCENE), sha256(DEMO)]
    t0 = time.perf_counter()
    with pytest.raises(kind) as info:
        call(tmp_path)
    assert time.perf_counter() - t0 < 30
    if kind is gf.ConfigError:
        assert isinstance(info.value, ValueError)  # what a caller catches for bad input
    m = str(info.value)
    assert "\n" not in m.strip(), m
    assert len(m) < 700, m
    for n in needles:
        assert n in m, (n, m)
    assert [sha256(SCENE), sha256(DEMO)] == before


def test_the_table_holds_at_least_sixty_cases():
    assert len(CLI_CASES) + len(API_CASES) >= 60


# -- what the refusals stand in for: the valid neighbours work -------------------------------------------------
def test_valid_neighbours_of_the_refused_inputs(tmp_path):
    fs = _headline()
    fs.set("bed.X0", 0.04)  # a number, not True
    r = fs.simulate(t_end="1 min", t_out=[0.0, 30.0, 60.0])  # a time with a unit is an end time
    assert list(r.t) == [0.0, 30.0, 60.0]
    assert r.psd(30.0).attrs["t_s"] == 30.0
    fs.set_t_end("2 min")
    assert fs.t_end == 120.0
    # the same bytes a tool writes with a byte-order mark are read
    path = _write(tmp_path / "s.yaml", b"\xef\xbb\xbf" + SWEEP.encode())
    assert sweep.load_sweep(path).name == "small"
    # a key repeated in different mappings is not repeated
    textfile.check_yaml("a: {x: 1}\nb: {x: 2}\n", "ok.yaml", "sweep file")


def test_a_contour_with_one_point_on_an_axis_draws_a_profile(tmp_path, capsys):
    out = tmp_path / "out"
    code = gcli.main(["contour", SCENE, "--x", "inlet.T:degC:50:50:1", "--y", "nozzle.mdot:g/min:60:120:3",
                      "--constraint", "d50_um>=300", "--out", str(out), "--no-progress", "--workers", "1"])
    err = capsys.readouterr().err
    assert code == 0, err
    assert "Traceback" not in err
    for f in ("contour.csv", "contour.json", "contour_d50_um.png", "feasible_window.png"):
        assert (out / f).stat().st_size > 0, f


@pytest.mark.parametrize("case", ["sweep_alias_bomb", "experiments_deep_nesting", "csv_latin1", "run_t_end_empty"])
def test_the_launcher_exits_2_without_a_traceback(tmp_path, case):
    setup, needles = CLI_CASES[case]
    argv, files, named = setup(tmp_path)
    before = [_digest(f) for f in files]
    p = cli(*argv, "--out", tmp_path / "out", timeout=60)
    assert_one_line_exit_2(p.returncode, p.stderr, needles, named)
    assert p.stdout == ""
    assert [_digest(f) for f in files] == before
