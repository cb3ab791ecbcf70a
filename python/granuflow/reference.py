"""The user reference of units and kernels, generated from the registries of the C++ core (what each one declares),
so that ``granuflow units NAME``, ``gf.unit_reference(NAME)`` and the pages in ``docs/units`` and ``docs/kernels``
cannot drift from the code. ``python3 -m granuflow docs --write docs`` regenerates the pages; a test checks them.

A unit's parameters, states and outputs can depend on its settings (the class count, the kernel chosen): the
reference shows the defaults, and ``unit_reference(NAME, settings={...})`` shows another choice.
"""
from __future__ import annotations

import math
from collections.abc import Mapping

from . import _core, materials

# Kernel families as they are chosen in a scene: the setting of the particle units that names one.
KERNEL_FAMILIES = {
    "aggregation": ("aggregation kernels", "`aggregation:` setting of `fluid_bed` and `pbm_batch`"),
    "breakage_selection": ("breakage selection rates", "`breakage:` setting of `fluid_bed` and `pbm_batch`"),
    "breakage_fragments": ("fragment distributions", "`fragments:` setting of `pbm_batch`"),
    "growth": ("growth laws", "`growth:` setting of `pbm_batch`"),
    "aggregation_scheme": ("aggregation schemes", "`aggregation_scheme:` setting"),
    "breakage_scheme": ("breakage schemes", "`breakage_scheme:` setting"),
    "growth_scheme": ("growth schemes", "`growth_scheme:` setting"),
    "separation": ("separation curves", "`upper_curve:`, `lower_curve:` of `sieve`, `classifier:` of the chambers"),
    "comminution": ("comminution laws", "`law:` setting of `mill`"),
    "drying_curve": ("drying curves", "`drying_curve:` setting of `fluid_bed` and the wet chambers"),
    "drying_surface": ("drying surfaces", "`drying_surface:` setting of `fluid_bed`"),
}


def unit_types() -> dict[str, str]:
    """Built-in unit types and their one-line descriptions."""
    return dict(_core.unit_types())


class UnitReference(dict):
    """What a unit type declares (a dict); printed, or shown in a notebook, it is the reference page."""

    def __str__(self) -> str:
        return unit_markdown(self["type"], self)

    def _repr_markdown_(self) -> str:
        return str(self)


def unit_reference(name: str, settings: Mapping[str, object] | None = None) -> UnitReference:
    """What a unit of type ``name`` declares: ``ports`` (stream kind, direction, optional), ``settings`` (type,
    allowed values, default), ``params`` (SI unit, bounds, default, source), ``states`` and ``outputs`` (SI units).
    ``settings`` choose another structure than the defaults (e.g. ``{"classes": 20}``). ConfigError for an unknown
    type or setting."""
    given = {str(k): (str(v).lower() if isinstance(v, bool) else str(v)) for k, v in (settings or {}).items()}
    return UnitReference(_core.unit_reference(str(name), given))


def kernel_reference() -> dict[str, list[dict]]:
    """Every registered kernel and scheme by family: name, description, parameters (SI unit, bounds, default,
    source), settings, and the per-class state it reads (``needs``)."""
    return _core.kernel_reference()


# -- text -----------------------------------------------------------------------------------------------------------
def _num(x: float) -> str:
    if x is None or (isinstance(x, float) and math.isnan(x)):
        return ""
    if abs(x) >= 1e299:
        return "-inf" if x < 0 else "inf"
    return f"{x:g}"


def _bounds(lo: float, hi: float) -> str:
    return f"[{_num(lo)}, {_num(hi)}]"


def _setting_allowed(s: dict) -> str:
    if s["choices"]:
        # prototypes registered from Python in this process are not part of the reference
        return " | ".join(c for c in s["choices"] if c not in set(_core.python_kernels()))
    if s["type"] in ("bool", "boolean"):
        return "true | false"
    if s["type"] in ("int", "integer", "real", "number"):
        return _bounds(s["lower"], s["upper"])
    return "any text"


def _cell(text: str) -> str:
    return str(text).replace("|", "\\|").replace("\n", " ")


def _table(header: list[str], rows: list[list[str]]) -> list[str]:
    out = ["| " + " | ".join(header) + " |", "|" + "|".join("---" for _ in header) + "|"]
    out += ["| " + " | ".join(_cell(c) for c in r) + " |" for r in rows]
    return out


def param_rows(params: list[dict], prefix: str = "") -> list[list[str]]:
    return [[f"`{prefix}{p['name']}`", p["unit"], _num(p["default"]), _bounds(p["lower"], p["upper"]),
             p["description"], p["source"]] for p in params]


def unit_markdown(name: str, ref: Mapping | None = None) -> str:
    """The reference page of a unit type (Markdown), as in docs/units/NAME.md (``ref``: one with other settings)."""
    r = ref if ref is not None else unit_reference(name)
    lines = [f"# Unit `{name}`", "", r["description"], "",
             "Generated from the unit registry by `granuflow docs --write docs` (do not edit by hand; "
             "`tests/python/test_reference_docs.py` checks it is up to date). Values are SI; a scene may give any "
             "unit of the same dimension (`\"60 degC\"`). Parameters, states and outputs below are those of the "
             "default settings.", ""]
    if r["explicit"]:
        lines += ["This unit has no hold-up: it is evaluated inline and adds no unknowns to the solver.", ""]
    lines += ["## Ports", ""]
    lines += _table(["port", "stream", "direction", "optional", "classes"],
                    [[f"`{p['name']}`", p["kind"], p["direction"], "yes" if p["optional"] else "no",
                      str(p["classes"]) if p["classes"] else ""] for p in r["ports"]]) if r["ports"] else ["(none)"]
    lines += ["", "## Settings (change the structure; set under `settings:`)", ""]
    lines += _table(["setting", "type", "allowed", "default", "description"],
                    [[f"`{s['name']}`", s["type"], _setting_allowed(s), f"`{s['default']}`", s["description"]]
                     for s in r["settings"]]) if r["settings"] else ["(none)"]
    lines += ["", "## Parameters (set under `params:`, `--set`, sweeps, calibration, `inputs:`)", ""]
    lines += _table(["parameter", "SI unit", "default", "bounds", "description", "source"],
                    param_rows(r["params"])) if r["params"] else ["(none)"]
    lines += ["", "## States", ""]
    lines += _table(["state", "kind", "SI unit"], [[f"`{s['name']}`", s["kind"], s["unit"]]
                                                   for s in _collapse(r["states"])]) if r["states"] else ["(none)"]
    lines += ["", "## Reported outputs", ""]
    lines += _table(["output", "SI unit"], [[f"`{o['name']}`", o["unit"]]
                                            for o in _collapse(r["outputs"])]) if r["outputs"] else ["(none)"]
    return "\n".join(lines) + "\n"


def _collapse(items: list[dict]) -> list[dict]:
    """Per-class entries (``N_0 ... N_19``) as one row ``N_<i>`` (i = 0..19)."""
    import re

    out, seen = [], {}
    for it in items:
        m = re.match(r"^(.*_)(\d+)$", it["name"])
        if m:
            key = (m.group(1), it.get("unit"), it.get("kind"))
            if key in seen:
                seen[key]["last"] = int(m.group(2))
                continue
            row = dict(it, name=f"{m.group(1)}<i>", first=int(m.group(2)), last=int(m.group(2)))
            seen[key] = row
            out.append(row)
        else:
            out.append(dict(it))
    for row in out:
        if "first" in row:
            row["name"] = f"{row['name']} (i = {row.pop('first')}..{row.pop('last')})"
    return out


def kernel_markdown(family: str) -> str:
    """The reference page of one kernel family (Markdown), as in docs/kernels/FAMILY.md."""
    title, chosen = KERNEL_FAMILIES.get(family, (family, ""))
    own = set(_core.python_kernels())  # prototypes registered in this process are not part of the reference
    entries = [e for e in kernel_reference()[family] if e["name"] not in own]
    lines = [f"# {title[0].upper() + title[1:]}", "", f"Chosen by the {chosen}." if chosen else "",
             "", "Generated from the kernel registry by `granuflow docs --write docs` (do not edit by hand; "
             "`tests/python/test_reference_docs.py` checks it is up to date). A unit declares a kernel's parameters "
             "under its own name with a prefix (for example `agg_` for aggregation kernels); `granuflow describe "
             "SCENE` lists them as the scene uses them.", ""]
    for e in entries:
        lines += [f"## `{e['name']}`", "", e["description"], ""]
        needs = [k.replace("_", " ") for k, v in (e.get("needs") or {}).items() if v]
        if "needs" in e:
            lines += [("Reads per class: " + ", ".join(needs) + " (evaluated at every residual)." if needs else
                       "Reads only the class sizes: evaluated once per run, not at every residual."), ""]
        if e.get("note"):
            lines += [f"Its settings need what a scene loads (declaring it alone says: {e['note']}).", ""]
        if e["settings"]:
            lines += _table(["setting", "type", "allowed", "default", "description"],
                            [[f"`{s['name']}`", s["type"], _setting_allowed(s), f"`{s['default']}`",
                              s["description"]] for s in e["settings"]]) + [""]
        if e["params"]:
            lines += _table(["parameter", "SI unit", "default", "bounds", "description", "source"],
                            param_rows(e["params"])) + [""]
    return "\n".join(lines).rstrip() + "\n"


def unit_text(name: str) -> str:
    """``granuflow units NAME``: the reference page as plain text for a terminal (no truncation)."""
    return unit_markdown(name)


# -- materials ------------------------------------------------------------------------------------------------------
def parameters_set(prop: dict) -> list[str]:
    """Where a property lands with the units' default settings: ``unit_type.param`` and ``kernel KERNEL.param``."""
    if prop["applies_to"] == "particles":
        return [f"particles.{prop['name']}"]
    names = {prop["name"], "agg_" + prop["name"]}
    out = [f"{t}.{p['name']}" for t in unit_types() if t != "particles"
           for p in unit_reference(t)["params"] if p["name"] in names]
    out += [f"aggregation kernel {k['name']}.{p['name']}" for k in kernel_reference().get("aggregation", [])
            for p in k["params"] if p["name"] == prop["name"]]
    return out


def _value(v: float) -> str:
    return f"{v:.6g}"


def material_markdown(m: dict) -> str:
    """The catalogue entry of one material as Markdown (``granuflow materials NAME``)."""
    rows = [[f"`{p['name']}`", _value(p["value"]), p["unit"], p["description"],
             ", ".join(f"`{x}`" for x in parameters_set(p)) or "(informative: no parameter reads it yet)",
             p["source"]] for p in m["properties"]]
    lines = [f"## `{m['name']}`", "", m["description"] + ".", "", f"Main source: {m['citation']}.", ""]
    lines += _table(["property", "value", "SI unit", "what", "sets", "source"], rows)
    return "\n".join(lines) + "\n"


def catalogue_markdown() -> str:
    """docs/materials.md: the whole catalogue."""
    lines = ["# Materials", "",
             "Generated from the catalogue in `framework/src/materials.cpp` by `granuflow docs --write docs` (do not "
             "edit by hand; `tests/python/test_reference_docs.py` checks it is up to date).", "",
             "A scene names its solid in the particle system: `particles: {material: maltodextrin_de21, settings: ...,"
             " params: ...}`. Each property below then becomes the default of the parameters it sets (`granuflow "
             "describe SCENE` shows `material NAME: source` as their source); the scene's own `params:` override any "
             "of them. A parameter that some material of the catalogue sets but the chosen material does not keeps "
             "the unit's built-in value only openly: its source in `describe` says so, and summary.json lists it "
             "under `material.built_in` (set it in the scene's params to replace it). "
             "A scene that names no material keeps the units' built-in defaults, which are paper 001's maltodextrin "
             "(its `describe` sources say `paper 001, Table N`).", "",
             "Values enter the catalogue only with a published source. Properties that no model reads yet are kept "
             "where a source gives them (strength, restitution), for the user's information.", ""]
    for m in materials.catalogue():
        lines += [material_markdown(m)]
    return "\n".join(lines)


def pages() -> dict[str, str]:
    """Every generated page: relative path under docs/ -> Markdown."""
    out = {f"units/{n}.md": unit_markdown(n) for n in unit_types()}
    out.update({f"kernels/{f}.md": kernel_markdown(f) for f in kernel_reference()})
    out["materials.md"] = catalogue_markdown()
    lines = ["# Reference: units and kernels", "",
             "Generated from the registries by `granuflow docs --write docs`; checked by "
             "`tests/python/test_reference_docs.py`.", "", "## Units", ""]
    lines += [f"- [`{n}`](units/{n}.md): {d}" for n, d in unit_types().items()]
    lines += ["", "## Kernels and schemes", ""]
    own = set(_core.python_kernels())
    lines += [f"- [{KERNEL_FAMILIES.get(f, (f, ''))[0]}](kernels/{f}.md): "
              + ", ".join(f"`{e['name']}`" for e in es if e["name"] not in own) for f, es in kernel_reference().items()]
    lines += ["", "## Materials", "", "- [the catalogue of solid materials](materials.md): "
              + ", ".join(f"`{m['name']}`" for m in materials.catalogue())]
    out["reference.md"] = "\n".join(lines) + "\n"
    return out
