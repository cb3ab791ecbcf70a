"""How accurate a result is: the numerical error of every summary output and time series, estimated from re-solves
on refined size grids and at a tighter tolerance (``Flowsheet.simulate(error_estimate=True)``,
``granuflow run --error-estimate``).

Four solves: the result itself (grid h, tolerance rtol), and at rtol/100 the same grid (h), and grids refined twice
and four times (h/2, h/4: the log-spacing of the diameter pivots halved, or twice as many classes per doubling of
volume, over the same range of sizes). For a value f:

* integration error  e_int  = f(h, rtol) - f(h, rtol/100)   (the error of IDAS shrinks about in proportion to rtol,
  so the tighter solve carries about 1 % of it);
* discretization error e_disc of f(h): Richardson extrapolation on the three grids at rtol/100. With
  d1 = f(h) - f(h/2) and d2 = f(h/2) - f(h/4) of one sign and |d2| < |d1|, the observed order is
  p = log2(d1 / d2) (clipped to [0.5, 6]) and f(0) = f(h/4) - d2 / (2^p - 1), e_disc = f(h) - f(0).
  Where the differences change sign or do not shrink (not yet in the asymptotic range) no order is observed and
  the bound |f(h) - f(h/4)| + |d2| is reported instead ("bound"); where all three agree to within the integration
  error, "converged";
* total error  e = e_int + e_disc: the estimate of f(h, rtol) minus the exact solution of the model, and
  f(h, rtol) - e the corrected value.

A scene without a size grid has only the integration error. The estimates are of the numerical error alone: not
of the model's error, nor of the grid's range (``Result.warnings`` says when its ends clip the distribution).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from .outputs import per_class_names

REFINEMENTS = (2, 4)          # grid refinement factors of the two extra grids
TOLERANCE_FACTOR = 100.0      # the tighter solve: rtol and atol divided by this
MIN_RTOL = 1e-13              # no tighter than this (IDAS is near roundoff)
ORDER_RANGE = (0.5, 6.0)      # observed orders outside this range are not trusted


def richardson(f1: float, f2: float, f4: float, noise: float = 0.0) -> tuple[float, float | None, str]:
    """(discretization error of f1, observed order or None, method) from values on grids h, h/2, h/4, where
    ``noise`` is the size of differences the integration error alone can make."""
    vals = (f1, f2, f4)
    if not all(math.isfinite(v) for v in vals):
        return math.nan, None, "not finite"
    d1, d2 = f1 - f2, f2 - f4
    tiny = max(2.0 * noise, 1e-14 * max(abs(v) for v in vals))
    if abs(d1) <= tiny and abs(d2) <= tiny:
        return d1 + d2, None, "converged"
    if d1 * d2 > 0 and abs(d2) < abs(d1) and abs(d2) > tiny:
        p = math.log2(d1 / d2)
        lo, hi = ORDER_RANGE
        p = min(max(p, lo), hi)
        f0 = f4 - d2 / (2.0 ** p - 1.0)
        return f1 - f0, p, "richardson"
    return math.copysign(abs(f1 - f4) + abs(d2), f1 - f4), None, "bound"


def richardson_series(f1: np.ndarray, f2: np.ndarray, f4: np.ndarray, noise: np.ndarray) -> np.ndarray:
    """:func:`richardson` pointwise (the discretization error of the series f1)."""
    return np.array([richardson(a, b, c, n)[0] for a, b, c, n in zip(f1, f2, f4, noise)], dtype=float)


@dataclass
class OutputError:
    """The estimated numerical error of one value (in its own unit: µm for ``*_um`` summary keys)."""
    value: float
    discretization: float | None   # None: the scene has no size grid
    integration: float
    order: float | None = None
    method: str = ""

    @property
    def total(self) -> float:
        return self.integration + (self.discretization or 0.0)

    @property
    def corrected(self) -> float:
        """The value with the estimated error removed."""
        return self.value - self.total

    @property
    def relative(self) -> float:
        return abs(self.total) / abs(self.value) if self.value else math.nan

    def to_json(self) -> dict:
        def num(x):
            return float(x) if x is not None and math.isfinite(x) else None
        return {"value": num(self.value), "discretization": num(self.discretization),
                "integration": num(self.integration), "total": num(self.total), "corrected": num(self.corrected),
                "relative": num(self.relative), "order": num(self.order), "method": self.method}


@dataclass
class ErrorEstimate:
    """The error estimate of a result: per summary key an :class:`OutputError`, per time series (states and outputs
    every solve has, e.g. ``bed.d50``) the error over time; how it was made."""
    outputs: dict[str, OutputError]
    series: dict[str, np.ndarray]
    grid: str                              # e.g. "particles.classes 10, 19, 37" ("" without a size grid)
    rtol: tuple[float, float]              # the result's and the tighter solve's
    wall_time_s: float = 0.0               # the extra solves
    notes: list[str] = field(default_factory=list)

    def __getitem__(self, key: str) -> OutputError:
        return self.outputs[key]

    def error(self, name: str) -> np.ndarray | None:
        """The estimated total error of a time series over the output times (None if not estimated)."""
        return self.series.get(name)

    def to_json(self) -> dict:
        return {"method": "re-solves: size grid refined twice and four times (Richardson extrapolation), "
                          f"tolerance divided by {TOLERANCE_FACTOR:g}",
                "grid": self.grid, "rtol": list(self.rtol), "wall_time_s": self.wall_time_s, "notes": list(self.notes),
                "outputs": {k: e.to_json() for k, e in self.outputs.items()}}

    def lines(self) -> list[str]:
        """One line per summary output: value, estimated error and its parts."""
        out = []
        for k, e in self.outputs.items():
            if not math.isfinite(e.value):
                continue
            disc = "n/a" if e.discretization is None else f"{e.discretization:+.3g}"
            order = f", order {e.order:.2f}" if e.order is not None else (f", {e.method}" if e.method else "")
            out.append(f"{k} = {e.value:.6g} +- {abs(e.total):.3g} (grid {disc}{order}; tolerance "
                       f"{e.integration:+.3g})")
        return out


def estimate(base, tight, refined: list, keys: list[str], grid: str, rtol: tuple[float, float],
             wall_time_s: float = 0.0, notes: list[str] | None = None) -> ErrorEstimate:
    """The estimate from results: ``base`` (the answer), ``tight`` (same grid, tighter tolerance) and ``refined``
    (grids h/2 and h/4 at the tighter tolerance; empty without a size grid). ``keys``: the summary keys."""
    s_base, s_tight = base.summary, tight.summary
    s_ref = [r.summary for r in refined]
    outs = {}
    for k in keys:
        v = s_base.get(k)
        if not isinstance(v, (int, float)) or isinstance(v, bool):
            continue
        vt = s_tight.get(k)
        e_int = v - vt if vt is not None else math.nan
        disc, order, method = None, None, ""
        if refined:
            f2, f4 = (s.get(k) for s in s_ref)
            if f2 is None or f4 is None or vt is None:
                disc, method = math.nan, "not finite"
            else:
                disc, order, method = richardson(vt, f2, f4, noise=abs(e_int))
        outs[k] = OutputError(float(v), disc, float(e_int), order, method)
    skip = set()
    for r in refined:
        skip |= per_class_names(list(base.state_names) + list(base.output_names),
                                list(r.state_names) + list(r.output_names))
    names = [n for n in list(base.state_names) + list(base.output_names)
             if n not in skip and n in tight and all(n in r for r in refined)]
    series = {}
    for n in names:
        b, t = base[n], tight[n]
        e = b - t
        if refined:
            e = e + richardson_series(t, refined[0][n], refined[1][n], np.abs(b - t))
        series[n] = e
    return ErrorEstimate(outs, series, grid, rtol, wall_time_s, list(notes or []))
