"""Contour maps over two operating variables and the feasible window of constraints."""
from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from typing import Any, Mapping, Sequence

import numpy as np

from .. import _core, sweep
from ..flowsheet import Flowsheet
from ..quantity import label
from .axes import Axis, map_axes, map_sim_kwargs, parse_constraints

ConfigError = _core.ConfigError
SolverError = _core.SolverError


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
    t_end_s: float = math.nan  # NaN for a map of steady states
    wall_time_s: float = math.nan
    solve_time_s: float = math.nan
    units: dict = field(default_factory=dict)  # unit of each output's values

    def __getitem__(self, output: str) -> np.ndarray:
        try:
            return self.values[output]
        except KeyError:
            raise KeyError(f"{output!r}: not an output of this grid ({', '.join(self.outputs)})") from None

    @property
    def shape(self) -> tuple[int, int]:
        return len(self.y.values), len(self.x.values)

    @property
    def steady(self) -> bool:
        """The values are steady states (solved directly), not the state at an end time."""
        return math.isnan(self.t_end_s)

    @property
    def when(self) -> str:
        """When the values hold, for titles: "at the steady state" or "after 60 min"."""
        return "at the steady state" if self.steady else f"after {self.t_end_s / 60:g} min"

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
        xs, ys = label(self.x.param, self.x.si_unit), label(self.y.param, self.y.si_unit)
        data = {self.x.column: X.ravel(), self.y.column: Y.ravel()}
        for ax, col in ((self.x, self.x.column), (self.y, self.y.column)):
            if ax.labels:  # a categorical setting: its names, not their positions
                data[col] = [ax.labels[int(v)] for v in data[col]]
        if xs != self.x.column:  # the SI values too, where the axis is not in SI already
            data[xs] = Xs.ravel()
        if ys != self.y.column:
            data[ys] = Ys.ravel()
        data.update({o: self.values[o].ravel() for o in self.outputs})
        data["status"] = self.status.ravel()
        data["message"] = self.message.ravel()
        df = pd.DataFrame(data)
        df.attrs.update({"scene": self.scene, "x": self.x.param, "y": self.y.param, "fixed": dict(self.fixed),
                         "t_end_s": self.t_end_s, "steady_state": self.steady, "outputs": list(self.outputs),
                         "units": {o: self.units.get(o, "") for o in self.outputs}})
        return df


def grid_points(x: Axis, y: Axis) -> list[dict]:
    return [{x.param: x.point(j), y.param: y.point(i)} for i in range(len(y.si)) for j in range(len(x.si))]


def contour_map(flowsheet: Flowsheet, x, y, outputs: Sequence[str] = ("d50_um",), *,
                fixed: Mapping[str, float | str] | None = None, t_end: float | str | None = None,
                workers: int | None = None, executor: str | Any = "threads", progress: bool | None = None,
                simulate: Mapping[str, Any] | None = None, error_estimate: bool = False,
                steady: bool = False) -> ContourGrid:
    """Simulate every point of the grid ``x`` by ``y`` and collect ``outputs`` at the end time (with ``steady``:
    at the steady state, solved directly for each point; a continuous process needs no long transient).

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
    error_estimate : bool
        Also the estimated numerical error of each output at every point (``values["d50_um_err"]``; four solves a
        point: finer size grids and a tighter tolerance, granuflow.accuracy): a map of the grid error next to the
        map of the output.

    Returns
    -------
    ContourGrid
        Failed points hold NaN and their status/message.
    """
    fs, ax, ay = map_axes(flowsheet, x, y, fixed, t_end)
    outputs = sweep.check_outputs(fs, list(outputs))
    t0 = time.perf_counter()
    df = sweep.run_sweep(fs, grid_points(ax, ay), outputs, workers=workers, progress=progress, executor=executor,
                         simulate=map_sim_kwargs(simulate), desc="contour map", error_estimate=error_estimate,
                         steady=steady)
    wall = time.perf_counter() - t0
    shape = (len(ay.values), len(ax.values))
    if error_estimate:
        outputs = outputs + [sweep.error_column(o) for o in outputs]
    return ContourGrid(
        x=ax, y=ay, outputs=tuple(outputs),
        values={o: df[o].to_numpy(dtype=float).reshape(shape) for o in outputs},
        status=df["status"].to_numpy(dtype=object).reshape(shape),
        message=df["message"].to_numpy(dtype=object).reshape(shape),
        scene=fs.name, fixed=dict(fixed or {}), t_end_s=math.nan if steady else fs.t_end, wall_time_s=wall,
        solve_time_s=float(np.nansum(df["solve_time_s"].to_numpy(dtype=float))),
        units={o: df.attrs["units"].get(o, "") for o in outputs})


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
        for ax, col in ((self.x, self.x.column), (self.y, self.y.column)):
            if ax.labels:  # a categorical setting: its names, not their positions
                data[col] = [ax.labels[int(v)] for v in data[col]]
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
