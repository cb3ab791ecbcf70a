"""A table of bad inputs (issue 12): scene files (content, encoding, shape, size), what stands where a scene file
should (directories, fifos, devices), --set on the command line, and the Python and core entry points that take
scenes, parameters, inputs, run options and experiments. Each case asserts the exit code 2 (or ConfigError, a
ValueError), one line, the names the message must contain, and that no input file changed.

The command-line cases call granuflow's main() in this process (the same code as the launcher, without starting
Python 100 times); a few run the real launcher to pin the process exit code and the absence of tracebacks.
"""
import math
import os
import random
import stat

import pytest

from conftest import DEMO, ROOT, SCENE, cli, sha256

import granuflow as gf
from granuflow import _calibration, _core
from granuflow import cli as gcli

with open(SCENE) as _f:
    HEADLINE = _f.read()
with open(DEMO) as _f:
    DEMO_TEXT = _f.read()

TANKS = """scene: tanks
t_end: 100 s
output: {n: 11}
units:
  feed: {type: liquid_feed, params: {mdot: 0.5 kg/s}}
  tank: {type: stirred_tank, params: {mass: 10 kg}}
  product: {type: liquid_product}
connections: [feed.out -> tank.in, tank.out -> product.in]
"""

LOOP = """scene: loop
t_end: 100 s
units:
  feed: {type: liquid_feed, params: {mdot: 0.5 kg/s}}
  mixer: {type: liquid_mixer}
  splitter: {type: liquid_splitter, params: {split: 0.6}}
  product: {type: liquid_product}
connections:
  - feed.out -> mixer.in1
  - mixer.out -> splitter.in
  - splitter.out1 -> product.in
  - splitter.out2 -> mixer.in2
"""


def sub(text, old, new):
    assert old in text, old
    return text.replace(old, new, 1)


def tanks(old, new):
    return sub(TANKS, old, new)


def headline(old, new):
    return sub(HEADLINE, old, new)


def alias_bomb(levels=9):
    lines = ["a0: &a0 [1,1,1,1,1,1,1,1,1,1]"]
    for k in range(1, levels):
        lines.append(f"a{k}: &a{k} [" + ",".join([f"*a{k - 1}"] * 10) + "]")
    return TANKS + "\n".join(lines) + f"\nplots: [*a{levels - 1}]\n"


def deep_block(levels):
    return TANKS + "notes:\n" + "".join("  " * (k + 1) + "- \n" for k in range(levels - 1)) + \
        "  " * levels + "- x\n"


RANDOM_BYTES = bytes(random.Random(12).randrange(256) for _ in range(4000))

# id -> (file content, words the message must contain). The file's path is always required too.
SCENE_FILES = {
    # size, shape and YAML features a scene never needs
    "alias_bomb": (alias_bomb(), ["line 14", "more than 200000 values", "alias"]),
    "alias_cycle": (TANKS + "plots: &p [1, *p]\n", ["cycle"]),
    "alias_to_missing_anchor": (TANKS + "plots: [*nothing]\n", ["not valid YAML"]),
    "deep_flow_nesting": (TANKS + "plots: " + "[" * 3000 + "]" * 3000 + "\n", ["deeper than 64 levels"]),
    "deep_block_nesting": (deep_block(80), ["deeper than 64 levels"]),
    "python_tag": (TANKS + "notes: !!python/object/apply:os.system [ls]\n",
                   ["YAML tag '!!python/object/apply:os.system' is not allowed"]),
    "custom_tag": (TANKS + "notes: !include other.yaml\n", ["YAML tag '!include'"]),
    "set_tag_on_mapping": (TANKS + "plots: !!set {a: null}\n", ["YAML tag '!!set'"]),
    "binary_tag": (TANKS + "notes: !!binary aGVsbG8=\n", ["YAML tag '!!binary'"]),
    "two_documents": (TANKS + "---\nscene: b\n", ["more than one YAML document"]),
    "file_over_1_mib": ("# " + "x" * (1 << 20) + "\n" + TANKS, ["bytes; a scene file is at most 1048576 bytes"]),
    "output_n_1e9": (tanks("output: {n: 11}", "output: {n: 1000000000}"), ["output.n = 1000000000", "n_out <= 100000"]),
    "output_n_100001": (tanks("output: {n: 11}", "output: {n: 100001}"), ["output.n = 100001", "n_out <= 100000"]),
    "output_times_too_many": (
        tanks("output: {n: 11}", "output: {times: [" + ",".join(f"{k * 1e-3:.4f}" for k in range(100001)) + "]}"),
        ["output.times", "at most 100000 times"]),
    # encoding
    "nul_byte": (b"scene: tanks\x00\n", ["line 1, column 13", "control byte 0x00", "not a text file"]),
    "escape_byte": (TANKS.encode() + b"notes: \x1b[31mred\n", ["line 9, column 8", "control byte 0x1b"]),
    "latin1_byte": ("scene: caf\xe9\n".encode("latin-1"), ["line 1, column 11", "byte 0xe9 is not UTF-8"]),
    "utf16_with_bom": (TANKS.encode("utf-16"), ["not a text file"]),
    "truncated_utf8_at_end": (TANKS.encode() + b"notes: \xe2\x82", ["line 9, column 8", "byte 0xe2 is not UTF-8"]),
    "overlong_utf8": (TANKS.encode() + b"notes: \xc0\xaf\n", ["byte 0xc0 is not UTF-8"]),
    "utf8_surrogate": (TANKS.encode() + b"notes: \xed\xa0\x80\n", ["byte 0xed is not UTF-8"]),
    "beyond_unicode": (TANKS.encode() + b"notes: \xf4\x90\x80\x80\n", ["byte 0xf4 is not UTF-8"]),
    "random_bytes": (RANDOM_BYTES, ["line 1"]),
    # top-level shape and keys
    "empty_file": ("", ["the file must be a mapping of scene keys, got empty"]),
    "only_a_comment": ("# nothing here\n", ["the file must be a mapping of scene keys"]),
    "top_level_list": ("- scene: tanks\n", ["the file must be a mapping of scene keys, got a list"]),
    "top_level_scalar": ("just words\n", ["the file must be a mapping of scene keys, got 'just words'"]),
    "list_as_key": (TANKS + "[a, b]: 1\n", ["a key must be a plain name, got a list"]),
    "mapping_as_key_in_units": (tanks("  product: {type: liquid_product}", "  {x: 1}: {type: liquid_product}"),
                                ["units", "a key must be a plain name, got a mapping"]),
    "empty_key": (TANKS + '"": 1\n', ["a key must be a plain name, got an empty key"]),
    "unknown_top_key": (TANKS + "solvr: {rtol: 1e-6}\n", ["solvr: unknown key", "solver"]),
    "top_key_twice": (TANKS + "t_end: 50 s\n", ["t_end: given twice"]),
    "missing_scene_name": (sub(TANKS, "scene: tanks\n", ""), ["scene: missing required key"]),
    "missing_units": ("scene: x\nt_end: 1 s\n", ["units: missing required key"]),
    "units_empty": (sub(TANKS, TANKS[TANKS.index("units:"):TANKS.index("connections")], "units: {}\n"),
                    ["units: expected a non-empty mapping"]),
    # values of the run
    "t_end_zero": (tanks("t_end: 100 s", "t_end: 0 s"), ["t_end = 0 s", "t_end > 0"]),
    "t_end_negative": (tanks("t_end: 100 s", "t_end: -5 min"), ["t_end = -300 s", "t_end > 0"]),
    "t_end_word": (tanks("t_end: 100 s", "t_end: soon"), ["t_end", "'soon' is not a number"]),
    "t_end_mass_unit": (tanks("t_end: 100 s", "t_end: 5 kg"), ["t_end", "unit 'kg' is kg, but the value must be in s"]),
    "t_end_list": (tanks("t_end: 100 s", "t_end: [1, 2]"), ["t_end", "expected a single value, got a list"]),
    "t_end_nan": (tanks("t_end: 100 s", "t_end: .nan"), ["t_end", "'.nan' is not a number"]),
    "t_end_inf": (tanks("t_end: 100 s", "t_end: 1e999 s"), ["t_end", "'1e999 s' is not a number"]),
    "output_n_fraction": (tanks("output: {n: 11}", "output: {n: 2.5}"), ["output.n", "'2.5' is not a whole number"]),
    "output_n_one": (tanks("output: {n: 11}", "output: {n: 1}"), ["output.n = 1", "n_out >= 2"]),
    "output_times_empty": (tanks("output: {n: 11}", "output: {times: []}"), ["output.times", "non-empty list"]),
    "output_n_and_times": (tanks("output: {n: 11}", "output: {n: 3, times: [0 s]}"), ["give either n or times"]),
    "output_time_after_end": (tanks("output: {n: 11}", "output: {times: [0 s, 200 s]}"),
                              ["output.times[1] = 200 s", "t_out <= t_end"]),
    "output_times_decreasing": (tanks("output: {n: 11}", "output: {times: [50 s, 10 s]}"),
                                ["output.times[1] = 10 s", "increasing"]),
    "rtol_above_one": (TANKS + "solver: {rtol: 2}\n", ["solver.rtol = 2", "0 < rtol < 1"]),
    "atol_zero": (TANKS + "solver: {atol: 0}\n", ["solver.atol = 0", "atol > 0"]),
    "max_steps_zero": (TANKS + "solver: {max_steps: 0}\n", ["solver.max_steps = 0", "max_steps >= 1"]),
    "unknown_linear_solver": (TANKS + "solver: {linear_solver: magic}\n", ["solver.linear_solver = 'magic'", "auto"]),
    "unknown_solver_key": (TANKS + "solver: {rtoll: 1e-6}\n", ["solver.rtoll: unknown key", "rtol"]),
    # units, settings, parameters
    "unknown_unit_type": (tanks("type: stirred_tank", "type: stirred_tnak"), ["units.tank.type", "stirred_tnak"]),
    "unit_without_type": (tanks("{type: liquid_product}", "{params: {}}"), ["units.product.type: missing required"]),
    "unit_name_with_dot": (tanks("  product: {", "  prod.uct: {"), ["prod.uct", "contain no '.'"]),
    "unknown_setting": (tanks("{type: liquid_product}", "{type: liquid_product, settings: {size: 3}}"),
                        ["units.product.settings.size: unknown setting"]),
    "classes_too_many": (headline("settings: {classes: 10, d_min", "settings: {classes: 100000, d_min"),
                         ["particles.settings.classes = 100000", "<= 200"]),
    "setting_is_a_list": (tanks("{type: liquid_product}", "{type: liquid_product, settings: {a: [1]}}"),
                          ["units.product.settings.a", "expected a single value, got a list"]),
    "unknown_parameter": (tanks("{mass: 10 kg}", "{mass: 10 kg, volume: 1 m3}"),
                          ["units.tank.params.volume", "unknown parameter 'tank.volume'", "mass"]),
    "parameter_below_bound": (tanks("{mass: 10 kg}", "{mass: -1 kg}"), ["tank.mass = -1 kg", "mass <="]),
    "parameter_wrong_unit": (tanks("{mass: 10 kg}", "{mass: 10 m}"), ["units.tank.params.mass", "unit 'm' is m"]),
    "parameter_unknown_unit": (tanks("{mass: 10 kg}", "{mass: 10 stone}"), ["unknown unit 'stone'", "kg, g"]),
    "parameter_not_a_number": (tanks("{mass: 10 kg}", "{mass: heavy}"), ["units.tank.params.mass = 'heavy'"]),
    "parameter_long_text": (tanks("{mass: 10 kg}", "{mass: " + "9" * 5000 + "x}"), ["units.tank.params.mass", "..."]),
    "parameter_multiline": (tanks("{mass: 10 kg}", '{mass: "10\\nkg"}'),
                            ["units.tank.params.mass", "unknown unit '\\nkg'"]),
    "parameter_twice": (tanks("{mass: 10 kg}", "{mass: 10 kg, mass: 20 kg}"), ["units.tank.params.mass: given twice"]),
    "nozzle_off_before_on": (headline("t_on: 0 s, t_off: 60 min", "t_on: 30 min, t_off: 10 min"),
                             ["units.nozzle.params.t_off = 600 s", "t_off >= t_on"]),
    # inputs
    "param_and_input": (sub(DEMO_TEXT, "{mdot: 0.5 kg/s, w: 0.1}", "{mdot: 0.5 kg/s, w: 0.1, T: 300 K}"),
                        ["inputs.feed.T", "units.feed.params.T", "remove one of them"]),
    "input_times_not_increasing": (TANKS + "inputs: {feed.T: {times: [10 s, 5 s], values: [300 K, 310 K]}}\n",
                                   ["inputs.feed.T.times[1] = 5 s", "strictly increasing"]),
    "input_sizes_differ": (TANKS + "inputs: {feed.T: {times: [0 s, 5 s], values: [300 K]}}\n",
                           ["inputs.feed.T", "2 times, 1 values"]),
    "input_interp_unknown": (TANKS + "inputs: {feed.T: {times: [0 s], values: [300 K], interp: cubic}}\n",
                             ["inputs.feed.T.interp", "'cubic'", "linear, step"]),
    "input_unknown_parameter": (TANKS + "inputs: {feed.Tx: {times: [0 s], values: [300 K]}}\n",
                                ["inputs.feed.Tx", "unknown parameter"]),
    "input_value_out_of_bounds": (TANKS + "inputs: {feed.T: {times: [0 s, 5 s], values: [300 K, 900 K]}}\n",
                                  ["input feed.T.values[1] = 900 K", "200 <= T <= 700"]),
    "input_not_a_mapping": (TANKS + "inputs: {feed.T: [300 K]}\n", ["inputs.feed.T", "expected a mapping"]),
    "input_on_link_target": (headline("links:", "inputs: {bed.T0: {times: [0 s], values: [300 K]}}\nlinks:"),
                             ["links.bed.T0", "inputs.bed.T0", "remove one of them"]),
    "input_ramps_into_saturation": (
        headline("T: 60 degC, Y: 5 g/kg", "Y: 5 g/kg").replace(
            "links:", "inputs: {inlet.T: {times: [0 s, 20 min], values: [60 degC, -15 degC]}}\nlinks:", 1),
        ["units.inlet.params.Y = 0.005 kg/kg", "saturation humidity", "at t = 1200 s of the inputs inlet.T"]),
    # links
    "link_unknown_source": (headline("bed.T0: inlet.T", "bed.T0: inlet.Tx"), ["links.bed.T0", "inlet.Tx"]),
    "link_units_differ": (headline("gas.Y0: inlet.Y", "gas.Y0: inlet.T"), ["links.gas.Y0", "units differ"]),
    "link_target_also_given": (headline("bed_mass: 15 kg,", "bed_mass: 15 kg, T0: 300 K,"),
                               ["links.bed.T0", "units.bed.params.T0", "set inlet.T instead"]),
    "link_to_itself": (headline("gas.Y0: inlet.Y", "gas.Y0: gas.Y0"), ["links.gas.Y0", "cannot follow itself"]),
    "link_source_above_follower_bound": (headline("T: 60 degC, Y", "T: 550 K, Y"),
                                         ["links.bed.T0", "inlet.T = 550 K",
                                          "bed.T0 in [250, 500] follows it by a link"]),
    # connections and summary
    "connection_without_arrow": (tanks("tank.out -> product.in", "tank.out => product.in"),
                                 ["connections[1]", "expected \"unit.port -> unit.port\""]),
    "connection_unknown_port": (tanks("tank.out -> product.in", "tank.exit -> product.in"),
                                ["connections[1]", "no port 'exit'", "out"]),
    "port_connected_twice": (tanks("tank.out -> product.in]", "tank.out -> product.in, feed.out -> product.in]"),
                             ["connections[2]", "connected twice"]),
    "port_not_connected": (tanks(", tank.out -> product.in", ""), ["port tank.out", "is not connected"]),
    "connections_not_a_list": (tanks("connections: [feed.out -> tank.in, tank.out -> product.in]",
                                     "connections: {a: b}"), ["connections: expected a list"]),
    "summary_unknown_state": (TANKS + "summary: {T_K: tank.Temperature}\n",
                              ["summary.T_K", "'tank.Temperature' is neither a state nor a reported output"]),
    # the model's domain
    "inlet_air_supersaturated": (headline("T: 60 degC, Y: 5 g/kg", "T: 250 K, Y: 5 g/kg"),
                                 ["units.inlet.params.Y = 0.005 kg/kg", "saturation humidity", "at T = 250 K"]),
}

TOTAL_RECYCLE = sub(LOOP, "split: 0.6", "split: 0.0")

# Scenes that load but cannot run: refused before integration, still exit 2.
RUN_REFUSALS = {
    "total_recycle_without_holdup": (TOTAL_RECYCLE, ["flowsheet 'loop'", "mixer.mdot", "splitter.mdot2",
                                                     "units mixer, splitter", "hold-up"]),
    "recycle_singular_at_the_start": (sub(LOOP, "t_end: 100 s", "t_end: 100 s\nsolver: {linear_solver: sparse}"),
                                      ["flowsheet 'loop'", "mixer.T", "at the initial state",
                                       "linear_solver: dense"]),
}


def write(tmp_path, name, content):
    path = tmp_path / name
    if isinstance(content, bytes):
        path.write_bytes(content)
    else:
        path.write_text(content)
    return path


def run_main(capsys, *args):
    """granuflow's main() in this process: its return code and its stderr."""
    capsys.readouterr()
    code = gcli.main([str(a) for a in args])
    return code, capsys.readouterr().err


def assert_one_line_exit_2(code, err, *needles, path=None):
    assert code == 2, (code, err)
    assert "Traceback" not in err, err
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    assert lines[0].startswith("granuflow: bad input: "), lines[0]
    if path is not None:
        assert str(path) in lines[0], (path, lines[0])
    for n in needles:
        assert n in lines[0], (n, lines[0])


@pytest.mark.parametrize("case", sorted({**SCENE_FILES, **RUN_REFUSALS}))
def test_bad_scene_file_exits_2(tmp_path, capsys, case):
    content, needles = {**SCENE_FILES, **RUN_REFUSALS}[case]
    path = write(tmp_path, "scene.yaml", content)
    before = sha256(path)
    out = tmp_path / "out"
    code, err = run_main(capsys, "run", path, "--out", out)
    assert_one_line_exit_2(code, err, *needles, path=path)
    assert len(err) < 1500, err
    assert sha256(path) == before
    assert not (out / "summary.json").exists()


def test_table_holds_at_least_a_hundred_cases():
    n = len(SCENE_FILES) + len(RUN_REFUSALS) + len(NOT_A_FILE) + len(BAD_SETS) + len(API_CASES) + \
        len(EXPERIMENT_CASES)
    assert n >= 100, n


def _fifo(tmp_path):
    path = tmp_path / "scene_fifo.yaml"
    os.mkfifo(path)
    return path


def _dir(tmp_path):
    path = tmp_path / "scene_dir.yaml"
    path.mkdir()
    return path


def _symlink_to_dir(tmp_path):
    path = tmp_path / "link.yaml"
    path.symlink_to(_dir(tmp_path))
    return path


# What stands where a scene file should: (make path, words).
NOT_A_FILE = {
    "directory": (_dir, ["is a directory; expected a scene file"]),
    "symlink_to_directory": (_symlink_to_dir, ["is a directory"]),
    "fifo": (_fifo, ["not a regular file"]),
    "character_device": (lambda tmp_path: "/dev/zero", ["not a regular file"]),
    "missing": (lambda tmp_path: tmp_path / "nowhere.yaml", ["No such file or directory"]),
    "missing_folder": (lambda tmp_path: tmp_path / "no" / "scene.yaml", ["No such file or directory"]),
}


@pytest.mark.parametrize("case", sorted(NOT_A_FILE))
def test_not_a_scene_file_exits_2(tmp_path, capsys, case):
    make, needles = NOT_A_FILE[case]
    path = make(tmp_path)
    code, err = run_main(capsys, "run", path, "--out", tmp_path / "out")
    assert_one_line_exit_2(code, err, *needles, path=path)


def test_a_file_larger_than_its_stat_size_is_read_whole():
    """The scene is read into a buffer sized by stat(), grown while the file goes on: a file that grew since, or one of
    /proc (size 0), is read to its end (up to the limit). /proc/cpuinfo's second "processor" line lies past the first
    buffers, so naming it given twice shows the read went on; a reader that stopped at the stat size read nothing."""
    with open("/proc/cpuinfo") as f:
        if f.read().count("processor") < 2:
            pytest.skip("one CPU: /proc/cpuinfo has a single block")
    assert os.stat("/proc/cpuinfo").st_size == 0
    with pytest.raises(gf.ConfigError, match=r"^/proc/cpuinfo: processor: given twice$"):
        gf.load("/proc/cpuinfo")


# --set on the command line: (scene, arguments, words).
BAD_SETS = {
    "set_input_driven": (DEMO, ["--set", "feed.T=310 K"], ["feed.T = 310 K", "driven by the time-dependent input",
                                                           "inputs: feed.T"]),
    "set_above_follower_bound": (SCENE, ["--set", "inlet.T=550 K"],
                                 ["inlet.T = 550 K", "bed.T0 in [250, 500] follows it by a link"]),
    "set_supersaturated": (SCENE, ["--set", "inlet.T=250 K"], ["Y = 0.005 kg/kg", "saturation humidity"]),
    "set_link_target": (SCENE, ["--set", "bed.T0=300 K"], ["bed.T0 = 300 K", "follows inlet.T by a link"]),
    "set_unknown_parameter": (SCENE, ["--set", "inlet.Tx=300 K"], ["inlet.Tx", "unknown parameter"]),
    "set_word": (SCENE, ["--set", "inlet.T=warm"], ["inlet.T", "warm"]),
    "set_wrong_unit": (SCENE, ["--set", "inlet.T=5 kg"], ["unit 'kg' is kg, but the value must be in K"]),
    "set_negative_flow": (SCENE, ["--set", "inlet.V_dot=-1 m3/h"], ["inlet.V_dot", "0 <= V_dot"]),
}


@pytest.mark.parametrize("case", sorted(BAD_SETS))
def test_bad_set_exits_2(tmp_path, capsys, case):
    scene, args, needles = BAD_SETS[case]
    before = sha256(scene)
    out = tmp_path / "out"
    code, err = run_main(capsys, "run", scene, "--out", out, *args)
    assert_one_line_exit_2(code, err, *needles)
    assert sha256(scene) == before
    assert not (out / "summary.json").exists()


def _loop_simulate():
    gf.load_text(TOTAL_RECYCLE, "loop.yaml").simulate()


def _demo():
    return gf.load(DEMO)


def _headline():
    return gf.load(SCENE)


def _experiment(**kw):
    e = {"name": "E1", "settings": {"inlet.T": 330.0}, "t_end": 600.0,
         "observations": [{"name": "gas.T", "t": [0.0, 300.0], "value": [330.0, 320.0], "sigma_abs": 2.0}]}
    e.update(kw)
    return e


def _predict(*exps):
    fs = _headline()
    _calibration.predict(fs._scene, list(exps), {}, {})


def _obs(**kw):
    o = {"name": "gas.T", "t": [0.0, 300.0], "value": [330.0, 320.0], "sigma_abs": 2.0}
    o.update(kw)
    return _experiment(observations=[o])


# Python and core entry points: (call, words). Each must raise ConfigError (a ValueError) with one line.
API_CASES = {
    "load_text_lone_surrogate": (lambda: gf.load_text("scene: \udcff\n", "s.yaml"),
                                 ["s.yaml", "line 1, column 8", "is not UTF-8"]),
    "load_text_bytes_latin1": (lambda: _core.load_scene_text(b"scene: caf\xe9\n", "b.yaml"),
                               ["b.yaml", "0xe9 is not UTF-8"]),
    "load_text_not_text": (lambda: _core.load_scene_text(42, "n.yaml"), ["n.yaml", "given as text (str), got int"]),
    "load_text_alias_bomb": (lambda: gf.load_text(alias_bomb(), "bomb.yaml"), ["bomb.yaml", "alias"]),
    "load_directory": (lambda: gf.load(ROOT), ["is a directory"]),
    "set_bool": (lambda: _demo().set("tank1.T0", True), ["tank1.T0 = True", "not a bool"]),
    "set_nan": (lambda: _demo().set("tank1.T0", float("nan")), ["tank1.T0 = nan", "a finite value"]),
    "set_list": (lambda: _demo().set("tank1.T0", [300]), ["tank1.T0 = [300]", "expected a number"]),
    "set_none": (lambda: _demo().set("tank1.T0", None), ["tank1.T0 = None", "expected a number"]),
    "set_input_driven": (lambda: _demo().set("feed.T", 320.0), ["feed.T = 320 K", "driven by the time-dependent"]),
    "set_above_follower_bound": (lambda: _headline().set("inlet.T", 560.0),
                                 ["inlet.T = 560 K", "bed.T0 in [250, 500]"]),
    "set_input_out_of_bounds": (lambda: _demo().set_input("feed.T", [0, 10], [300, 900]),
                                ["input feed.T.values[1] = 900 K"]),
    "set_input_not_increasing": (lambda: _demo().set_input("feed.T", [10, 0], [300, 310]),
                                 ["input feed.T.times[1]", "strictly increasing"]),
    "set_input_link_start_out_of_range": (lambda: _headline().set_input("inlet.T", [0, 600], [560, 330]),
                                          ["input inlet.T at t = 0 s = 560 K", "bed.T0 in [250, 500]"]),
    "set_input_bad_interp": (lambda: _demo().set_input("feed.T", [0], [300], interp="cubic"), ["'cubic'"]),
    "simulate_n_out_1e9": (lambda: _demo().simulate(n_out=10**9), ["simulate(): n_out = 1000000000", "<= 100000"]),
    "simulate_too_many_times": (lambda: _demo().simulate(t_out=[k * 1e-3 for k in range(100001)]),
                                ["simulate(): t_out", "at most 100000 times"]),
    "simulate_empty_t_out": (lambda: _demo().simulate(t_out=[]), ["simulate(): t_out = []", "non-empty list"]),
    "simulate_zero_t_end": (lambda: _demo().simulate(t_end=0.0), ["simulate(): t_end = 0", "t_end > 0"]),
    "simulate_bad_rtol": (lambda: _demo().simulate(rtol=-1.0), ["simulate(): rtol = -1", "0 < rtol < 1"]),
    "simulate_total_recycle": (_loop_simulate, ["loop.yaml: flowsheet 'loop'", "mixer.mdot", "splitter.mdot2"]),
    "set_t_end_zero": (lambda: _demo().set_t_end(0.0), ["t_end = 0 s", "t_end > 0"]),
    # the same limits for the YAML files the Python layer reads (sweep, contour, calibration, experiments)
    "check_yaml_alias_bomb": (lambda: _core.check_yaml_text(alias_bomb(), "sweep.yaml", "sweep file"),
                              ["sweep.yaml: line 14", "a sweep file is far smaller (an alias bomb?)"]),
    "check_yaml_python_tag": (lambda: _core.check_yaml_text("a: !!python/name:os.system x\n", "exp.yaml"),
                              ["exp.yaml: line 1, column 4", "YAML tag '!!python/name:os.system'"]),
    "check_yaml_latin1_bytes": (lambda: _core.check_yaml_text(b"runs: [caf\xe9]\n", "stages.yaml", "stage file"),
                                ["stages.yaml: line 1, column 11", "a stage file is YAML text in UTF-8"]),
    "check_yaml_deep": (lambda: _core.check_yaml_text("a: " + "[" * 500 + "]" * 500, "c.yaml"),
                        ["c.yaml", "deeper than 64 levels"]),
}

# The calibration core's experiments (as the Python layer hands them over): (experiments, words).
EXPERIMENT_CASES = {
    "setting_link_target": ([_experiment(settings={"bed.T0": 300.0})], ["experiment 'E1'", "setting bed.T0",
                                                                        "follows inlet.T by a link"]),
    "setting_unknown": ([_experiment(settings={"inlet.Tx": 300.0})], ["experiment 'E1'", "inlet.Tx"]),
    "setting_out_of_bounds": ([_experiment(settings={"inlet.T": 560.0})], ["experiment 'E1': setting inlet.T = 560 K",
                                                                           "250 <= T <= 500"]),
    "setting_nan": ([_experiment(settings={"inlet.T": math.nan})], ["experiment 'E1': setting inlet.T = nan"]),
    "setting_bool": ([_experiment(settings={"inlet.T": True})], ["experiment 'E1'.settings.inlet.T = True",
                                                                 "a number"]),
    "setting_text": ([_experiment(settings={"inlet.T": "hot"})], ["experiment 'E1'.settings.inlet.T = 'hot'"]),
    "duplicate_names": ([_experiment(), _experiment()], ["experiment 'E1' is given twice"]),
    "missing_name": ([{"observations": []}], ["experiment: missing required key 'name'"]),
    "missing_observations": ([{"name": "E1"}], ["experiment 'E1': missing required key 'observations'"]),
    "observation_unknown": ([_obs(name="gas.Tx")], ["experiment 'E1': observation", "gas.Tx"]),
    "times_not_increasing": ([_obs(t=[300.0, 0.0])], ["experiment 'E1': observation gas.T.t[1]", "increasing"]),
    "times_negative": ([_obs(t=[-1.0, 0.0])], ["gas.T.t[0] = -1 s"]),
    "time_after_t_end": ([_obs(t=[0.0, 900.0])], ["gas.T.t[1] = 900 s", "t <= t_end"]),
    "sizes_differ": ([_obs(value=[330.0])], ["gas.T: 2 times but 1 values"]),
    "no_sigma": ([_obs(sigma_abs=0.0)], ["exactly one of sigma_abs > 0, sigma_rel > 0"]),
    "both_sigmas": ([_obs(sigma_rel=0.1)], ["exactly one of sigma_abs > 0, sigma_rel > 0"]),
    "value_inf": ([_obs(value=[330.0, math.inf])], ["gas.T.value[1]", "a finite number (NaN: not measured)"]),
    "t_end_negative": ([_experiment(t_end=-5.0)], ["experiment 'E1'.t_end = -5 s"]),
    "values_not_numbers": ([_obs(value="330")], ["observation gas.T.value = '330'", "a list of numbers"]),
    "unknown_key": ([_experiment(temperature=300.0)], ["experiment: unknown key 'temperature'"]),
}


def _one_line_config_error(call, needles):
    with pytest.raises(ValueError) as info:
        call()
    assert isinstance(info.value, _core.ConfigError), repr(info.value)
    m = str(info.value)
    assert "\n" not in m, m
    for n in needles:
        assert n in m, (n, m)


@pytest.mark.parametrize("case", sorted(API_CASES))
def test_python_entry_point_raises_config_error(case):
    call, needles = API_CASES[case]
    before = sha256(SCENE), sha256(DEMO)
    _one_line_config_error(call, needles)
    assert (sha256(SCENE), sha256(DEMO)) == before


@pytest.mark.parametrize("case", sorted(EXPERIMENT_CASES))
def test_bad_experiment_is_refused_before_any_run(case):
    exps, needles = EXPERIMENT_CASES[case]
    _one_line_config_error(lambda: _predict(*exps), needles)


def test_clear_input_is_the_explicit_way_to_replace_an_input():
    fs = gf.load_text(TANKS + "inputs: {feed.T: {times: [0 s, 10 s], values: [300 K, 350 K]}}\n", "t.yaml")
    with pytest.raises(ValueError, match="driven by the time-dependent input feed.T"):
        fs.set("feed.T", 320.0)
    fs._scene.clear_input("feed.T")
    fs.set("feed.T", 320.0)
    r = fs.simulate(t_end=10.0, n_out=3)
    assert r["feed.T"][-1] == pytest.approx(320.0)


def test_spec_reports_the_bounds_a_link_leaves():
    assert _headline().spec("inlet.T")["upper"] == 500.0


# The real launcher: the process exit code, nothing but one line on stderr, and no hang on the worst inputs.
@pytest.mark.parametrize("case", ["alias_bomb", "nul_byte", "deep_flow_nesting", "output_n_1e9", "python_tag"])
def test_launcher_exits_2_quickly(tmp_path, case):
    content, needles = SCENE_FILES[case]
    path = write(tmp_path, "scene.yaml", content)
    p = cli("run", path, "--out", tmp_path / "out", timeout=60)
    assert_one_line_exit_2(p.returncode, p.stderr, *needles, path=path)
    assert p.stdout == ""


def test_launcher_on_a_fifo_does_not_block(tmp_path):
    path = _fifo(tmp_path)
    p = cli("run", path, "--out", tmp_path / "out", timeout=60)
    assert_one_line_exit_2(p.returncode, p.stderr, "not a regular file", path=path)
    assert stat.S_ISFIFO(os.stat(path).st_mode)


REGRESSIONS = os.path.join(ROOT, "tests", "fuzz", "regressions", "scene")


@pytest.mark.parametrize("name", sorted(os.listdir(REGRESSIONS)))
def test_fuzz_regression_scene_exits_2(tmp_path, capsys, name):
    """Every saved scene finding of the fuzz target (tests/fuzz/README.md) is bad input on the command line."""
    path = os.path.join(REGRESSIONS, name)
    before = sha256(path)
    code, err = run_main(capsys, "run", path, "--out", tmp_path / "out")
    assert_one_line_exit_2(code, err, path=path)
    assert sha256(path) == before
