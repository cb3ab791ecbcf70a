"""The hand-written documents stay true (issue 33 §6): every `unit.name` they cite is a parameter, setting, state,
port or output of that unit in a shipped scene, every `granuflow COMMAND` they show is a command, and every option shown
with a command is one of its options. The generated reference (granuflow docs) is checked by test_reference_docs."""
import glob
import os
import re

import pytest
from conftest import cli

import granuflow as gf
from granuflow import reference

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
GENERATED = set(reference.pages())
DOCS = sorted(["README.md"] + [os.path.relpath(p, ROOT) for p in glob.glob(os.path.join(ROOT, "docs", "*.md"))
                               if os.path.relpath(p, os.path.join(ROOT, "docs")) not in GENERATED])
# `file.ext` and `module.function` names that look like `unit.name` but are not
NOT_UNITS = {"summary", "steady", "sweep", "contour", "calibration", "timeseries", "psd", "gf", "fs", "res", "np",
             "granuflow", "os", "sys", "tests", "docs", "flowsheets", "python", "build", "out", "run", "ida", "kinsol",
             "scipy", "pytest", "examples", "yaml", "json", "csv", "math", "numpy", "pandas", "result", "self"}
EXTENSIONS = {"json", "yaml", "yml", "md", "csv", "py", "ipynb", "cpp", "hpp", "txt", "svg", "png", "pdf", "npz",
              "html", "so", "sh", "dot", "cff", "toml", "cmake"}


def _text(rel):
    with open(os.path.join(ROOT, rel), encoding="utf-8") as f:
        return f.read()


def _type_names(typ, cache={}):
    """Every name a unit type declares under any one choice of one setting (a parameter such as V_vessel exists only
    with beta0_basis: per_m3)."""
    if typ not in cache:
        keys = ("params", "states", "outputs", "settings", "ports")
        base = reference.unit_reference(typ)
        names = {x["name"] for key in keys for x in base[key]}
        for s in base["settings"]:
            for value in s.get("choices") or []:
                try:
                    r = reference.unit_reference(typ, {s["name"]: value})
                except (gf.ConfigError, ValueError):
                    continue
                names |= {x["name"] for key in keys for x in r[key]}
        cache[typ] = names
    return cache[typ]


def _known_names():
    """unit instance name -> every parameter, setting, state and output it has in any shipped scene, or its type
    has under another choice of a setting."""
    import yaml
    known = {}
    for path in glob.glob(os.path.join(ROOT, "flowsheets", "*.yaml")):
        if "\nunits:" not in open(path, encoding="utf-8").read():
            continue
        fs = gf.load(path)
        names = list(fs.params) + list(fs.state_names) + list(fs.output_names)
        names += [f"{u}.{s['name']}" for u, specs in fs.setting_specs().items() for s in specs]
        for n in names:
            unit, _, rest = n.partition(".")
            known.setdefault(unit, set()).add(rest)
        for unit, spec in (yaml.safe_load(fs.text).get("units") or {}).items():
            known.setdefault(unit, set()).update(_type_names(spec["type"]))
    return known


KNOWN = _known_names()


def _cited(rel):
    """(`unit.name`, line number) for every unit.name in code (spans and blocks) whose unit is a scene's."""
    out = []
    for i, span in _code(rel):
        for m in re.finditer(r"(?<![\w./-])([a-z][a-z0-9_]*)\.([A-Za-z][A-Za-z0-9_]*)(?![\w.(/-]|\(\))", span):
            unit, name = m.groups()
            if unit in NOT_UNITS or name in EXTENSIONS or unit not in KNOWN:
                continue
            out.append((f"{unit}.{name}", i))
    return out


def _indexed(name, names):
    """Per-class names are cited with an index (M_9, x_N10) or a placeholder (M_i, M_k)."""
    if name == "Q3":  # the calibration observable unit.Q3(size) (docs/measured_psd.md)
        return True
    base = re.sub(r"_(\d+|N\d+|[ijk])$", "", name)
    return any(re.sub(r"_(\d+|N\d+)$", "", n) == base for n in names)


@pytest.mark.parametrize("rel", DOCS)
def test_cited_parameters_settings_and_outputs_exist(rel):
    wrong = [f"{rel}:{line}: `{ref}`" for ref, line in _cited(rel)
             if not (ref.split(".", 1)[1] in KNOWN[ref.split(".")[0]]
                     or _indexed(ref.split(".", 1)[1], KNOWN[ref.split(".")[0]]))]
    assert not wrong, "names that no shipped scene has:\n" + "\n".join(wrong)


def _commands():
    r = cli("--help")
    return set(re.search(r"\{([a-z,-]+)\}", r.stdout).group(1).split(","))


COMMANDS = _commands()
_OPTIONS = {}


def _options(cmd):
    if cmd not in _OPTIONS:
        _OPTIONS[cmd] = set(re.findall(r"(--[a-z][a-z0-9-]*)", cli(cmd, "--help").stdout))
    return _OPTIONS[cmd]


def _code(rel):
    """(line number, text) of every line of a fenced code block and every inline code span: where commands are
    shown (prose that says "granuflow runs ..." is not a command line)."""
    fenced = False
    for i, line in enumerate(_text(rel).splitlines(), 1):
        if line.lstrip().startswith("```"):
            fenced = not fenced
            continue
        if fenced:
            yield i, line
        else:
            for span in re.findall(r"`([^`]+)`", line):
                yield i, span


@pytest.mark.parametrize("rel", DOCS)
def test_shown_commands_and_options_exist(rel):
    wrong = []
    for i, code in _code(rel):
        if re.search(r"(import|from)\s+granuflow", code):
            continue
        for m in re.finditer(r"(?:^|[\s(/])granuflow\s+([a-z][a-z0-9-]*)([^#|]*)", code):
            cmd, rest = m.groups()
            if cmd not in COMMANDS:
                wrong.append(f"{rel}:{i}: command '{cmd}'")
                continue
            wrong += [f"{rel}:{i}: {cmd} {o}" for o in re.findall(r"(?<![\w-])(--[a-z][a-z0-9-]*)", rest)
                      if o not in _options(cmd) | {"--help"}]
    assert not wrong, "commands or options that the command line does not have:\n" + "\n".join(wrong)


def test_the_checks_see_what_the_readme_shows():
    seen = {m.group(1) for _, code in _code("README.md") for m in re.finditer(r"granuflow\s+([a-z]+)", code)}
    assert {"run", "steady", "sweep", "contour", "calibrate", "describe", "draw"} <= seen
    cited = {ref for ref, _ in _cited("README.md")}
    assert "nozzle.mdot" in cited and "bed.agg_ln_beta0" in cited


def test_a_moved_parameter_or_setting_names_its_new_place():
    fs = gf.load(os.path.join(ROOT, "flowsheets", "stoeckl_gf25_batch.yaml"))
    with pytest.raises(gf.ConfigError, match=r"'rho_s' is a parameter of particles: particles\.rho_s"):
        fs.set("bed.rho_s", 1500)
    text = fs.text.replace("    type: fluid_bed\n", "    type: fluid_bed\n    settings: {classes: 20}\n", 1)
    with pytest.raises(gf.ConfigError, match="'classes' is a setting of particles: set it under particles: settings:"):
        gf.load_text(text)
