"""Operating variables (axes) and constraints on outputs."""
from __future__ import annotations

import math
import re
from dataclasses import dataclass
from typing import Any, Mapping

import numpy as np

from .. import _core, structure, sweep
from ..flowsheet import Flowsheet
from ..quantity import affine, parse_time, split as split_quantity

ConfigError = _core.ConfigError
SolverError = _core.SolverError


# Most points on one axis of a map (a 401 x 401 grid is already 160,801 simulations).
MAX_AXIS_POINTS = 401

T_END = "t_end"  # pseudo-parameter of optimize(): the end time of the run (batch time)
_OPS = (">=", "<=", ">", "<")


@dataclass(frozen=True)
class Axis:
    """One operating variable: ``values`` in the edge ``unit`` and ``si`` (what the simulation gets)."""

    param: str
    unit: str
    values: np.ndarray
    si: np.ndarray
    description: str = ""
    si_unit: str = ""
    settings: tuple = ()  # a unit setting's axis: the value each point gets (10, "constant"); rebuilds per value
    labels: tuple = ()    # a categorical setting: the names; ``values`` are then their positions 0, 1, ...

    def point(self, i: int):
        """The value the flowsheet gets at position ``i`` of the axis: the setting's value, or SI."""
        return self.settings[i] if self.settings else float(self.si[i])

    @property
    def column(self) -> str:
        """Column name of the edge values in data frames, e.g. ``inlet.T [degC]``."""
        return f"{self.param} [{self.unit}]" if self.unit else self.param

    @property
    def label(self) -> str:
        """Axis label for plots."""
        name = f"{self.description} ({self.param})" if self.description else self.param
        return f"{name} / {self.unit}" if self.unit else name

    @property
    def lo(self) -> float:
        return float(self.values[0])

    @property
    def hi(self) -> float:
        return float(self.values[-1])

    def to_si(self, value) -> np.ndarray:
        a, b = self._affine
        return a + b * np.asarray(value, dtype=float)

    def from_si(self, si) -> np.ndarray:
        a, b = self._affine
        return (np.asarray(si, dtype=float) - a) / b

    @property
    def _affine(self) -> tuple[float, float]:
        # edge units are affine in SI (degC); recover a, b from two points of the axis
        v, s = self.values, self.si
        if len(v) >= 2 and v[-1] != v[0]:
            b = (s[-1] - s[0]) / (v[-1] - v[0])
            return float(s[0] - b * v[0]), float(b)
        return float(s[0] - v[0]), 1.0


def param_si_unit(fs: Flowsheet, param: str) -> str:
    return "s" if param == T_END else fs.spec(param)["unit"]


def _param_affine(fs: Flowsheet, param: str, unit: str, where: str) -> tuple[float, float]:
    si_unit = param_si_unit(fs, param)
    try:
        return affine(unit, si_unit, param)
    except ConfigError as e:
        raise ConfigError(f"{where}: unit '{unit}' does not fit {param} (SI unit {si_unit}): "
                          f"{' '.join(str(e).split())}") from None


def _parse_spec(spec, where: str, with_n: bool):
    """(param, unit, lo, hi[, n]) or (param, unit, values) from a tuple, a dict entry or a string."""
    if isinstance(spec, Axis):
        return spec.param, spec.unit, list(spec.values)
    given = spec
    if isinstance(spec, str):
        parts = spec.split(":")
        want = 5 if with_n else 4
        if len(parts) != want:
            form = "unit.param:unit:lo:hi:n" if with_n else "unit.param:unit:lo:hi"
            raise ConfigError(f"{where} = '{spec}': expected {form} (e.g. inlet.T:degC:40:80"
                              f"{':15' if with_n else ''})")
        spec = [parts[0].strip(), parts[1].strip()] + parts[2:]
        try:
            spec[2:4] = [float(spec[2]), float(spec[3])]
            if with_n:
                spec[4] = int(spec[4])
        except ValueError:
            raise ConfigError(f"{where}: expected numbers for lo and hi" + (" and an integer n" if with_n else "")
                              + f", got {':'.join(parts[2:])}") from None
    if not isinstance(spec, (tuple, list)) or len(spec) < 3 or not isinstance(spec[0], str):
        form = "(param, unit, lo, hi, n) or (param, unit, [values])" if with_n else "(param, unit, lo, hi)"
        raise ConfigError(f"{where} = {spec!r}: expected {form}")
    param, unit = spec[0], spec[1] if spec[1] is not None else ""
    if not isinstance(unit, str):
        raise ConfigError(f"{where} = {spec!r}: the unit must be a string ('' for SI)")
    rest = list(spec[2:])
    if len(rest) == 1 and np.ndim(rest[0]) == 1:
        return param, unit, [float(v) for v in rest[0]]
    if with_n:
        if len(rest) != 3:
            raise ConfigError(f"{where} = {spec!r}: expected (param, unit, lo, hi, n)")
        lo, hi, n = rest
        if not isinstance(n, (int, np.integer)) or isinstance(n, bool) or not 1 <= n <= MAX_AXIS_POINTS:
            raise ConfigError(f"{where} = {given!r}: n = {n!r}: expected an integer 1 <= n <= {MAX_AXIS_POINTS} "
                              "(points per axis)")
        if not (math.isfinite(float(lo)) and math.isfinite(float(hi))) or float(hi) < float(lo):
            raise ConfigError(f"{where} = {given!r}: expected finite lo <= hi")
        return param, unit, list(np.linspace(float(lo), float(hi), int(n)))
    if len(rest) != 2:
        raise ConfigError(f"{where} = {spec!r}: expected (param, unit, lo, hi)")
    lo, hi = float(rest[0]), float(rest[1])
    if not (math.isfinite(lo) and math.isfinite(hi)) or hi <= lo:
        raise ConfigError(f"{where} = {spec!r}: expected finite lo < hi")
    return param, unit, [lo, hi]


def _list_axis(fs: Flowsheet, spec: str, where: str) -> Axis | tuple:
    """``"name=v1,v2,..."``: a unit setting's axis (``particles.classes=10,20,40``, ``bed.aggregation=kapur,sum``;
    every value checked by building the flowsheet with it), or for a parameter ``(param, unit, [values])`` (the
    values numbers in one unit: ``inlet.T=40 degC,60 degC``)."""
    name, _, text = spec.partition("=")
    name = name.strip()
    raw = [v.strip() for v in text.split(",")]
    if not name or not all(raw):
        raise ConfigError(f"{where} = '{spec}': expected unit.name=v1,v2,... (e.g. particles.classes=10,20,40)")
    if len(raw) > MAX_AXIS_POINTS:
        raise ConfigError(f"{where}: {name}: {len(raw)} values: expected at most {MAX_AXIS_POINTS} points per axis")
    if len(set(raw)) != len(raw):
        raise ConfigError(f"{where} = '{spec}': a value is given twice")
    if not structure.is_setting(fs, name, raw[0]):
        parts = []
        for v in raw:
            try:
                parts.append(split_quantity(v, where))
            except ConfigError:
                raise ConfigError(f"{where}: {name} = '{v}': expected a number with an optional unit ({name} is a "
                                  "parameter; a list of names is for a unit setting)") from None
        if len({u for _, u in parts}) != 1:
            raise ConfigError(f"{where} = '{spec}': give every value in the same unit")
        return name, parts[0][1], [x for x, _ in parts]
    for v in raw:  # as the scene loader checks it, with the value named
        structure.with_settings(fs, {name: v}, where)
    ss = structure.setting_spec(fs, name)
    desc = ss.get("description", "") if ss else ""
    if ss is not None and ss["type"] in ("integer", "number"):
        si = np.array([float(structure.si_text(fs, name, v, where)) for v in raw])
        parts = [split_quantity(v, where) for v in raw]
        if len({u for _, u in parts}) != 1:
            raise ConfigError(f"{where} = '{spec}': give every value in the same unit")
        values = np.array([x for x, _ in parts])
        if values.size > 1 and not np.all(np.diff(values) > 0):
            raise ConfigError(f"{where}: {name}: expected increasing values, got {raw}")
        return Axis(name, parts[0][1], values, si, desc, structure.setting_si_unit(ss) if ss else "",
                    settings=tuple(int(v) if ss["type"] == "integer" else v for v in raw))
    pos = np.arange(len(raw), dtype=float)
    return Axis(name, "", pos, pos, desc, "", settings=tuple(raw), labels=tuple(raw))


def make_axis(fs: Flowsheet, spec, where: str = "axis", *, with_n: bool = True, allow_t_end: bool = False) -> Axis:
    """An :class:`Axis` from ``(param, unit, lo, hi, n)``, ``(param, unit, [values])``, ``"param:unit:lo:hi:n"``
    or ``"name=v1,v2,..."`` (a unit setting: ``particles.classes=10,20,40``, a categorical one
    ``bed.aggregation=kapur,sum``; or a parameter's values in one unit); checks the parameter, the unit and the
    parameter's bounds, a setting's values by building the flowsheet with each. Raises ConfigError naming
    ``where``."""
    if isinstance(spec, str) and "=" in spec:
        listed = _list_axis(fs, spec, where)
        if isinstance(listed, Axis):
            return listed
        spec = listed
    param, unit, values = _parse_spec(spec, where, with_n)
    if param == T_END and allow_t_end:
        desc, lower, upper = "end time of the run", 0.0, math.inf
    elif param not in fs.params:
        extra = f"{T_END}, " if allow_t_end else ""
        raise ConfigError(f"{where}: unknown parameter '{param}' of scene '{fs.name}' "
                          f"(allowed: {extra}{', '.join(fs.params)})")
    else:
        s = fs.spec(param)
        desc, lower, upper = s.get("description", ""), s["lower"], s["upper"]
        if s.get("input"):
            raise ConfigError(f"{where}: {param} is driven by a time-dependent input of scene '{fs.name}' "
                              f"(inputs: {param}); every point would run the input, not the axis values: vary "
                              "another parameter, or remove the input from the scene")
    a, b = _param_affine(fs, param, unit, where)
    v = np.asarray(values, dtype=float)
    if v.size > MAX_AXIS_POINTS:
        raise ConfigError(f"{where}: {param}: {v.size} values: expected at most {MAX_AXIS_POINTS} points per axis")
    if v.size == 0 or (v.size > 1 and not np.all(np.diff(v) > 0)):
        raise ConfigError(f"{where}: {param}: expected increasing values, got {v.tolist()}")
    si = a + b * v
    bad = (si < lower) | (si > upper) | ~np.isfinite(si)
    if param == T_END:
        bad |= si <= 0
    if bad.any():
        raise ConfigError(f"{where}: {param} = {v[bad][0]:g} {unit}: outside the bounds "
                          f"{lower:g} <= {param} <= {upper:g} {param_si_unit(fs, param)}")
    if param != T_END:
        # a value the flowsheet refuses although within the bounds (a link target, which follows its source; a
        # link source its followers cannot start from) would fail at every point after the runs: refuse it now
        probe = fs.clone()
        for value in dict.fromkeys([float(si[0]), float(si[-1])]):
            try:
                probe.set(param, value)
            except ConfigError as e:
                shown = f"{(value - a) / b:g} {unit}".strip()
                raise ConfigError(f"{where}: {param} = {shown}: {' '.join(str(e).split())}") from None
    return Axis(param, unit, v, si, desc, param_si_unit(fs, param))


def fixed_flowsheet(flowsheet: Flowsheet, fixed: Mapping[str, float | str] | None,
                    t_end: float | str | None) -> Flowsheet:
    """A clone with ``fixed`` applied (the caller's flowsheet is never changed)."""
    fs = flowsheet.clone()
    settings, fixed = structure.split(fs, dict(fixed or {}))
    fs = structure.with_settings(fs, settings, "fixed:")
    for k, v in fixed.items():
        if k not in fs.params:
            raise ConfigError(f"fixed: unknown parameter '{k}' of scene '{fs.name}' (allowed: {', '.join(fs.params)})")
        sweep.file.set_or_raise(fs, k, v, f"fixed.{k}")
    if t_end is not None:
        fs.set_t_end(parse_time(t_end, "t_end"))
    return fs


def map_axes(flowsheet: Flowsheet, x, y, fixed: Mapping[str, float | str] | None,
             t_end: float | str | None) -> tuple[Flowsheet, Axis, Axis]:
    """The flowsheet with ``fixed`` applied and the two axes of a map over it."""
    fs = fixed_flowsheet(flowsheet, fixed, t_end)
    ax = make_axis(fs, x, "x")
    ay = make_axis(fs, y, "y")
    if ax.param == ay.param:
        raise ConfigError(f"x and y: both vary {ax.param}")
    if fixed and (ax.param in fixed or ay.param in fixed):
        raise ConfigError(f"fixed: {ax.param if ax.param in fixed else ay.param} is a variable of the map")
    return fs, ax, ay


def map_sim_kwargs(simulate: Mapping[str, Any] | None) -> dict:
    kw = {"n_out": 2}
    kw.update(simulate or {})
    if "t_out" in kw:
        kw.pop("n_out")
    return kw


# ------------------------------------------------------------------------------------------------
# constraints
# ------------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class Constraint:
    """``output op bound`` with op in >=, >, <=, <; the bound in the unit of the output (d50_um: µm)."""

    output: str
    op: str
    bound: float

    def __str__(self) -> str:
        return f"{self.output} {self.op} {self.bound:g}"

    @property
    def scale(self) -> float:
        return abs(self.bound) if self.bound != 0 else 1.0

    def margin(self, value) -> np.ndarray:
        """Signed distance to the bound relative to |bound|: >= 0 where met (> 0 for strict constraints), NaN
        where the value is NaN."""
        v = np.asarray(value, dtype=float)
        return ((v - self.bound) if self.op in (">=", ">") else (self.bound - v)) / self.scale

    def satisfied(self, value) -> np.ndarray:
        v = np.asarray(value, dtype=float)
        with np.errstate(invalid="ignore"):
            out = {">=": v >= self.bound, ">": v > self.bound, "<=": v <= self.bound, "<": v < self.bound}[self.op]
        return out & np.isfinite(v)


_CONSTRAINT_RE = re.compile(r"^\s*([A-Za-z_][\w.]*)\s*(>=|<=|>|<)\s*([-+0-9.eE]+)\s*$")


def parse_constraints(constraints) -> list[Constraint]:
    """Constraints from ``{"d50_um": (">=", 400)}``, ``["d50_um>=400", ...]`` or Constraint objects."""
    if constraints is None:
        return []
    if isinstance(constraints, (str, Constraint)):
        constraints = [constraints]
    items = list(constraints.items()) if isinstance(constraints, Mapping) else list(constraints)
    out = []
    for c in items:
        if isinstance(c, Constraint):
            out.append(c)
            continue
        if isinstance(c, str):
            m = _CONSTRAINT_RE.match(c)
            if not m:
                raise ConfigError(f"constraint '{c}': expected OUTPUT OP NUMBER with OP one of {', '.join(_OPS)} "
                                  f"(e.g. d50_um>=400)")
            bound = float(m.group(3))
            if not math.isfinite(bound):
                raise ConfigError(f"constraint '{c}': bound {m.group(3)} is not a finite number")
            out.append(Constraint(m.group(1), m.group(2), bound))
            continue
        if isinstance(c, tuple) and len(c) == 2 and isinstance(c[0], str):
            name, rule = c
            if (isinstance(rule, (tuple, list)) and len(rule) == 2 and rule[0] in _OPS
                    and isinstance(rule[1], (int, float)) and math.isfinite(rule[1])):
                out.append(Constraint(name, rule[0], float(rule[1])))
                continue
            raise ConfigError(f"constraint {name}: {rule!r}: expected (op, bound) with op one of {', '.join(_OPS)}")
        raise ConfigError(f"constraint {c!r}: expected 'OUTPUT OP NUMBER', (output, (op, bound)) or a Constraint")
    return out
