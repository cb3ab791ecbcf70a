"""Design space: contour maps of summary outputs over two operating variables, the feasible window of constraints on
outputs, constrained optimization with NLopt, and a probabilistic design space (paper 001, section 4.3, Figs. 17-20).

Operating variables are given as ``(param, unit, lo, hi, n)`` (contour axes), ``(param, unit, lo, hi)``
(optimization variables) or the same as a string ``"inlet.T:degC:40:80:15"``; values are in the given edge unit,
the simulations run in SI. Outputs are summary keys (``d50_um``, ``bed_moisture_wet``, ... as in summary.json) or
state/output names (final value). Constraints are ``{"d50_um": (">=", 400), "bed_moisture_wet": ("<", 0.04)}`` or
strings ``"d50_um>=400"``, bounds in the unit of the output.

Python::

    import granuflow as gf
    from granuflow import design_space as ds

    fs = gf.load("flowsheets/stoeckl_gf25_batch.yaml")
    grid = ds.contour_map(fs, x=("inlet.T", "degC", 40, 80, 15), y=("nozzle.mdot", "g/min", 60, 120, 15),
                          outputs=["d50_um", "bed_moisture_wet"], workers=2)
    grid["d50_um"]                       # (ny, nx) array; grid.x.values, grid.y.values in degC and g/min
    win = ds.feasible_window(grid, {"d50_um": (">=", 400), "bed_moisture_wet": ("<", 0.04)})
    win.mask, win.outline                # boolean map; closed polygons (degC, g/min) of the window
    ds.plot_contour(grid, "d50_um", "d50.png", window=win)

    opt = ds.optimize(fs, objective="nozzle.mdot", maximize=True,
                      variables=[("nozzle.mdot", "g/min", 60, 120), ("inlet.T", "degC", 40, 80)],
                      constraints=["d50_um>=400", "bed_moisture_wet<0.04"], algorithm="LN_COBYLA")
    opt.x, opt.constraints, opt.n_simulations, opt.nlopt_result

    pmap = ds.probabilistic_design_space(fs, x=..., y=..., constraints=..., params=["bed.ln_beta0", "bed.X_cr"],
                                         covariance=[[0.15**2, 0], [0, 0.005**2]], method="linear")
    pmap.probability                     # P(all constraints met), (ny, nx)

Every function that simulates takes ``workers``, ``executor`` (``"threads"``, ``"serial"``, a
``distributed.Client`` or an executor object, see :mod:`granuflow.sweep`) and ``progress``, and runs through
:func:`granuflow.sweep.run_sweep` or its executors. Only the final state matters here, so runs use ``n_out=2``
(outputs are interpolated: the values are identical to a default run).
"""
from __future__ import annotations

import math
import re
import time
from dataclasses import dataclass, field
from typing import Any, Mapping, Sequence

import numpy as np

from . import _core, sweep
from .flowsheet import Flowsheet

ConfigError = _core.ConfigError
# Most points on one axis of a map (a 401 x 401 grid is already 160,801 simulations).
MAX_AXIS_POINTS = 401
SolverError = _core.SolverError

T_END = "t_end"  # pseudo-parameter of optimize(): the end time of the run (batch time)
_OPS = (">=", "<=", ">", "<")
_DISPLAY = {  # output -> (label, display unit, factor)
    "d10_um": ("d10,3", "µm", 1.0), "d50_um": ("d50,3", "µm", 1.0), "d90_um": ("d90,3", "µm", 1.0),
    "bed_moisture_wet": ("bed moisture (wet basis)", "wt%", 100.0),
    "bed_moisture": ("bed moisture (dry basis)", "wt% d.b.", 100.0),
    "T_gas_out_K": ("gas outlet temperature", "°C", None), "T_bed_K": ("bed temperature", "°C", None),
}


# ------------------------------------------------------------------------------------------------
# operating variables
# ------------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class Axis:
    """One operating variable: ``values`` in the edge ``unit`` and ``si`` (what the simulation gets)."""

    param: str
    unit: str
    values: np.ndarray
    si: np.ndarray
    description: str = ""

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


def _si_unit(fs: Flowsheet, param: str) -> str:
    return "s" if param == T_END else fs.spec(param)["unit"]


def _affine(fs: Flowsheet, param: str, unit: str, where: str) -> tuple[float, float]:
    si_unit = _si_unit(fs, param)
    try:
        return sweep._affine(unit, si_unit, param)
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


def make_axis(fs: Flowsheet, spec, where: str = "axis", *, with_n: bool = True, allow_t_end: bool = False) -> Axis:
    """An :class:`Axis` from ``(param, unit, lo, hi, n)``, ``(param, unit, [values])`` or ``"param:unit:lo:hi:n"``;
    checks the parameter, the unit and the parameter's bounds. Raises ConfigError naming ``where``."""
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
    a, b = _affine(fs, param, unit, where)
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
                          f"{lower:g} <= {param} <= {upper:g} {_si_unit(fs, param)}")
    return Axis(param, unit, v, si, desc)


def _fixed_flowsheet(flowsheet: Flowsheet, fixed: Mapping[str, float | str] | None,
                     t_end: float | str | None) -> Flowsheet:
    """A clone with ``fixed`` applied (the caller's flowsheet is never changed)."""
    fs = flowsheet.clone()
    for k, v in (fixed or {}).items():
        if k not in fs.params:
            raise ConfigError(f"fixed: unknown parameter '{k}' of scene '{fs.name}' (allowed: {', '.join(fs.params)})")
        sweep._set_or_raise(fs, k, v, f"fixed.{k}")
    if t_end is not None:
        fs.set_t_end(sweep._parse_time(t_end, "t_end"))
    return fs


def _map_axes(flowsheet: Flowsheet, x, y, fixed: Mapping[str, float | str] | None,
              t_end: float | str | None) -> tuple[Flowsheet, Axis, Axis]:
    """The flowsheet with ``fixed`` applied and the two axes of a map over it."""
    fs = _fixed_flowsheet(flowsheet, fixed, t_end)
    ax = make_axis(fs, x, "x")
    ay = make_axis(fs, y, "y")
    if ax.param == ay.param:
        raise ConfigError(f"x and y: both vary {ax.param}")
    if fixed and (ax.param in fixed or ay.param in fixed):
        raise ConfigError(f"fixed: {ax.param if ax.param in fixed else ay.param} is a variable of the map")
    return fs, ax, ay


def _sim_kwargs(simulate: Mapping[str, Any] | None) -> dict:
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


# ------------------------------------------------------------------------------------------------
# contour maps
# ------------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class ContourGrid:
    """Outputs over a grid of two operating variables. ``values[o]`` and ``status`` have shape (ny, nx): row i is
    ``y.values[i]``, column j is ``x.values[j]`` (as ``matplotlib.contourf(x.values, y.values, values[o])``)."""

    x: Axis
    y: Axis
    outputs: tuple
    values: dict
    status: np.ndarray
    message: np.ndarray
    scene: str
    fixed: dict = field(default_factory=dict)
    t_end_s: float = math.nan
    wall_time_s: float = math.nan
    solve_time_s: float = math.nan

    def __getitem__(self, output: str) -> np.ndarray:
        try:
            return self.values[output]
        except KeyError:
            raise KeyError(f"{output!r}: not an output of this grid ({', '.join(self.outputs)})") from None

    @property
    def shape(self) -> tuple[int, int]:
        return len(self.y.values), len(self.x.values)

    @property
    def ok(self) -> np.ndarray:
        return self.status == sweep.STATUS_OK

    @property
    def n_simulations(self) -> int:
        return int(self.status.size)

    @property
    def simulations_per_s(self) -> float:
        return self.n_simulations / self.wall_time_s if self.wall_time_s > 0 else math.nan

    def to_dataframe(self):
        """Tidy table, one row per grid point: both variables in their edge units and SI, the outputs, status."""
        import pandas as pd

        X, Y = np.meshgrid(self.x.values, self.y.values)
        Xs, Ys = np.meshgrid(self.x.si, self.y.si)
        data = {self.x.column: X.ravel(), self.y.column: Y.ravel(), self.x.param: Xs.ravel(),
                self.y.param: Ys.ravel()}
        data.update({o: self.values[o].ravel() for o in self.outputs})
        data["status"] = self.status.ravel()
        data["message"] = self.message.ravel()
        df = pd.DataFrame(data)
        df.attrs.update({"scene": self.scene, "x": self.x.param, "y": self.y.param, "fixed": dict(self.fixed),
                         "t_end_s": self.t_end_s, "outputs": list(self.outputs)})
        return df


def _grid_points(x: Axis, y: Axis) -> list[dict]:
    return [{x.param: float(xs), y.param: float(ys)} for ys in y.si for xs in x.si]


def contour_map(flowsheet: Flowsheet, x, y, outputs: Sequence[str] = ("d50_um",), *,
                fixed: Mapping[str, float | str] | None = None, t_end: float | str | None = None,
                workers: int | None = None, executor: str | Any = "threads", progress: bool | None = None,
                simulate: Mapping[str, Any] | None = None) -> ContourGrid:
    """Simulate every point of the grid ``x`` by ``y`` and collect ``outputs`` at the end time.

    Parameters
    ----------
    flowsheet : Flowsheet
        The scene; not modified (``fixed`` is applied to a clone).
    x, y : tuple or str
        ``(param, unit, lo, hi, n)``, ``(param, unit, [values])`` or ``"param:unit:lo:hi:n"``.
    outputs : sequence of str
        Summary keys or state/output names.
    fixed : mapping, optional
        Other parameters for every point, SI floats or strings with a unit (``{"inlet.V_dot": "700 m3/h"}``).
    t_end : float or str, optional
        End time (s or ``"60 min"``); default the scene's.
    workers, executor, progress, simulate
        As :func:`granuflow.sweep.run_sweep`.

    Returns
    -------
    ContourGrid
        Failed points hold NaN and their status/message.
    """
    fs, ax, ay = _map_axes(flowsheet, x, y, fixed, t_end)
    outputs = sweep._check_outputs(fs, list(outputs))
    t0 = time.perf_counter()
    df = sweep.run_sweep(fs, _grid_points(ax, ay), outputs, workers=workers, progress=progress, executor=executor,
                         simulate=_sim_kwargs(simulate), desc="contour map")
    wall = time.perf_counter() - t0
    shape = (len(ay.values), len(ax.values))
    return ContourGrid(
        x=ax, y=ay, outputs=tuple(outputs),
        values={o: df[o].to_numpy(dtype=float).reshape(shape) for o in outputs},
        status=df["status"].to_numpy(dtype=object).reshape(shape),
        message=df["message"].to_numpy(dtype=object).reshape(shape),
        scene=fs.name, fixed=dict(fixed or {}), t_end_s=fs.t_end, wall_time_s=wall,
        solve_time_s=float(np.nansum(df["solve_time_s"].to_numpy(dtype=float))))


# ------------------------------------------------------------------------------------------------
# feasible window
# ------------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class FeasibleWindow:
    """Where every constraint is met on a grid.

    ``mask`` (ny, nx): all constraints met at the grid point (failed points: False). ``margins[str(c)]``: the
    relative margin of each constraint (>= 0 where met); ``margin``: their minimum. ``outline``: closed polygons
    ((k, 2) arrays of (x, y) in edge units) around the region where every margin, interpolated bilinearly between
    the grid points (on a grid 8 times finer), is >= 0; ``boundaries[str(c)]``: the lines where each constraint
    is exactly met."""

    x: Axis
    y: Axis
    constraints: tuple
    mask: np.ndarray
    margins: dict
    margin: np.ndarray
    outline: list
    boundaries: dict

    @property
    def fraction(self) -> float:
        """Fraction of the grid points inside the window."""
        return float(self.mask.mean()) if self.mask.size else math.nan

    @property
    def empty(self) -> bool:
        return not self.mask.any()

    def ranges(self) -> dict:
        """Smallest and largest x and y of the feasible grid points (edge units); None if the window is empty."""
        if self.empty:
            return {self.x.column: None, self.y.column: None}
        X, Y = np.meshgrid(self.x.values, self.y.values)
        return {self.x.column: (float(X[self.mask].min()), float(X[self.mask].max())),
                self.y.column: (float(Y[self.mask].min()), float(Y[self.mask].max()))}

    def to_dataframe(self):
        """One row per grid point: the variables (edge units), each constraint's margin, ``feasible``."""
        import pandas as pd

        X, Y = np.meshgrid(self.x.values, self.y.values)
        data = {self.x.column: X.ravel(), self.y.column: Y.ravel()}
        data.update({f"margin[{k}]": v.ravel() for k, v in self.margins.items()})
        data["feasible"] = self.mask.ravel()
        return pd.DataFrame(data)

    def outline_dataframe(self):
        """The outline as a table: ``polygon`` index and the vertices (x, y in edge units)."""
        import pandas as pd

        rows = [(k, float(p[0]), float(p[1])) for k, poly in enumerate(self.outline) for p in poly]
        return pd.DataFrame(rows, columns=["polygon", self.x.column, self.y.column])


def _filled_polygons(x, y, z, lower: float) -> list[np.ndarray]:
    """Closed polygons (outer boundaries and holes, each its own ring) of {z >= lower}, NaN excluded."""
    import contourpy

    zm = np.ma.masked_invalid(np.asarray(z, dtype=float))
    if zm.count() == 0 or len(x) < 2 or len(y) < 2:
        return []
    gen = contourpy.contour_generator(np.asarray(x, float), np.asarray(y, float), zm, fill_type="OuterOffset")
    hi = max(float(zm.max()), lower) + 1.0
    points, offsets = gen.filled(lower, hi)
    rings = []
    for pts, offs in zip(points, offsets):
        for a, b in zip(offs[:-1], offs[1:]):
            rings.append(np.asarray(pts[a:b], dtype=float))
    return rings


def _lines(x, y, z, level: float) -> list[np.ndarray]:
    import contourpy

    zm = np.ma.masked_invalid(np.asarray(z, dtype=float))
    if zm.count() == 0 or len(x) < 2 or len(y) < 2:
        return []
    gen = contourpy.contour_generator(np.asarray(x, float), np.asarray(y, float), zm, line_type="Separate")
    return [np.asarray(seg, dtype=float) for seg in gen.lines(level)]


def _refine(v: np.ndarray, factor: int = 8) -> np.ndarray:
    if len(v) < 2:
        return np.asarray(v, dtype=float)
    parts = [np.linspace(a, b, factor, endpoint=False) for a, b in zip(v[:-1], v[1:])]
    return np.concatenate(parts + [v[-1:]])


def _bilinear(x, y, z, xf, yf) -> np.ndarray:
    """z (ny, nx) on (x, y) interpolated bilinearly at (xf, yf); NaN cells stay NaN."""
    if len(x) < 2 or len(y) < 2:
        return np.asarray(z, dtype=float)
    from scipy.interpolate import RegularGridInterpolator

    f = RegularGridInterpolator((np.asarray(y, float), np.asarray(x, float)), np.asarray(z, dtype=float),
                                method="linear")
    Yf, Xf = np.meshgrid(yf, xf, indexing="ij")
    return f(np.stack([Yf.ravel(), Xf.ravel()], axis=1)).reshape(len(yf), len(xf))


def feasible_window(grid, constraints) -> FeasibleWindow:
    """The feasible window of ``constraints`` on a :class:`ContourGrid` (or anything with ``x``, ``y`` and
    ``values``: a :class:`ProbabilityMap` gives the nominal window). Every constraint's output must be on the grid.
    """
    cons = parse_constraints(constraints)
    if not cons:
        raise ConfigError("feasible_window: give at least one constraint (e.g. {'d50_um': ('>=', 400)})")
    for c in cons:
        if c.output not in grid.values:
            raise ConfigError(f"constraint {c}: '{c.output}' is not an output of the grid "
                              f"(outputs: {', '.join(grid.values)}); add it to contour_map(outputs=...)")
    shape = (len(grid.y.values), len(grid.x.values))
    mask = np.ones(shape, dtype=bool)
    margins = {}
    for c in cons:
        v = grid.values[c.output]
        mask &= c.satisfied(v)
        margins[str(c)] = c.margin(v)
    margin = np.min(np.stack(list(margins.values())), axis=0)
    # the outline: each margin interpolated (bilinearly) onto a grid 8 times finer, then their minimum, so that
    # the window's corners where two constraints cross are resolved rather than cut across a coarse cell
    xf, yf = _refine(grid.x.values), _refine(grid.y.values)
    fine = np.min(np.stack([_bilinear(grid.x.values, grid.y.values, m, xf, yf) for m in margins.values()]), axis=0)
    outline = _filled_polygons(xf, yf, fine, 0.0)
    boundaries = {k: _lines(grid.x.values, grid.y.values, m, 0.0) for k, m in margins.items()}
    return FeasibleWindow(grid.x, grid.y, tuple(cons), mask, margins, margin, outline, boundaries)


# ------------------------------------------------------------------------------------------------
# plots (PNG files, as granuflow.plots)
# ------------------------------------------------------------------------------------------------
def _display(output: str, values):
    label, unit, factor = _DISPLAY.get(output, (output, "", 1.0))
    v = np.asarray(values, dtype=float)
    v = v - 273.15 if factor is None else v * factor
    return (f"{label} / {unit}" if unit else label), v


def _display_bound(c: Constraint) -> str:
    label, unit, factor = _DISPLAY.get(c.output, (c.output, "", 1.0))
    b = c.bound - 273.15 if factor is None else c.bound * factor
    op = {">=": "≥", "<=": "≤"}.get(c.op, c.op)
    return f"{label} {op} {b:g} {unit}".strip()


def _axes(ax, path, figsize=(6.4, 4.8)):
    """The axes to draw on: ``ax``; else a new figure, without pyplot when it only goes to a file (so that saving
    PNGs never changes the backend of a notebook), with pyplot otherwise (shown inline)."""
    if ax is not None:
        return ax.figure, ax, False
    if path:
        from matplotlib.figure import Figure

        fig = Figure(figsize=figsize)
        return fig, fig.add_subplot(), True
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=figsize)
    return fig, ax, True


def _finish(fig, ax, path, own: bool):
    if own:
        fig.tight_layout()
    if path:
        fig.savefig(path, dpi=110)
        return path
    return ax


def _draw_window(ax, window: FeasibleWindow, *, color="k", hatch="//", label="feasible window"):
    from matplotlib.patches import Polygon

    first = True
    for ring in window.outline:
        ax.add_patch(Polygon(ring, closed=True, fill=False, hatch=hatch, edgecolor=color, linewidth=1.6,
                             label=label if first else None))
        first = False


def plot_contour(grid: ContourGrid, output: str, path: str | None = None, *, ax=None, levels: int | Sequence = 12,
                 window: FeasibleWindow | None = None, title: str | None = None, cmap: str = "viridis",
                 mark_points: bool = False):
    """Filled contours of ``output`` over the grid with labelled contour lines (display units: µm, wt%, °C), the
    feasible ``window`` hatched and outlined if given. Saves a PNG at ``path`` (returns it), else draws on ``ax``
    (returns it)."""
    fig, ax, own = _axes(ax, path)
    label, z = _display(output, grid[output])
    zm = np.ma.masked_invalid(z)
    cf = ax.contourf(grid.x.values, grid.y.values, zm, levels=levels, cmap=cmap)
    cs = ax.contour(grid.x.values, grid.y.values, zm, levels=cf.levels, colors="k", linewidths=0.6)
    ax.clabel(cs, cs.levels[::2], fmt="%.3g", fontsize=7)
    fig.colorbar(cf, ax=ax, label=label)
    if window is not None:
        _draw_window(ax, window)
        ax.legend(loc="upper left", fontsize=8, framealpha=0.8)
    if mark_points:
        X, Y = np.meshgrid(grid.x.values, grid.y.values)
        ax.plot(X[~grid.ok], Y[~grid.ok], "rx", ms=5, label="failed")
    ax.set_xlabel(grid.x.label)
    ax.set_ylabel(grid.y.label)
    ax.set_title(title if title is not None else f"{label.split(' / ')[0]} after {grid.t_end_s / 60:g} min")
    return _finish(fig, ax, path, own)


def plot_feasible_window(window: FeasibleWindow, path: str | None = None, *, grid: ContourGrid | None = None,
                         background: str | None = None, ax=None, title: str | None = None):
    """Fig. 20 style: each constraint's boundary line (labelled), the feasible window hatched, the grid points
    inside it marked red; optionally filled contours of ``background`` (an output of ``grid``) underneath."""
    fig, ax, own = _axes(ax, path)
    if grid is not None and background is not None:
        label, z = _display(background, grid[background])
        cf = ax.contourf(grid.x.values, grid.y.values, np.ma.masked_invalid(z), levels=12, cmap="Greys", alpha=0.6)
        fig.colorbar(cf, ax=ax, label=label)
    colors = ["tab:blue", "tab:orange", "tab:green", "tab:purple", "tab:brown"]
    for k, c in enumerate(window.constraints):
        for n, seg in enumerate(window.boundaries[str(c)]):
            ax.plot(seg[:, 0], seg[:, 1], color=colors[k % len(colors)], lw=2,
                    label=_display_bound(c) if n == 0 else None)
    _draw_window(ax, window, color="tab:red")
    X, Y = np.meshgrid(window.x.values, window.y.values)
    ax.plot(X[window.mask], Y[window.mask], "o", color="tab:red", ms=3, label="feasible grid points")
    ax.plot(X[~window.mask], Y[~window.mask], "o", color="0.6", ms=2, label="infeasible grid points")
    ax.set_xlim(window.x.lo, window.x.hi)
    ax.set_ylim(window.y.lo, window.y.hi)
    ax.set_xlabel(window.x.label)
    ax.set_ylabel(window.y.label)
    ax.set_title(title if title is not None else "Design space: " + ", ".join(_display_bound(c)
                                                                              for c in window.constraints))
    ax.legend(loc="best", fontsize=7, framealpha=0.85)
    return _finish(fig, ax, path, own)


def plot_probability(pmap: "ProbabilityMap", path: str | None = None, *, ax=None, title: str | None = None,
                     levels: Sequence[float] = (0.5, 0.9)):
    """P(all constraints met) as filled contours with the ``levels`` (0.5, 0.9) drawn and labelled, and the nominal
    feasible window (mean parameters) dashed."""
    fig, ax, own = _axes(ax, path)
    cf = ax.contourf(pmap.x.values, pmap.y.values, pmap.probability, levels=np.linspace(0, 1, 11), cmap="RdYlGn",
                     vmin=0, vmax=1)
    fig.colorbar(cf, ax=ax, label="P(constraints met)")
    cs = ax.contour(pmap.x.values, pmap.y.values, pmap.probability, levels=list(levels), colors="k",
                    linewidths=[1.2, 2.0][:len(levels)] or 1.2)
    ax.clabel(cs, fmt=lambda v: f"P = {v:g}", fontsize=8)
    win = pmap.nominal_window
    for n, ring in enumerate(win.outline):
        ax.plot(np.r_[ring[:, 0], ring[:1, 0]], np.r_[ring[:, 1], ring[:1, 1]], "b--", lw=1.2,
                label="nominal window" if n == 0 else None)
    if win.outline:
        ax.legend(loc="upper left", fontsize=8, framealpha=0.8)
    ax.set_xlabel(pmap.x.label)
    ax.set_ylabel(pmap.y.label)
    ax.set_title(title if title is not None else
                 f"Probabilistic design space ({pmap.method}, {len(pmap.params)} uncertain parameters)")
    return _finish(fig, ax, path, own)


# ------------------------------------------------------------------------------------------------
# constrained optimization (NLopt)
# ------------------------------------------------------------------------------------------------
# algorithms that take inequality constraints themselves; AUGLAG* wrap a local algorithm and add them
_CONSTRAINED = {"LN_COBYLA", "LD_MMA", "LD_CCSAQ", "LD_SLSQP", "GN_ISRES", "GN_ORIG_DIRECT", "GN_ORIG_DIRECT_L",
                "GN_AGS", "AUGLAG", "AUGLAG_EQ", "LN_AUGLAG", "LN_AUGLAG_EQ", "LD_AUGLAG", "LD_AUGLAG_EQ"}
_NEEDS_LOCAL = {"AUGLAG", "AUGLAG_EQ", "LN_AUGLAG", "LN_AUGLAG_EQ", "LD_AUGLAG", "LD_AUGLAG_EQ", "G_MLSL",
                "G_MLSL_LDS", "GN_MLSL", "GN_MLSL_LDS", "GD_MLSL", "GD_MLSL_LDS"}
_C_SAFETY = 1e-6  # relative margin NLopt is asked to keep (solver noise at rtol 1e-6 is of that order)
_RESULTS = ("SUCCESS", "STOPVAL_REACHED", "FTOL_REACHED", "XTOL_REACHED", "MAXEVAL_REACHED", "MAXTIME_REACHED",
            "FAILURE", "INVALID_ARGS", "OUT_OF_MEMORY", "ROUNDOFF_LIMITED", "FORCED_STOP")


def _nlopt():
    try:
        import nlopt
    except ImportError:
        raise ImportError("granuflow.design_space.optimize needs NLopt's Python bindings: "
                          "apt-get install python3-nlopt") from None
    return nlopt


def nlopt_algorithms() -> dict:
    """NLopt's algorithms by name -> description, e.g. ``{"LN_COBYLA": "COBYLA (...)", ...}``. Prefixes: G global,
    L local; N derivative-free, D gradient-based (gradients by forward differences here)."""
    nlopt = _nlopt()
    names = [n for n in dir(nlopt) if re.match(r"^(G|L)[ND]?_[A-Z0-9_]+$", n) or n.startswith("AUGLAG")]
    return {n: nlopt.algorithm_name(getattr(nlopt, n)) for n in sorted(names)}


def _algorithm(name: str, role: str = "algorithm"):
    algos = nlopt_algorithms()
    if not isinstance(name, str) or name.upper() not in algos:
        local = ", ".join(n for n in algos if n.startswith("L"))
        glob = ", ".join(n for n in algos if n.startswith("G"))
        other = ", ".join(n for n in algos if n.startswith("A"))
        raise ConfigError(f"{role} = {name!r}: unknown NLopt algorithm (local: {local}; global: {glob}; "
                          f"augmented Lagrangian: {other})")
    return name.upper()


@dataclass(frozen=True)
class OptimizationResult:
    """The outcome of :func:`optimize`.

    ``x``: the optimum, variable -> value in its edge unit (``x_si`` in SI); ``value``: the objective there;
    ``outputs``: the simulated outputs there; ``constraints``: str(constraint) -> {"value", "margin", "met"};
    ``feasible``: all met; ``n_simulations``: simulations run (including finite-difference gradients);
    ``nlopt_result``: NLopt's result code as text (``XTOL_REACHED``, ``MAXEVAL_REACHED``, ... or the exception
    NLopt stopped with, e.g. ``ROUNDOFF_LIMITED``); ``history``: every evaluation as a DataFrame."""

    x: dict
    x_si: dict
    units: dict
    objective: str
    maximize: bool
    value: float
    outputs: dict
    constraints: dict
    feasible: bool
    n_simulations: int
    n_evaluations: int
    nlopt_result: str
    message: str
    algorithm: str
    local_algorithm: str | None
    wall_time_s: float
    history: Any = None

    def __repr__(self) -> str:
        xs = ", ".join(f"{k} = {v:.5g} {self.units[k]}".rstrip() for k, v in self.x.items())
        return (f"<OptimizationResult {self.algorithm}: {'max' if self.maximize else 'min'} {self.objective} = "
                f"{self.value:.6g} at {xs}; feasible={self.feasible}; {self.n_simulations} simulations; "
                f"{self.nlopt_result}>")


class _Problem:
    """Evaluations in scaled variables u in [0, 1]^n, cached (NLopt asks the objective and each constraint at the
    same point)."""

    def __init__(self, fs, axes, objective, maximize, constraints, outputs, sim_kwargs):
        self.fs, self.axes, self.objective, self.maximize = fs, axes, objective, maximize
        self.constraints, self.outputs, self.sim_kwargs = constraints, outputs, sim_kwargs
        self.cache: dict[tuple, dict] = {}
        self.rows: list[dict] = []
        self.n_sim = 0
        self.worst = -math.inf if maximize else math.inf

    def si(self, u) -> dict:
        return {a.param: float(a.si[0] + (a.si[-1] - a.si[0]) * min(max(float(ui), 0.0), 1.0))
                for a, ui in zip(self.axes, u)}

    def evaluate(self, u, kind: str = "point") -> dict:
        key = tuple(float(v) for v in u)
        hit = self.cache.get(key)
        if hit is not None:
            return hit
        xs = self.si(u)
        kw = dict(self.sim_kwargs)
        row: dict[str, Any] = {"kind": kind}
        for a in self.axes:
            row[a.column] = float(a.from_si(xs[a.param]))
        status, message, values = sweep.STATUS_OK, "", {}
        try:
            for p, v in xs.items():
                if p == T_END:
                    kw["t_end"] = v
                else:
                    self.fs.set(p, v)
            if self.outputs:
                self.n_sim += 1
                values = sweep._final_values(self.fs.simulate(**kw), self.outputs)
        except (SolverError, ConfigError) as e:
            status, message = sweep.STATUS_FAILED, " ".join(str(e).split())
            values = {o: math.nan for o in self.outputs}
        if self.objective in xs:
            axis = next(a for a in self.axes if a.param == self.objective)
            f = float(axis.from_si(xs[self.objective]))
        else:
            f = values.get(self.objective, math.nan)
        margins = [float(c.margin(values.get(c.output, math.nan))) for c in self.constraints]
        met = [bool(c.satisfied(values.get(c.output, math.nan))) for c in self.constraints]
        if math.isfinite(f):
            self.worst = min(self.worst, f) if self.maximize else max(self.worst, f)
        row.update(values)
        row.update({"objective": f, "feasible": all(met) and status == sweep.STATUS_OK, "status": status,
                    "message": message})
        rec = {"u": key, "f": f, "margins": margins, "met": met, "values": values, "status": status, "row": row}
        self.cache[key] = rec
        self.rows.append(row)
        return rec

    def f_for_nlopt(self, rec) -> float:
        """Objective as NLopt sees it: failures get the worst value seen, pushed further away."""
        f = rec["f"]
        if math.isfinite(f):
            return f
        w = self.worst if math.isfinite(self.worst) else 0.0
        return w - (abs(w) + 1.0) if self.maximize else w + (abs(w) + 1.0)

    @staticmethod
    def c_for_nlopt(rec, i) -> float:
        """Constraint i as NLopt wants it (<= 0 when met): minus the relative margin, shifted by _C_SAFETY so that
        a point NLopt ends on (active constraint) meets the constraint itself; failures count as violated."""
        m = rec["margins"][i]
        return _C_SAFETY - m if math.isfinite(m) else 1.0


def optimize(flowsheet: Flowsheet, objective: str, variables, constraints=None, *, maximize: bool = False,
             algorithm: str = "LN_COBYLA", local_algorithm: str | None = None, x0: Mapping[str, float] | None = None,
             fixed: Mapping[str, float | str] | None = None, t_end: float | str | None = None,
             xtol_rel: float = 1e-4, ftol_rel: float | None = None, maxeval: int = 200,
             maxtime: float | None = None, population: int | None = None, seed: int | None = 0,
             fd_step: float = 1e-3, simulate: Mapping[str, Any] | None = None) -> OptimizationResult:
    """Optimize ``objective`` over ``variables`` subject to ``constraints`` on outputs, with NLopt.

    Parameters
    ----------
    flowsheet : Flowsheet
        The scene; not modified.
    objective : str
        A variable (``"nozzle.mdot"``: the largest spray rate; ``"t_end"``: the shortest batch) or an output
        (summary key or state/output name).
    variables : sequence or mapping
        ``(param, unit, lo, hi)`` or ``"param:unit:lo:hi"`` per variable (or ``{param: (unit, lo, hi)}``);
        ``param`` may be ``"t_end"`` (the end time of the run). NLopt works in the variables scaled to [0, 1].
    constraints : mapping or sequence, optional
        ``{"d50_um": (">=", 400)}`` or ``["d50_um>=400", ...]``; passed to NLopt as inequality constraints on the
        relative margins (a strict ``<`` is handled as ``<=`` by the optimizer, checked strictly in the result).
    maximize : bool
        Maximize instead of minimize.
    algorithm : str
        Any NLopt algorithm by name: local ``LN_COBYLA`` (default), ``LD_SLSQP``, ``LD_MMA``, ...; global
        ``GN_ISRES``, ``GN_ORIG_DIRECT_L``, ``GN_AGS``, ...; with constraints only those that handle them or
        ``AUGLAG``/``LN_AUGLAG``/``LD_AUGLAG`` around ``local_algorithm``. ``LD_*``/``GD_*`` get gradients by
        forward differences of step ``fd_step`` (scaled units; one simulation per variable).
    local_algorithm : str, optional
        Subsidiary algorithm of AUGLAG* and MLSL (default ``LN_BOBYQA``, or ``LD_LBFGS`` for LD_AUGLAG/GD_MLSL).
    x0 : mapping, optional
        Start, variable -> value in its edge unit (default: the flowsheet's value, or mid-range if that is outside
        the bounds).
    fixed, t_end, simulate
        As :func:`contour_map`.
    xtol_rel, ftol_rel, maxeval, maxtime, population, seed
        NLopt stopping criteria; ``population`` for ISRES/CRS/ESCH/MLSL; ``seed`` for NLopt's random numbers.

    Returns
    -------
    OptimizationResult
        If NLopt stops with a point that is not feasible (or with an exception such as ROUNDOFF_LIMITED), the best
        feasible point evaluated is returned and ``message`` says so.
    """
    nlopt = _nlopt()
    algo = _algorithm(algorithm)
    cons = parse_constraints(constraints)
    local = None
    if algo in _NEEDS_LOCAL:
        default = "LD_LBFGS" if algo.startswith(("LD_", "GD_")) else "LN_BOBYQA"
        local = _algorithm(local_algorithm or default, "local_algorithm")
    elif local_algorithm is not None:
        raise ConfigError(f"local_algorithm = {local_algorithm!r}: only for AUGLAG* and *MLSL* algorithms "
                          f"(algorithm = {algo})")
    if cons and algo not in _CONSTRAINED:
        raise ConfigError(f"algorithm = {algo}: NLopt's {algo} does not take constraints; use one that does "
                          f"({', '.join(sorted(_CONSTRAINED - {'AUGLAG_EQ', 'LN_AUGLAG_EQ', 'LD_AUGLAG_EQ'}))}) "
                          f"or algorithm='AUGLAG' with local_algorithm='{algo}'")
    fs = _fixed_flowsheet(flowsheet, fixed, t_end)
    if isinstance(variables, Mapping):  # {param: (unit, lo, hi)}
        variables = [(k, *v) for k, v in variables.items()]
    elif isinstance(variables, str) or (isinstance(variables, tuple) and len(variables) >= 3
                                        and isinstance(variables[0], str) and isinstance(variables[2], (int, float))):
        variables = [variables]  # a single variable
    axes = [make_axis(fs, v, f"variables[{i}]", with_n=False, allow_t_end=True) for i, v in enumerate(variables)]
    if not axes:
        raise ConfigError("variables: give at least one (param, unit, lo, hi)")
    if len({a.param for a in axes}) != len(axes):
        raise ConfigError("variables: a parameter is given twice")
    for a in axes:
        if fixed and a.param in fixed:
            raise ConfigError(f"fixed: {a.param} is also a variable")
    var_names = [a.param for a in axes]
    outputs = [c.output for c in cons]
    if objective not in var_names:
        if objective in fs.params or objective == T_END:
            raise ConfigError(f"objective = '{objective}': a parameter that is not a variable is constant "
                              f"(variables: {', '.join(var_names)})")
        outputs = [objective] + outputs
    outputs = sweep._check_outputs(fs, list(dict.fromkeys(outputs)), where="objective/constraints")
    for k in (x0 or {}):
        if k not in var_names:
            raise ConfigError(f"x0: '{k}' is not a variable ({', '.join(var_names)})")
    u0 = []
    for a in axes:
        if x0 and a.param in x0:
            v = float(x0[a.param])
            if not a.lo <= v <= a.hi:
                raise ConfigError(f"x0: {a.param} = {v:g} {a.unit}: outside {a.lo:g} ... {a.hi:g}")
        else:
            v = float(a.from_si(fs.t_end if a.param == T_END else fs.get(a.param)))
            if not a.lo <= v <= a.hi:
                v = 0.5 * (a.lo + a.hi)
        u0.append((v - a.lo) / (a.hi - a.lo))
    if not (isinstance(maxeval, int) and maxeval >= 1):
        raise ConfigError(f"maxeval = {maxeval!r}: expected an integer >= 1")
    if not 0 < fd_step < 0.5:
        raise ConfigError(f"fd_step = {fd_step!r}: expected 0 < fd_step < 0.5 (scaled units)")

    prob = _Problem(fs, axes, objective, maximize, cons, outputs, _sim_kwargs(simulate))
    n = len(axes)
    n_eval = [0]

    def grad_of(u, value_of):
        g = np.empty(n)
        f0 = value_of(prob.evaluate(u))
        for i in range(n):
            up = np.array(u, dtype=float)
            h = fd_step if up[i] + fd_step <= 1.0 else -fd_step
            up[i] += h
            g[i] = (value_of(prob.evaluate(up, kind="gradient")) - f0) / h
        return g

    def f_obj(u, grad):
        n_eval[0] += 1
        rec = prob.evaluate(u)
        if grad.size > 0:
            grad[:] = grad_of(u, prob.f_for_nlopt)
        return prob.f_for_nlopt(rec)

    def make_c(i):
        def f_c(u, grad):
            rec = prob.evaluate(u)
            if grad.size > 0:
                grad[:] = grad_of(u, lambda r: _Problem.c_for_nlopt(r, i))
            return _Problem.c_for_nlopt(rec, i)
        return f_c

    opt = nlopt.opt(getattr(nlopt, algo), n)
    opt.set_lower_bounds([0.0] * n)
    opt.set_upper_bounds([1.0] * n)
    if maximize:
        opt.set_max_objective(f_obj)
    else:
        opt.set_min_objective(f_obj)
    for i in range(len(cons)):
        opt.add_inequality_constraint(make_c(i), 0.5 * _C_SAFETY)
    opt.set_xtol_rel(xtol_rel)
    if ftol_rel is not None:
        opt.set_ftol_rel(ftol_rel)
    opt.set_maxeval(maxeval)
    if maxtime is not None:
        opt.set_maxtime(float(maxtime))
    if population is not None:
        opt.set_population(int(population))
    opt.set_initial_step([0.1] * n)
    if local is not None:
        lo_opt = nlopt.opt(getattr(nlopt, local), n)
        lo_opt.set_xtol_rel(xtol_rel)
        lo_opt.set_maxeval(maxeval)
        opt.set_local_optimizer(lo_opt)
    if seed is not None:
        nlopt.srand(int(seed))

    t0 = time.perf_counter()
    names = {getattr(nlopt, r): r for r in _RESULTS}
    message = ""
    u_best = None
    try:
        u_best = opt.optimize(list(u0))
        code = names.get(opt.last_optimize_result(), str(opt.last_optimize_result()))
    except nlopt.RoundoffLimited:
        code = "ROUNDOFF_LIMITED"
    except nlopt.ForcedStop:
        code = "FORCED_STOP"
    except (RuntimeError, ValueError) as e:  # NLopt's generic failure / invalid arguments
        if isinstance(e, ConfigError):
            raise
        code = "FAILURE" if isinstance(e, RuntimeError) else "INVALID_ARGS"
        message = f"NLopt: {e}. "
    wall = time.perf_counter() - t0

    rec = prob.evaluate(u_best) if u_best is not None else None
    ok = rec is not None and rec["status"] == sweep.STATUS_OK and all(rec["met"])
    if not ok:
        feas = [r for r in prob.cache.values() if r["status"] == sweep.STATUS_OK and all(r["met"])
                and math.isfinite(r["f"])]
        if feas:
            best = (max if maximize else min)(feas, key=lambda r: r["f"])
            message += ("NLopt's final point is infeasible; returning the best feasible point evaluated."
                        if rec is not None else "returning the best feasible point evaluated.")
            rec = best
        elif rec is None:
            if not prob.cache:  # NLopt stopped before its first evaluation
                prob.evaluate(u0)
            rec = min(prob.cache.values(), key=lambda r: -min(r["margins"], default=0.0)
                      if all(map(math.isfinite, r["margins"])) else math.inf)
            message += "no feasible point found; returning the least infeasible point evaluated."
        else:
            message += "no feasible point found."
    xs = prob.si(rec["u"])
    x = {a.param: float(a.from_si(xs[a.param])) for a in axes}
    import pandas as pd

    history = pd.DataFrame(prob.rows)
    return OptimizationResult(
        x=x, x_si=xs, units={a.param: a.unit for a in axes}, objective=objective, maximize=maximize,
        value=float(rec["f"]), outputs=dict(rec["values"]),
        constraints={str(c): {"value": rec["values"].get(c.output, math.nan), "margin": rec["margins"][i],
                              "met": rec["met"][i]} for i, c in enumerate(cons)},
        feasible=rec["status"] == sweep.STATUS_OK and all(rec["met"]), n_simulations=prob.n_sim,
        n_evaluations=n_eval[0], nlopt_result=code, message=message.strip(), algorithm=algo, local_algorithm=local,
        wall_time_s=wall, history=history)


# ------------------------------------------------------------------------------------------------
# probabilistic design space
# ------------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class ProbabilityMap:
    """P(all constraints met) over a grid of two operating variables when the model parameters ``params`` are
    uncertain, N(``mean``, ``covariance``) in SI.

    ``probability`` (ny, nx); ``values[o]``: the output at the mean parameters (nominal); ``sigma[o]``: its
    propagated standard deviation (linear: sqrt(J C J^T); Monte Carlo: sample standard deviation);
    ``nominal_window``: the feasible window of the nominal values."""

    x: Axis
    y: Axis
    constraints: tuple
    params: tuple
    mean: np.ndarray
    covariance: np.ndarray
    method: str
    probability: np.ndarray
    values: dict
    sigma: dict
    n_samples: int
    seed: int
    n_simulations: int
    n_failed: int
    wall_time_s: float
    sensitivities: str = ""

    @property
    def nominal_window(self) -> FeasibleWindow:
        return feasible_window(self, self.constraints)

    def to_dataframe(self):
        import pandas as pd

        X, Y = np.meshgrid(self.x.values, self.y.values)
        data = {self.x.column: X.ravel(), self.y.column: Y.ravel(), "probability": self.probability.ravel()}
        for o in self.values:
            data[o] = self.values[o].ravel()
            data[f"sigma[{o}]"] = self.sigma[o].ravel()
        return pd.DataFrame(data)


def _summary_source(fs: Flowsheet, name: str) -> tuple[str, float]:
    """(state/output name, factor to the summary's unit) of a summary key or a state/output name."""
    smap = dict(fs._scene.summary_map)
    if name in smap:
        return smap[name], (1e6 if name.endswith("_um") else 1.0)
    return name, 1.0


class _LinearizedPoint:
    """Executor task of the linear method: nominal outputs and their Jacobian w.r.t. the uncertain parameters at one
    grid point (picklable, so it runs on Dask workers too)."""

    def __init__(self, base, params, outputs, sources, sim_kwargs, steps, use_core, rel_step):
        self.base, self.params, self.outputs, self.sources = base, params, outputs, sources
        self.sim_kwargs, self.steps, self.use_core, self.rel_step = sim_kwargs, steps, use_core, rel_step

    def _values(self, fs) -> dict:
        return sweep._final_values(fs.simulate(**self.sim_kwargs), self.outputs)

    def __call__(self, fs, item) -> dict:
        i, point = item
        row: dict[str, Any] = {"_i": i, "n_sim": 0}
        try:
            fs.update(self.base)
            fs.update(point)
            vals = self._values(fs)
            row["n_sim"] += 1
            J = np.zeros((len(self.outputs), len(self.params)))
            if self.use_core:
                t_end = float(self.sim_kwargs.get("t_end", fs.t_end))
                dz = _core.output_sensitivities(fs._scene, t_end, [t_end], list(self.params), self.rel_step)
                row["n_sim"] += 1
                names = fs.output_names
                for a, (src, factor) in enumerate(self.sources):
                    J[a] = np.asarray(dz)[0, :, names.index(src)] * factor
            else:  # central differences, step 0.1 sigma (a secant over the scale of the uncertainty)
                for k, p in enumerate(self.params):
                    p0 = fs.get(p)
                    fs.set(p, p0 + self.steps[k])
                    up = self._values(fs)
                    fs.set(p, p0 - self.steps[k])
                    dn = self._values(fs)
                    fs.set(p, p0)
                    row["n_sim"] += 2
                    for a, o in enumerate(self.outputs):
                        J[a, k] = (up[o] - dn[o]) / (2.0 * self.steps[k])
            row["values"], row["J"], row["status"], row["message"] = vals, J, sweep.STATUS_OK, ""
        except (SolverError, ConfigError) as e:
            row["status"], row["message"] = sweep.STATUS_FAILED, " ".join(str(e).split())
        return row


def probabilistic_design_space(flowsheet: Flowsheet, x, y, constraints, *, params: Sequence[str],
                               covariance, mean: Mapping[str, float] | Sequence[float] | None = None,
                               method: str = "linear", n_samples: int | None = None, seed: int = 0,
                               fixed: Mapping[str, float | str] | None = None, t_end: float | str | None = None,
                               workers: int | None = None, executor: str | Any = "threads",
                               progress: bool | None = None, simulate: Mapping[str, Any] | None = None,
                               sensitivities: str = "auto", rel_step: float = 1e-6) -> ProbabilityMap:
    """Probability that every constraint is met at each operating point when the model parameters ``params`` are
    normally distributed with ``mean`` (default: the flowsheet's values) and ``covariance`` (SI units, e.g. from a
    calibration).

    ``method="linear"``: the outputs are linearized in the parameters at every grid point, z ~ N(z0, J C J^T);
    P is the fraction of ``n_samples`` (default 20 000) draws of that normal distribution meeting all constraints
    (the same draws at every point, fixed ``seed``: the map is smooth and reproducible, and exactly 0 or 1 where
    the margin is many standard deviations). J comes from forward sensitivities (``_core.output_sensitivities``:
    one sensitivity solve per point) when every constrained quantity is a reported output
    (``sensitivities="auto"``/``"core"``), else from central differences with steps of 0.1 sigma
    (``sensitivities="fd"``: 2 simulations per parameter). ``method="monte_carlo"``: ``n_samples`` (default 64)
    parameter draws (fixed ``seed``, the same draws at every point) are simulated at every grid point; P is the
    fraction meeting all constraints. Failed simulations and draws outside the parameter bounds count as not
    meeting them (and are counted in ``n_failed``).
    """
    if method not in ("linear", "monte_carlo"):
        raise ConfigError(f"method = {method!r}: expected 'linear' or 'monte_carlo'")
    if sensitivities not in ("auto", "core", "fd"):
        raise ConfigError(f"sensitivities = {sensitivities!r}: expected 'auto', 'core' or 'fd'")
    n = n_samples if n_samples is not None else (64 if method == "monte_carlo" else 20000)
    if not isinstance(n, (int, np.integer)) or isinstance(n, bool) or n < 1:
        raise ConfigError(f"n_samples = {n_samples!r}: expected an integer >= 1")
    n = int(n)
    fs, ax, ay = _map_axes(flowsheet, x, y, fixed, t_end)
    cons = parse_constraints(constraints)
    if not cons:
        raise ConfigError("constraints: give at least one (e.g. {'d50_um': ('>=', 400)})")
    sweep._check_outputs(fs, [c.output for c in cons], where="constraints")
    params = list(params)
    if not params:
        raise ConfigError("params: name the uncertain parameters")
    for p in params:
        if p not in fs.params:
            raise ConfigError(f"params: unknown parameter '{p}' (allowed: {', '.join(fs.params)})")
        if p in (ax.param, ay.param):
            raise ConfigError(f"params: {p} is an operating variable of the map")
    if len(set(params)) != len(params):
        raise ConfigError("params: a parameter is named twice")
    k = len(params)
    cov = np.asarray(covariance, dtype=float)
    if cov.ndim == 1 and cov.shape == (k,):
        cov = np.diag(cov)
    if cov.shape != (k, k) or not np.all(np.isfinite(cov)) or not np.allclose(cov, cov.T, rtol=1e-10, atol=0):
        raise ConfigError(f"covariance: expected a symmetric {k}x{k} matrix (or {k} variances) in SI units of "
                          f"{', '.join(params)}, got shape {cov.shape}")
    w, V = np.linalg.eigh(cov)
    if w.min() < -1e-12 * max(w.max(), 0.0):
        raise ConfigError("covariance: not positive semi-definite")
    L = V * np.sqrt(np.clip(w, 0.0, None))  # cov = L L^T
    if mean is None:
        mu = np.array([fs.get(p) for p in params])
    elif isinstance(mean, Mapping):
        unknown = set(mean) - set(params)
        if unknown:
            raise ConfigError(f"mean: {', '.join(sorted(unknown))} not in params")
        mu = np.array([float(mean.get(p, fs.get(p))) for p in params])
    else:
        mu = np.asarray(mean, dtype=float)
        if mu.shape != (k,):
            raise ConfigError(f"mean: expected {k} values (SI) for {', '.join(params)}")
    for p, m in zip(params, mu):
        sweep._set_or_raise(fs, p, float(m), f"mean[{p}]")
    rng = np.random.default_rng(seed)
    outputs = list(dict.fromkeys(c.output for c in cons))
    shape = (len(ay.values), len(ax.values))
    grid_pts = _grid_points(ax, ay)
    sim_kwargs = _sim_kwargs(simulate)
    t0 = time.perf_counter()

    if method == "monte_carlo":
        draws = mu + rng.standard_normal((n, k)) @ L.T
        points = [{**gp, **{p: float(d[j]) for j, p in enumerate(params)}} for gp in grid_pts for d in draws]
        df = sweep.run_sweep(fs, points, outputs, workers=workers, progress=progress, executor=executor,
                             simulate=sim_kwargs, desc="probabilistic design space")
        ok = (df["status"] == sweep.STATUS_OK).to_numpy().reshape(shape + (n,))
        met = ok.copy()
        vals = {o: df[o].to_numpy(dtype=float).reshape(shape + (n,)) for o in outputs}
        for c in cons:
            met &= c.satisfied(vals[c.output])
        prob = met.mean(axis=2)
        values, sigma = {}, {}
        with np.errstate(invalid="ignore", divide="ignore"):
            import warnings

            with warnings.catch_warnings():  # all-failed points: NaN, not a warning
                warnings.simplefilter("ignore", RuntimeWarning)
                for o in outputs:
                    v = np.where(ok, vals[o], np.nan)
                    values[o] = np.nanmean(v, axis=2)
                    sigma[o] = np.nanstd(v, axis=2, ddof=1 if n > 1 else 0)
        return ProbabilityMap(ax, ay, tuple(cons), tuple(params), mu, cov, method, prob, values, sigma, n, seed,
                              len(points), int((~ok).sum()), time.perf_counter() - t0)

    # linear
    sources = [_summary_source(fs, o) for o in outputs]
    core_ok = all(src in fs.output_names for src, _ in sources)
    if sensitivities == "core" and not core_ok:
        raise ConfigError("sensitivities = 'core': not available for "
                          + ", ".join(o for o, (src, _) in zip(outputs, sources) if src not in fs.output_names)
                          + " (not a reported output; use 'fd' or 'auto')")
    use_core = core_ok and sensitivities != "fd"
    steps = [0.1 * math.sqrt(cov[j, j]) if cov[j, j] > 0 else max(1e-6 * abs(mu[j]), 1e-12) for j in range(k)]
    base = {p: fs.get(p) for p in (ax.param, ay.param)}
    task = _LinearizedPoint(base, params, outputs, sources, sim_kwargs, steps, use_core, rel_step)
    rows = sweep._collect(sweep.make_executor(executor, workers), task, fs, list(enumerate(grid_pts)), progress,
                          "probabilistic design space")
    eps = rng.standard_normal((n, k))
    m = len(outputs)
    prob = np.zeros(len(rows))
    values = {o: np.full(len(rows), math.nan) for o in outputs}
    sigma = {o: np.full(len(rows), math.nan) for o in outputs}
    n_failed = 0
    for r in rows:
        i = r["_i"]
        if r["status"] != sweep.STATUS_OK:
            n_failed += 1
            continue
        z0 = np.array([r["values"][o] for o in outputs])
        JL = r["J"] @ L  # (m, k)
        z = z0 + eps @ JL.T  # (n, m)
        met = np.ones(n, dtype=bool)
        for c in cons:
            met &= c.satisfied(z[:, outputs.index(c.output)])
        prob[i] = met.mean()
        sd = np.sqrt(np.einsum("ij,ij->i", JL, JL))
        for a in range(m):
            values[outputs[a]][i] = z0[a]
            sigma[outputs[a]][i] = sd[a]
    n_sim = sum(r.get("n_sim", 0) for r in rows)
    return ProbabilityMap(ax, ay, tuple(cons), tuple(params), mu, cov, method, prob.reshape(shape),
                          {o: v.reshape(shape) for o, v in values.items()},
                          {o: v.reshape(shape) for o, v in sigma.items()}, n, seed, n_sim, n_failed,
                          time.perf_counter() - t0, "core" if use_core else "fd")


# ------------------------------------------------------------------------------------------------
# command line: granuflow contour
# ------------------------------------------------------------------------------------------------
def contour_command(args) -> int:
    """``granuflow contour SCENE --x P:U:LO:HI:N --y ... --output O [--constraint "O>=V"] --out DIR``: writes
    contour.csv (one row per grid point; with constraints their margins and ``feasible``), contour.json (metadata,
    feasible window ranges and outline), contour_<output>.png and, with constraints, feasible_window.png and
    feasible_window.csv (the outline polygons). Returns 3 if every point failed, else 0."""
    import json
    import os
    import sys

    from .flowsheet import load

    fs = load(args.scene)
    from .cli import _json_value, check_out_dir, check_workers, parse_sets

    fixed = parse_sets(args.set)
    check_workers(args.workers)
    cons = parse_constraints(args.constraint or [])
    sweep._check_outputs(fs, list(args.output or ["d50_um"]), where="--output")
    for raw, c in zip(args.constraint or [], cons):
        sweep._check_outputs(fs, [c.output], where=f"--constraint '{raw}'")
    make_axis(fs, args.x, "--x")
    make_axis(fs, args.y, "--y")
    check_out_dir(args.out)
    outputs = list(dict.fromkeys(list(args.output or ["d50_um"]) + [c.output for c in cons]))
    executor: Any = args.executor
    client = None
    if args.dask:
        from distributed import Client

        client = executor = Client(args.dask)
    try:
        grid = contour_map(fs, args.x, args.y, outputs, fixed=fixed, t_end=args.t_end, workers=args.workers,
                           executor=executor, progress=False if args.no_progress else None)
    finally:
        if client is not None:
            client.close()
    os.makedirs(args.out, exist_ok=True)
    df = grid.to_dataframe()
    written = ["contour.csv", "contour.json"]
    win = None
    if cons:
        win = feasible_window(grid, cons)
        wdf = win.to_dataframe()
        for c in wdf.columns[2:]:
            df[c] = wdf[c].to_numpy()
        win.outline_dataframe().to_csv(os.path.join(args.out, "feasible_window.csv"), index=False)
        plot_feasible_window(win, os.path.join(args.out, "feasible_window.png"), grid=grid, background=outputs[0])
        written += ["feasible_window.csv", "feasible_window.png"]
    df.to_csv(os.path.join(args.out, "contour.csv"), index=False)
    for o in outputs:
        if np.isfinite(grid[o]).sum() >= 4:
            plot_contour(grid, o, os.path.join(args.out, f"contour_{o}.png"), window=win)
            written.append(f"contour_{o}.png")
    n_failed = int((~grid.ok).sum())
    meta = {"scene": os.path.abspath(args.scene), "x": {"param": grid.x.param, "unit": grid.x.unit,
                                                         "values": grid.x.values.tolist()},
            "y": {"param": grid.y.param, "unit": grid.y.unit, "values": grid.y.values.tolist()},
            "outputs": outputs, "fixed": fixed, "t_end_s": grid.t_end_s, "n_points": grid.n_simulations,
            "n_failed": n_failed, "wall_time_s": grid.wall_time_s, "simulations_per_s": _json_value(grid.simulations_per_s),
            "constraints": [str(c) for c in cons]}
    if win is not None:
        meta["feasible_fraction"] = win.fraction
        meta["feasible_ranges"] = win.ranges()
        meta["outline"] = [ring.tolist() for ring in win.outline]
    with open(os.path.join(args.out, "contour.json"), "w") as f:
        json.dump(meta, f, indent=2, allow_nan=False)
    if not args.quiet:
        print(f"{fs.name}: {grid.n_simulations} points ({n_failed} failed) in {grid.wall_time_s:.2f} s "
              f"({grid.simulations_per_s:.0f} simulations/s)"
              + (f"; feasible window: {100 * win.fraction:.0f} % of the grid, {win.ranges()}" if win else "")
              + f"; wrote {', '.join(written)} to {args.out}")
    if n_failed:
        i = np.argwhere(~grid.ok)[0]
        print(f"granuflow: {n_failed} of {grid.n_simulations} points failed; first: {grid.x.param} = "
              f"{grid.x.values[i[1]]:g} {grid.x.unit}, {grid.y.param} = {grid.y.values[i[0]]:g} {grid.y.unit}: "
              f"{grid.message[tuple(i)]}", file=sys.stderr)
    return 3 if n_failed == grid.n_simulations else 0
