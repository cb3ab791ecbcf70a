"""A plain run reads its scene and writes its results without NumPy or PyYAML (issue 32: their imports took longer
than the run). What replaced them is held to them here: the core's JSON of a scene section against PyYAML's safe
loader, the core's settings splice against a PyYAML-based splice, the core's reductions of a run's arrays against
NumPy's, and a run's files against those computed from NumPy arrays."""
import copy
import json
import math
import os
import subprocess
import sys

import numpy as np
import pytest
import yaml

import granuflow as gf
from granuflow import _core, structure

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
SCENE = os.path.join(ROOT, "flowsheets", "stoeckl_gf25_batch.yaml")

SCALARS = [
    "yes", "No", "ON", "off", "true", "False", "y", "n", "~", "null", "Null", "", "0", "-0", "+12", "017", "0o17",
    "0x1F", "0b101", "1_000", "1:30", "-1:30", "1:30.5", "1e3", "1.0e3", "1.0e+3", "50e-6", "2.5E-3", "1.", ".5",
    "+.inf", "-.Inf", ".NaN", ".nan", "3.14159265358979323846", "0.1", "-0.0", "12abc", "1 min", "60 degC", "1%",
    "'on'", '"017"', "'1e3'", '"a \\"quoted\\" \\\\ word"', "it's", "µm and °C", "!!str 12", "!!int '42'",
    "!!float '2'", "!!bool 'yes'", "x # a comment", "123456789012345678901234567890", "1.0e999", "-1.0e999",
    "1.0e-999", "1.0e-310", "0xFFFFFFFFFFFFFFFF", "4294967295:59:59",
]


def _notes_text(items) -> str:
    body = "\n".join(f"  k{i}: {s}" for i, s in enumerate(items))
    with open(SCENE, encoding="utf-8") as f:
        head = f.read()
    return (head + "\nnotes:\n" + body +
            "\n  nested: {list: [1, 'two', 3.0, [yes, ~]], map: {a: 0x10}}\n  block: |\n    line one\n    line two\n")


def _same(a, b) -> bool:
    if isinstance(a, float) and isinstance(b, float) and math.isnan(a) and math.isnan(b):
        return True
    if isinstance(a, dict) and isinstance(b, dict):
        return a.keys() == b.keys() and all(_same(a[k], b[k]) for k in a)
    if isinstance(a, list) and isinstance(b, list):
        return len(a) == len(b) and all(_same(x, y) for x, y in zip(a, b))
    return type(a) is type(b) and a == b and (not isinstance(a, float) or math.copysign(1, a) == math.copysign(1, b))


def test_a_scene_section_is_typed_as_pyyaml_types_it():
    text = _notes_text(SCALARS)
    mine = gf.load_text(text, "sections.yaml").section("notes")
    theirs = yaml.load(text, Loader=yaml.SafeLoader)["notes"]
    wrong = {k: (mine.get(k), v) for k, v in theirs.items() if not _same(mine.get(k), v)}
    assert not wrong, wrong
    by = {s: mine[f"k{i}"] for i, s in enumerate(SCALARS)}  # YAML 1.1 as PyYAML reads it, not YAML 1.2:
    assert by["ON"] is True and by["017"] == 15 and by["1:30"] == 90 and by["~"] is None and by["'on'"] == "on"
    assert by["1e3"] == "1e3" and by["1.0e+3"] == 1000.0 and isinstance(by["1.0e+3"], float) and by["y"] == "y"
    big = "123456789012345678901234567890"
    assert math.copysign(1.0, by["-0.0"]) == -1.0 and by[big] == int(big)


@pytest.mark.parametrize("value", ["0x10000000000000000", "0b" + "1" * 65, "0" + "7" * 23, "5124095576030432:0:0"])
def test_an_integer_beyond_64_bits_names_the_file_the_section_and_the_line(value):
    # PyYAML reads any integer; the core converts binary, octal, hex and base 60 in 64 bits and says so
    text = _notes_text(["1", value])
    line = text.splitlines().index(f"  k1: {value}") + 1
    with pytest.raises(ValueError) as e:
        gf.load_text(text, "sections.yaml")
    msg = str(e.value)
    assert msg.startswith("sections.yaml: ") and "section 'notes'" in msg and f"line {line}:" in msg, msg
    assert f"integer {value} is too large" in msg and "below 2^64" in msg, msg


def test_a_timestamp_stays_its_text_and_a_missing_section_is_none():
    text = _notes_text(["2001-12-14"])
    fs = gf.load_text(text, "sections.yaml")
    assert fs.section("notes")["k0"] == "2001-12-14"  # PyYAML would build a date, which JSON cannot carry
    assert fs.section("sweep") is None and fs.extra == {"plots": fs.section("plots"), "notes": fs.section("notes")}
    assert fs.extra["plots"] == yaml.safe_load(text)["plots"] and len(fs.extra["plots"]) == 4


def _splice_with_pyyaml(text: str, unit: str, settings: dict) -> str:
    """The splice as granuflow did it with PyYAML's node marks before the core took it over (the reference)."""
    root = yaml.compose(text, Loader=yaml.SafeLoader)

    def find(node, key):
        if isinstance(node, yaml.MappingNode):
            for k, v in node.value:
                if isinstance(k, yaml.ScalarNode) and k.value == key:
                    return v
        return None

    def insertion(node, entries):
        if not node.value:
            return node.start_mark.index, node.end_mark.index, "{" + entries + "}"
        first = node.value[0][0].start_mark
        if node.flow_style:
            return first.index, first.index, entries + ", "
        return first.index, first.index, entries.replace(", ", "\n" + " " * first.column) + "\n" + " " * first.column

    section = find(root, "particles") if unit == "particles" else None
    if section is None:
        section = find(find(root, "units"), unit)
    quoted = {k: json.dumps(v) for k, v in settings.items()}
    node = find(section, "settings")
    edits = []
    if not isinstance(node, yaml.MappingNode):
        edits.append(insertion(section, "settings: {" + ", ".join(f"{k}: {v}" for k, v in quoted.items()) + "}"))
    else:
        missing = []
        for k, v in quoted.items():
            value = find(node, k)
            if isinstance(value, yaml.ScalarNode):
                edits.append((value.start_mark.index, value.end_mark.index, v))
            else:
                missing.append(f"{k}: {v}")
        if missing:
            edits.append(insertion(node, ", ".join(missing)))
    for start, end, new in sorted(edits, reverse=True):
        text = text[:start] + new + text[end:]
    return text


SPLICE_CASES = [
    ("particles", "particles:\n  settings: {classes: 10, d_min: 50e-6}  # the grid\nunits: {}\n", {"classes": 19}),
    ("particles", "particles:\n  settings:\n    classes: 10   # ten\n    d_max: '1 mm'\n", {"classes": 40, "q": 2}),
    ("particles", "particles:\n  material: x\n", {"classes": 12}),
    ("particles", "particles: {material: x, settings: {}}\n", {"classes": 12, "grid": "geometric"}),
    ("particles", "particles:\n  settings: {classes: \"10\", d_min: 'a''b'}\n", {"classes": 8, "d_min": "1 um"}),
    ("bed", "units:\n  bed:\n    type: fluid_bed\n    settings: {liquid_classes: 20, kernel: eke}\n",
     {"liquid_classes": 40}),
    ("bed", "# µm grid\nunits:\n  bed: {type: x, settings: {liquid_classes: !!int 20}}\n", {"liquid_classes": 5}),
]


@pytest.mark.parametrize("unit,text,settings", SPLICE_CASES)
def test_the_core_splices_settings_as_the_pyyaml_splice_did(unit, text, settings):
    assert structure.splice_settings(text, unit, settings, "s.yaml") == _splice_with_pyyaml(text, unit, settings)


# Where the PyYAML splice above went wrong: it split every ", " of what it added into lines, so two settings added to
# a block-style unit without `settings:` became a flow mapping broken over two lines at the keys' indentation (not
# YAML), and a value with ", " in it was cut in two.
SEMANTIC_SPLICE_CASES = [
    ("bed", "units:\n  bed:\n    type: fluid_bed\n    params: {bed_mass: 15 kg}\n",
     {"aggregation": "none", "breakage": "none"}),
    ("bed", "units:\n  bed:\n    type: fluid_bed\n    settings:\n      kernel: eke   # c\n",
     {"note": "a, b", "aggregation": "none", "kernel": "glass_transition"}),
    ("particles", "particles:\n  material: x\n  # grid\nunits: {}\n", {"classes": 12, "grid": "a, b"}),
]


@pytest.mark.parametrize("unit,text,settings", SEMANTIC_SPLICE_CASES)
def test_settings_spliced_together_read_back_as_set_and_leave_the_rest(unit, text, settings):
    out = structure.splice_settings(text, unit, settings, "s.yaml")
    before, after = yaml.safe_load(text), yaml.safe_load(out)
    where = (lambda d: d["particles"]) if unit == "particles" else (lambda d: d["units"][unit])
    assert where(after)["settings"] == {**(where(before).get("settings") or {}), **settings}
    where(after).pop("settings"), where(before).pop("settings", None)
    assert after == before
    assert all(line in out.splitlines() for line in text.splitlines() if "kernel" not in line)  # comments kept


def test_two_settings_of_one_unit_change_the_headline_scene_together():
    fs = gf.load(SCENE)
    both = fs.with_settings({"bed.aggregation": "none", "bed.breakage": "none"})
    kind, settings = both.unit_settings()["bed"]
    assert kind == "fluid_bed" and settings["aggregation"] == "none" and settings["breakage"] == "none"
    one = fs.with_settings({"bed.aggregation": "none"})
    # the second setting took effect: breakage off moves the product of a run without aggregation
    d_both = both.simulate(warn=False, grid_check=False, accuracy=False).summary
    d_one = one.simulate(warn=False, grid_check=False, accuracy=False).summary
    assert d_both["d10_um"] != d_one["d10_um"]


def test_a_splice_refuses_what_it_cannot_keep_byte_for_byte():
    with pytest.raises(gf.ConfigError, match="s.yaml: no unit 'bed'"):
        structure.splice_settings("units: {}\n", "bed", {"classes": 3}, "s.yaml")
    with pytest.raises(gf.ConfigError, match="block scalar"):
        structure.splice_settings("particles:\n  settings:\n    classes: |\n      10\n", "particles",
                                  {"classes": 3}, "s.yaml")


def _numpy_end_fractions(o, mcols):
    m = o[:, mcols]
    total = m.sum(axis=1)
    out = []
    for k in (0, -1):
        f = np.divide(m[:, k], total, out=np.zeros_like(total), where=total > 0)
        out.append((float(f[0]), float(f[-1]), float(np.max(f))))
    return out


@pytest.mark.parametrize("rows", [1, 2, 7, 121])
def test_the_core_reductions_are_numpys(rows):
    rng = np.random.default_rng(rows)
    o = rng.lognormal(size=(rows, 150)) * rng.choice([0.0, 1e-30, 1.0, 1e12], size=(rows, 150))
    o[0, 3] = -0.0
    if rows > 2:
        o[1, :] = 0.0  # a row without mass: fraction 0
        o[2, 7] = np.nan
    view = o[:, ::2]  # a strided view, not a copy
    for mcols in ([0, 1, 2], list(range(3, 70)), list(range(75))):
        got = _core.end_fractions(view, mcols, [0, -1])
        want = _numpy_end_fractions(view, mcols)
        assert [tuple(g) for g in got] == pytest.approx(want, rel=0, abs=0, nan_ok=True)
    for j in (0, 3, 7, 74):
        a, b = _core.column_max(view, j), float(np.max(view[:, j]))
        assert a == b or (math.isnan(a) and math.isnan(b))
    y = o.copy()
    y[:, 5] = np.where(y[:, 5] == 0.0, -0.0, y[:, 5])
    for i, j in ((3, 3), (5, 5), (7, 7), (4, 9)):
        assert _core.columns_equal(y, i, o, j) == np.array_equal(y[:, i], o[:, j])
    t = np.linspace(0.0, 3600.0, rows)
    cols = [(0, 1), (1, 4), (0, 7), (1, 149)]
    shift, scale = [0.0, -273.15, 0.0, 1.5], [1.0, 1.0, 1e-6, 3.0]
    blocks = [y, o]
    ref = np.column_stack([t, t / 60.0] + [(blocks[k][:, j] - a) / b for (k, j), a, b in zip(cols, shift, scale)])
    assert _core.csv_table(t, blocks, cols, shift, scale) == _core.csv_rows(ref)


def test_a_runs_arrays_become_numpy_on_first_use():
    fs = gf.load(SCENE)
    res = fs.simulate(t_end=600.0, n_out=5, warn=False, grid_check=False)
    summary = res.summary
    assert "y" not in res.__dict__  # not made before a caller asks
    y = res.y
    assert isinstance(y, np.ndarray) and y.shape == (5, len(res.state_names)) and res.y is y
    assert y.flags.writeable and res.t[-1] == 600.0
    assert summary == res.summary and np.array_equal(copy.copy(res).outputs, res.outputs)
    assert res["bed.d50"][-1] * 1e6 == pytest.approx(summary["d50_um"], rel=1e-15)


def test_a_plain_run_imports_neither_numpy_nor_pyyaml(tmp_path):
    heavy = ("numpy", "yaml", "pandas", "granuflow._calibration")
    code = ("import sys; from granuflow.cli import main; rc = main(['run', sys.argv[1], '--out', sys.argv[2], "
            f"'--no-plots', '--quiet']); print(sorted(m for m in {heavy!r} if m in sys.modules))")
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(p for p in sys.path if p))
    p = subprocess.run([sys.executable, "-c", code, SCENE, str(tmp_path / "o")], capture_output=True, text=True,
                       env=env, timeout=300)
    assert p.returncode == 0, p.stderr
    assert p.stdout.strip().splitlines()[-1] == "[]"
    s = json.loads((tmp_path / "o" / "summary.json").read_text())
    assert s["d50_um"] == gf.load(SCENE).simulate(warn=False).summary["d50_um"] and "grid_check" in s
    assert (tmp_path / "o" / "timeseries.csv").read_text().count("\n") == 122
