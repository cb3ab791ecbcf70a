"""Bad input to `granuflow run`: exit 2 and one line naming the file, the key, the value and what is allowed;
never a silent fallback, and the scene file is left alone. Each case is a copy of the headline scene with one
edit (or a --set on the command line)."""
import pytest
from conftest import SCENE, assert_bad_input, cli, run_bad_scene, scene_with, sha256


BAD_SCENES = {
    # was exit 0 with 101 rows
    "empty output times": ("output: {n: 121}", "output: {times: []}",
                           ["output.times", "[]", "non-empty list of times in [0, t_end]"]),
    "output n and times": ("output: {n: 121}", "output: {n: 121, times: [0 s, 60 min]}",
                           ["output", "either n or times"]),
    # the unit instance and the scene key, %g numbers
    "spray stops before it starts": ("t_on: 0 s, t_off: 60 min", "t_on: 30 min, t_off: 10 min",
                                     ["units.nozzle.params.t_off", "600 s", "t_off >= t_on (1800 s)"]),
    "negative smallest size": ("d_min: 50e-6", "d_min: -50e-6",
                               ["particles.settings.d_min", "-5e-05", "1e-07 <= d_min <= 0.01"]),
    # the scene key, not SimOptions.t_end
    "zero end time": ("t_end: 60 min", "t_end: 0 min", ["t_end = 0 s", "t_end > 0"]),
    "output time past the end": ("output: {n: 121}", "output: {times: [0 s, 30 min, 90 min]}",
                                 ["output.times[2] = 5400 s", "0 <= t_out <= t_end (3600 s)"]),
    "output times not increasing": ("output: {n: 121}", "output: {times: [0 s, 30 min, 20 min]}",
                                    ["output.times[2] = 1200 s", "increasing (previous 1800 s)"]),
    "relative tolerance above 1": ("rtol: 1e-6", "rtol: 2", ["solver.rtol = 2", "0 < rtol < 1"]),
    "one output row": ("output: {n: 121}", "output: {n: 1}", ["output.n = 1", "n_out >= 2"]),
    # a value for a parameter that follows another would be overwritten at the start of the run
    "link target given as a parameter": ("params: {bed_mass: 15 kg,", "params: {T0: 300 K, bed_mass: 15 kg,",
                                         ["links.bed.T0", "units.bed.params.T0", "follows inlet.T"]),
    "link target given an input": ("links:", "inputs: {bed.T0: {times: [0 s, 10 s], values: [300 K, 310 K]}}\nlinks:",
                                   ["links.bed.T0", "inputs.bed.T0", "follows inlet.T"]),
    "link to a link target": ("  gas.Y0: inlet.Y\n", "  gas.Y0: inlet.Y\n  nozzle.w: gas.Y0\n",
                              ["links.nozzle.w", "gas.Y0 itself follows inlet.Y", "link nozzle.w to inlet.Y"]),
}


@pytest.mark.parametrize("case", list(BAD_SCENES))
def test_bad_scene_exits_2_with_one_line(tmp_path, case):
    old, new, needles = BAD_SCENES[case]
    run_bad_scene(tmp_path, scene_with(tmp_path, old, new), *needles)


@pytest.mark.parametrize("args,needles", [
    # bed.T0 follows inlet.T (links: bed.T0: inlet.T): the override was silently dropped
    (["--set", "bed.T0=300"], ["bed.T0 = 300 K", "follows inlet.T by a link", "links: bed.T0: inlet.T",
                               "set inlet.T instead, or remove the link"]),
    (["--set", "gas.Y0=0.01"], ["gas.Y0 = 0.01", "follows inlet.Y by a link", "set inlet.Y instead"]),
    # a cross-parameter check names the unit instance, not its type
    (["--set", "nozzle.t_on=30 min", "--set", "nozzle.t_off=10 min"],
     ["nozzle.t_off = 600 s", "t_off >= t_on (1800 s)"]),
])
def test_bad_set_exits_2_and_leaves_the_scene_alone(tmp_path, args, needles):
    before = sha256(SCENE)
    p = cli("run", SCENE, "--out", tmp_path / "out", *args)
    assert_bad_input(p, *needles)
    assert "spray_nozzle.t_off" not in p.stderr
    assert sha256(SCENE) == before
    assert not (tmp_path / "out" / "summary.json").exists()


def test_setting_a_link_target_to_the_value_it_follows_is_accepted():
    import granuflow as gf

    fs = gf.load(SCENE)
    assert fs.get("bed.T0") == fs.get("inlet.T")  # a link target reports the value it takes in a run
    fs.set("inlet.T", "70 degC")
    assert fs.get("bed.T0") == pytest.approx(343.15)
    fs.update({p: fs.get(p) for p in fs.params})  # a copy of every value can be set back (worker processes)
    with pytest.raises(gf.ConfigError, match=r"bed\.T0 = 300 K: cannot be set, it follows inlet\.T"):
        fs.set("bed.T0", 300.0)
