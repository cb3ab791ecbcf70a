"""Units of measure parsed by UDUNITS-2 (issue 33 §3): prefixes, products, quotients and powers compose, offsets
(degC) and dimensionless spellings work, a unit that is not understood or of the wrong dimension is refused with
one line naming it, and the parser (not thread-safe itself) gives the same answers from many threads."""
import os
import subprocess
import sys
import textwrap
from concurrent.futures import ThreadPoolExecutor

import pytest
from conftest import SCENE

import granuflow as gf
from granuflow import _core
from granuflow.quantity import to_si


@pytest.mark.parametrize("text, si, expected", [
    ("60 degC", "K", 333.15),
    ("700 m3/h", "m3/s", 700 / 3600),
    ("90 g/min", "kg/s", 90e-3 / 60),
    ("200 um", "m", 200e-6),
    ("3 mPa s", "Pa s", 3e-3),
    ("2 kJ/(kg K)", "J/(kg K)", 2000.0),
    ("1.5 J/kg K", "J/(kg K)", 1.5),        # the engineering reading, not J K / kg
    ("4 kg.m-3", "kg/m3", 4.0),             # products and powers in UDUNITS' own notation
    ("2 m^3/s", "m3/s", 2.0),
    ("36 kg/(h m2)", "kg/(m2 s)", 0.01),
    ("5 W/K", "W/K", 5.0),                  # a heat-loss coefficient: no list had to learn it
    ("12 kW/K", "W/K", 12e3),
    ("250 mbar", "Pa", 25e3),
    ("30 mL/min", "m3/s", 30e-6 / 60),
    ("5 %", "-", 0.05),
    ("3 wt%", "kg/kg", 0.03),
    ("8 g/kg", "kg/kg", 8e-3),
    ("2 ms", "s", 2e-3),
])
def test_composed_units_convert_to_si(text, si, expected):
    assert to_si(text, si, "x") == pytest.approx(expected, rel=1e-14)


@pytest.mark.parametrize("text, spaced, si", [("50um", "50 um", "m"), ("90g/min", "90 g/min", "kg/s"),
                                              ("1e-3m", "1e-3 m", "m"), ("60degC", "60 degC", "K"),
                                              ("-3.5e+2mbar", "-3.5e+2 mbar", "Pa"), (".5kg", ".5 kg", "kg")])
def test_a_unit_written_on_to_its_number_reads_as_with_a_space(text, spaced, si):
    # as the core reads scene files and --set (parse_quantity); before, Python's edge refused "50um"
    from granuflow.quantity import parse_time, split
    assert to_si(text, si, "x") == to_si(spaced, si, "x")
    assert parse_time("60min", "t_end") == 3600.0
    for bad in ("fv_koren", "", "abc 3"):
        with pytest.raises(gf.ConfigError, match="expected a number, optionally followed by a unit"):
            split(bad, "x")


def test_temperature_differences_drop_the_offset():
    from granuflow.quantity import difference_to_si
    assert difference_to_si("2 degC", "K", "sigma") == pytest.approx(2.0, rel=1e-14)


@pytest.mark.parametrize("unit, message", [
    ("blorp", "unknown unit 'blorp' (allowed: any unit of kg, e.g. kg, g)"),
    ("kg/blorp", "unknown unit 'kg/blorp'"),
    ("s since 2000-01-01", "unknown unit 's since 2000-01-01'"),   # a time origin is not a unit of a quantity
    ("lg(re 1 mW)", "unknown unit 'lg(re 1 mW)'"),                 # nor is a logarithmic unit
    ("\nkg", "unknown unit '\nkg'"),
    ("m", "unit 'm' is m, but the value must be in kg"),
    ("W/K", "unit 'W/K' is W/K, but the value must be in kg"),
])
def test_refusals_name_the_unit(unit, message):
    with pytest.raises(gf.ConfigError) as e:
        _core.to_si(1.0, unit, "kg", "units.tank.params.mass")
    assert str(e.value).startswith("units.tank.params.mass: ")
    assert message in str(e.value)


def test_a_settings_si_unit_is_read_from_its_description():
    from granuflow.structure import setting_si_unit
    assert setting_si_unit({"type": "number", "description": "largest pivot diameter, m (Table 5)"}) == "m"
    assert setting_si_unit({"type": "number", "description": "a count, dimensionless"}) == ""


def test_a_real_setting_in_a_scene_file_may_carry_a_unit_as_a_parameter_does():
    """`d_min: 50 um` in a scene file reads as 50e-6 (before: "expected a finite number", while `--set` converted
    it); `--set particles.d_min=50um` without a space too; a unit of another dimension, or one on a setting that
    has none, is refused naming the setting."""
    text = open(SCENE).read()
    plain = "settings: {classes: 10, d_min: 50e-6, d_max: 1000e-6}"
    assert plain in text
    si = gf.load_text(text, "si.yaml")
    units = gf.load_text(text.replace(plain, "settings: {classes: 10, d_min: 50 um, d_max: 1mm}"), "units.yaml")
    grid = lambda fs: {k: float(fs.unit_settings()["particles"][1][k]) for k in ("d_min", "d_max")}  # noqa: E731
    assert grid(units) == pytest.approx(grid(si), rel=1e-15) and grid(si) == {"d_min": 50e-6, "d_max": 1e-3}
    run = {"warn": False, "grid_check": False, "accuracy": False}
    assert units.simulate(**run).summary["d50_um"] == pytest.approx(si.simulate(**run).summary["d50_um"], rel=1e-9)
    assert grid(si.with_settings({"particles.d_min": "50um"})) == pytest.approx(grid(si), rel=1e-15)
    with pytest.raises(gf.ConfigError, match=r"particles.settings.d_min = '50 kg': unit 'kg' is kg, but the value "
                                             r"must be in m"):
        gf.load_text(text.replace(plain, "settings: {classes: 10, d_min: 50 kg}"), "kg.yaml")
    two_d = open(os.path.join(os.path.dirname(SCENE), "sen_2d_dem_kernel.yaml")).read()
    assert "      liquid_classes: 40\n" in two_d
    with pytest.raises(gf.ConfigError, match=r"number_scale = '1e9 kg': expected a plain number \(this setting "
                                             r"has no unit\)"):
        line = "      liquid_classes: 40\n"
        gf.load_text(two_d.replace(line, line + "      number_scale: 1e9 kg\n"), "2d.yaml")


def test_many_threads_get_the_same_conversions():
    texts = [("60 degC", "K"), ("700 m3/h", "m3/s"), ("3 mPa s", "Pa s"), ("5 W/K", "W/K"), ("2 kJ/(kg K)",
             "J/(kg K)")] * 40
    serial = [to_si(t, si, "x") for t, si in texts]
    with ThreadPoolExecutor(8) as pool:
        parallel = list(pool.map(lambda a: to_si(a[0], a[1], "x"), texts))
    assert parallel == serial


def test_a_process_forked_while_the_unit_database_loads_reads_units():
    """Importing the extension starts reading the unit database on a thread of its own; a process forked then (a
    ProcessPoolExecutor or multiprocessing pool started at once) copies only the forking thread. Without the fork
    handlers the child waited forever at its first unit, on a lock its parent's loading thread held. The extension is
    imported on its own here (not through the package, whose further imports usually outlast the loading), so that
    the fork comes while the database is being read: every child of the old code hung."""
    code = textwrap.dedent(f"""
        import os, signal, sys
        sys.path.insert(0, {os.path.dirname(_core.__file__)!r})
        import _core  # the extension alone: its import starts the database thread, and nothing else delays the fork
        for _ in range(3):
            pid = os.fork()
            if pid == 0:
                signal.alarm(10)  # a hung child ends (SIGALRM) instead of outliving the test
                _core.load_scene({SCENE!r})
                os._exit(0)
            _, status = os.waitpid(pid, 0)
            assert status == 0, f"the forked child ended with status {{status}} (SIGALRM: it hung)"
        print("ok")
    """)
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60)
    assert r.returncode == 0 and r.stdout.strip() == "ok", r.stderr[-2000:]
