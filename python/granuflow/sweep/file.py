"""Sweep files (YAML): schema, checks and the points they define."""
from __future__ import annotations

import os
from dataclasses import dataclass, field
from typing import Any, Mapping

from .. import _core, structure
from ..flowsheet import Flowsheet, load
from ..quantity import affine, is_number, parse_time, split, to_si
from ..textfile import load_yaml, short
from .runner import DEFAULT_OUTPUTS, check_outputs, error_column, run_sweep

ConfigError = _core.ConfigError
_TOP_KEYS = ("sweep", "description", "scene", "variables", "points", "outputs", "set", "t_end", "notes")
_VAR_KEYS = ("param", "unit", "levels", "description")
_POINT_LABELS = ("name", "kind")


@dataclass
class Variable:
    name: str          # column name in the results
    param: str         # scene parameter, "unit.param", or a unit setting ("particles.classes": rebuilds the flowsheet)
    unit: str          # edge unit of the values ("" = SI)
    levels: list[float] = field(default_factory=list)  # optional, informative (low, centre, high)
    description: str = ""
    setting: bool = False  # a unit setting: point values as written in a scene file (10, "constant", "3 mm")

    def to_si(self, value: float, si_unit: str) -> float:
        return to_si(float(value), si_unit, self.param, self.unit)

    def quantity(self, value):
        return value if self.setting else f"{value!r} {self.unit}".strip()


@dataclass
class Sweep:
    """A loaded sweep file. ``run()`` returns the results as a DataFrame."""

    path: str
    name: str
    description: str
    scene: str                       # absolute path of the scene file
    variables: list[Variable]
    points: list[dict]               # {"name", "kind", <variable>: value in the variable's unit}
    outputs: list[str]
    set: dict = field(default_factory=dict)
    t_end: float | None = None       # s

    # -- building blocks -------------------------------------------------------------------------
    def flowsheet(self, overrides: Mapping[str, float | str] | None = None) -> Flowsheet:
        """The scene with the sweep file's ``set`` and then ``overrides`` applied."""
        fs = load(self.scene)
        for k, v in (overrides or {}).items():
            if any(var.param == k for var in self.variables):
                raise ConfigError(f"--set {k}={v}: {k} is a variable of sweep '{self.name}' "
                                  f"(its values come from the points)")
        fs = structure.with_settings(fs, structure.split(fs, self.set)[0], f"{self.path}: set:")
        fs = structure.with_settings(fs, structure.split(fs, overrides or {})[0], "--set")
        for k, v in structure.split(fs, self.set)[1].items():
            set_or_raise(fs, k, v, f"{self.path}: set.{k}")
        for k, v in structure.split(fs, overrides or {})[1].items():
            set_or_raise(fs, k, v, f"--set {k}")
        if self.t_end is not None:
            fs.set_t_end(self.t_end)
        return fs

    def param_points(self) -> list[dict]:
        """The points as ``{"unit.param": "value unit"}`` for :func:`run_sweep`."""
        return [{v.param: v.quantity(p[v.name]) for v in self.variables} for p in self.points]

    @property
    def point_names(self) -> list[str]:
        return [p["name"] for p in self.points]

    # -- running ---------------------------------------------------------------------------------
    def run(self, *, workers: int | None = None, progress: bool | None = None, executor: str | Any = "threads",
            overrides: Mapping[str, float | str] | None = None, raise_errors: bool = False,
            flowsheet: Flowsheet | None = None, simulate: Mapping[str, Any] | None = None,
            error_estimate: bool = False):
        """Run every point. Returns a DataFrame: ``point``, ``kind``, one column per variable (in its edge unit),
        the outputs (with ``error_estimate``, each followed by ``<output>_err``, its estimated numerical error),
        ``wall_time_s``, ``solve_time_s``, ``status``, ``message``. ``df.attrs`` holds the sweep name,
        the variables (parameter, unit, levels) and the outputs, which :func:`main_effects` uses."""
        fs = flowsheet if flowsheet is not None else self.flowsheet(overrides)
        raw = run_sweep(fs, self.param_points(), self.outputs, names=self.point_names, workers=workers,
                        progress=progress, executor=executor, raise_errors=raise_errors, simulate=simulate,
                        desc=self.name, error_estimate=error_estimate)
        errs = [error_column(o) for o in self.outputs] if error_estimate else []
        df = raw[["point"]].copy()
        df["kind"] = [p.get("kind", "") for p in self.points]
        for v in self.variables:
            df[v.name] = [p[v.name] if v.setting else float(p[v.name]) for p in self.points]
        for c in self.outputs + errs + ["wall_time_s", "solve_time_s", "status", "message"]:
            df[c] = raw[c].to_numpy()
        df.attrs.update(self.metadata())
        df.attrs["units"] = {**{v.name: "" if v.setting else v.unit or fs.spec(v.param)["unit"]
                                for v in self.variables},
                             **{o: raw.attrs["units"].get(o, "") for o in self.outputs + errs},
                             "wall_time_s": "s", "solve_time_s": "s"}
        return df

    def metadata(self) -> dict:
        return {"sweep": self.name, "description": self.description, "scene": self.scene,
                "variables": {v.name: {"param": v.param, "unit": v.unit, "levels": list(v.levels),
                                       **({"setting": True} if v.setting else {})}
                              for v in self.variables},
                "outputs": list(self.outputs), "set": dict(self.set), "t_end_s": self.t_end}


def _setting_variable(fs: Flowsheet, vname: str, spec: dict, err) -> Variable:
    """A variable that is a unit setting: its values as a scene file writes them (no edge unit: a real setting's
    value may carry one, "3 mm"); levels informative."""
    if spec.get("unit", ""):
        raise err(f"variables.{vname}.unit", f"{spec['param']} is a unit setting: give its values as in a scene "
                                             "file (a length with its unit, e.g. '3 mm'), not a unit")
    levels = spec.get("levels", [])
    if not isinstance(levels, list):
        raise err(f"variables.{vname}.levels", f"expected a list, got {short(levels)}")
    return Variable(vname, spec["param"], "", list(levels), str(spec.get("description", "")), setting=True)


def set_or_raise(fs: Flowsheet, name: str, value, where: str, shown=None) -> None:
    try:
        fs.set(name, value)
    except (ConfigError, TypeError) as e:
        shown = value if shown is None else shown
        raise ConfigError(f"{where} = {short(shown)}: {' '.join(str(e).split())}") from None


def load_sweep(path: str | os.PathLike) -> Sweep:
    """Read and check a sweep file. Raises ConfigError naming the file, the key, the value and what is allowed;
    every point is checked against the parameter bounds before anything runs."""
    path = os.fspath(path)
    doc = load_yaml(path, "sweep file")
    if not isinstance(doc, dict):
        raise ConfigError(f"{path}: expected a mapping with keys {', '.join(_TOP_KEYS)}, got {short(doc)}")

    def err(key: str, msg: str) -> ConfigError:
        return ConfigError(f"{path}: {key}: {msg}")

    for k in doc:
        if k not in _TOP_KEYS:
            raise err(str(k), f"unknown key (allowed: {', '.join(_TOP_KEYS)})")
    for k in ("scene", "variables", "points"):
        if k not in doc:
            raise err(k, "missing required key")
    if not isinstance(doc["scene"], str):
        raise err("scene", f"expected a path (relative to the sweep file), got {short(doc['scene'])}")
    scene = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(path)), doc["scene"]))
    if not os.path.isfile(scene):
        raise err("scene", f"'{doc['scene']}': no such file ({scene})")
    fs = load(scene)
    name = str(doc.get("sweep") or os.path.splitext(os.path.basename(path))[0])

    # variables
    vdoc = doc["variables"]
    if not isinstance(vdoc, dict) or not vdoc:
        raise err("variables", "expected a mapping name -> {param: unit.param, unit: U, levels: [...]}")
    variables = []
    for vname, spec in vdoc.items():
        key = f"variables.{vname}"
        if not isinstance(vname, str) or vname in _POINT_LABELS:
            raise err(key, f"invalid variable name (not {', '.join(_POINT_LABELS)})")
        if not isinstance(spec, dict):
            raise err(key, "expected a mapping {param: unit.param, unit: U, levels: [...]}")
        for k in spec:
            if k not in _VAR_KEYS:
                raise err(f"{key}.{k}", f"unknown key (allowed: {', '.join(_VAR_KEYS)})")
        if "param" not in spec:
            raise err(f"{key}.param", "missing required key")
        param = spec["param"]
        if structure.is_setting(fs, param):
            variables.append(_setting_variable(fs, vname, spec, err))
            continue
        if param not in fs.params:
            raise err(f"{key}.param", f"unknown parameter '{param}' of scene '{fs.name}' "
                                      f"(allowed: {', '.join(fs.params)})")
        if fs.spec(param).get("input"):
            raise err(f"{key}.param", f"{param} is driven by a time-dependent input of scene '{fs.name}' (inputs: "
                                      f"{param}); every point would run the input, not the sweep's values: sweep "
                                      "another parameter, or remove the input from the scene")
        si_unit = fs.spec(param)["unit"]
        unit = spec.get("unit", "")
        if not isinstance(unit, str):
            raise err(f"{key}.unit", f"expected a unit string, got {short(unit)}")
        try:
            affine(unit, si_unit, param)
        except ConfigError as e:
            raise err(f"{key}.unit", f"'{unit}' does not fit {param} (SI unit {si_unit}): "
                                     f"{' '.join(str(e).split())}") from None
        levels = spec.get("levels", [])
        if not isinstance(levels, list) or not all(is_number(x) for x in levels):
            raise err(f"{key}.levels", f"expected a list of numbers in {unit or si_unit}, got {short(levels)}")
        variables.append(Variable(vname, param, unit, [float(x) for x in levels], str(spec.get("description", ""))))
    if len({v.param for v in variables}) != len(variables):
        raise err("variables", "two variables set the same parameter")

    # outputs
    outputs = doc.get("outputs", list(DEFAULT_OUTPUTS))
    if not isinstance(outputs, list) or not outputs:
        raise err("outputs", f"expected a list of summary keys, got {short(outputs)}")
    outputs = check_outputs(fs, outputs, where=f"{path}: outputs")

    # fixed settings and end time
    fixed = doc.get("set") or {}
    if not isinstance(fixed, dict):
        raise err("set", f"expected a mapping unit.param -> value, got {short(fixed)}")
    for k, v in fixed.items():
        if k not in fs.params and not structure.is_setting(fs, k):
            raise err(f"set.{k}", f"unknown parameter (allowed: {', '.join(fs.params)})")
        if any(var.param == k for var in variables):
            raise err(f"set.{k}", "is also a sweep variable")
        if not (is_number(v) or isinstance(v, str)):
            raise err(f"set.{k}", f"expected a number or a string with a unit, got {short(v)}")
    settings, params = structure.split(fs, fixed)
    fs = structure.with_settings(fs, settings, f"{path}: set:")
    for k, v in params.items():
        set_or_raise(fs, k, v, f"{path}: set.{k}")
    t_end = None
    if "t_end" in doc:
        t_end = parse_time(doc["t_end"], f"{path}: t_end")
        if not t_end > 0:
            raise err("t_end", f"{short(doc['t_end'])}: expected an end time > 0 (e.g. 60 min)")

    # points
    pdoc = doc["points"]
    if not isinstance(pdoc, list) or not pdoc:
        raise err("points", "expected a non-empty list of {name: ..., <variable>: value, ...}")
    points, seen = [], set()
    allowed = list(_POINT_LABELS) + [v.name for v in variables]
    for i, p in enumerate(pdoc):
        if not isinstance(p, dict):
            raise err(f"points[{i}]", f"expected a mapping with keys {', '.join(allowed)}, got {short(p)}")
        pname = str(p.get("name", f"P{i + 1}"))
        key = f"points[{i}] ({pname})"
        if pname in seen:
            raise err(key, f"duplicate point name '{pname}'")
        seen.add(pname)
        for k in p:
            if k not in allowed:
                raise err(f"{key}.{k}", f"unknown key (allowed: {', '.join(allowed)})")
        point = {"name": pname, "kind": str(p.get("kind", ""))}
        for v in variables:
            if v.name not in p:
                raise err(f"{key}.{v.name}", f"missing (every point gives every variable: "
                                             f"{', '.join(x.name for x in variables)})")
            value = p[v.name]
            if v.setting:  # checked once per value below, by building the flowsheet with it
                point[v.name] = value
                continue
            point[v.name] = _edge_value(fs, v, value, f"{path}: {key}.{v.name}")
            set_or_raise(fs, v.param, value if isinstance(value, str) else v.quantity(point[v.name]),
                         f"{path}: {key}.{v.name}", shown=value)
        points.append(point)
    for v in variables:
        if v.setting:
            for value in dict.fromkeys(structure.setting_text(p[v.name]) for p in points):
                structure.with_settings(fs, {v.param: value}, f"{path}: points: {v.name} =")
    return Sweep(path=path, name=name, description=str(doc.get("description", "")), scene=scene,
                 variables=variables, points=points, outputs=outputs, set=dict(fixed), t_end=t_end)


def _quantity(value, where: str, expected: str) -> tuple[float, str] | None:
    """(number, unit) of a string such as "60 degC"; None for a plain number. ConfigError names `expected`."""
    if is_number(value):
        return None
    if isinstance(value, str):
        try:
            return split(value, where)
        except ConfigError:
            pass
    raise ConfigError(f"{where} = {short(value)}: expected {expected}")


def _edge_value(fs: Flowsheet, v: Variable, value, where: str) -> float:
    """A point value in the variable's edge unit (numbers are taken as given; strings may carry a unit)."""
    si_unit = fs.spec(v.param)["unit"]
    q = _quantity(value, where, f"a number in {v.unit or si_unit} or a number with a unit")
    if q is None:
        return float(value)
    try:
        si = to_si(q[0], si_unit, v.param, q[1])
    except ConfigError as e:
        raise ConfigError(f"{where} = {short(value)}: {' '.join(str(e).split())}") from None
    a, b = affine(v.unit, si_unit, v.param)
    return (si - a) / b


def run_sweep_file(path: str | os.PathLike, **kwargs):
    """``load_sweep(path).run(**kwargs)``."""
    return load_sweep(path).run(**kwargs)
