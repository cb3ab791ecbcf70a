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

from .names import display_name, not_corresponding  # noqa: F401 (part of this module's API)

TYPE_CHECKING = False  # typing's own flag without importing typing (a plain run imports neither it nor NumPy)
if TYPE_CHECKING:
    import numpy as np

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
    import numpy as np

    return np.array([richardson(a, b, c, n)[0] for a, b, c, n in zip(f1, f2, f4, noise)], dtype=float)


@dataclass
class OutputError:
    """The estimated numerical error of one value (in its own unit: µm for ``*_um`` summary keys). ``total`` is
    signed: the value minus the converged answer (a bias, not a ± band); ``corrected`` = value - total.
    ``reason`` says why the grid part was not estimated (the value does not correspond across grids)."""
    value: float
    discretization: float | None   # None: the scene has no size grid, or the value has no counterpart (reason)
    integration: float
    order: float | None = None
    method: str = ""
    unit: str = ""
    reason: str = ""

    @property
    def estimated(self) -> bool:
        return not self.reason

    @property
    def total(self) -> float:
        if self.reason:
            return math.nan
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
        out = {"value": num(self.value), "unit": self.unit, "total": num(self.total),
               "discretization": num(self.discretization), "integration": num(self.integration),
               "corrected": num(self.corrected), "relative": num(self.relative), "order": num(self.order),
               "method": self.method}
        if self.reason:
            out["not_estimated"] = self.reason
        return out

    def line(self, key: str) -> str:
        """``d50 = 499.7 µm; estimated error +61.4 µm (grid +61.3, tolerance +0.1); corrected 438.3 µm``."""
        name, unit = display_name(key, self.unit)
        u = f" {unit}" if unit else ""
        head = f"{name} = {self.value:.6g}{u}"
        if self.reason:
            return f"{head}; grid error not estimated ({self.reason}); tolerance {self.integration:+.3g}{u}"
        grid = "n/a" if self.discretization is None else f"{self.discretization:+.3g}{u}"
        how = f", order {self.order:.2f}" if self.order is not None else (f", {self.method}" if self.method else "")
        return (f"{head}; estimated error {self.total:+.3g}{u} (grid {grid}{how}, tolerance "
                f"{self.integration:+.3g}{u}); corrected {self.corrected:.6g}{u}")


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
        """One line per summary output: value, signed estimated error split into grid and tolerance, and the
        corrected value (or why the grid part was not estimated)."""
        return [e.line(k) for k, e in self.outputs.items() if math.isfinite(e.value)]


def estimate(base, tight, refined: list, keys: list[str], grid: str, rtol: tuple[float, float],
             wall_time_s: float = 0.0, notes: list[str] | None = None) -> ErrorEstimate:
    """The estimate from results: ``base`` (the answer), ``tight`` (same grid, tighter tolerance) and ``refined``
    (grids h/2 and h/4 at the tighter tolerance; empty without a size grid). ``keys``: the summary keys."""
    s_base, s_tight = base.summary_values(), tight.summary_values()  # the core's values (also of a d90 at the grid end)
    s_ref = [r.summary_values() for r in refined]
    units = base.summary.get("units", {})
    skip = not_corresponding(base, refined) if refined else {}
    outs = {}
    for k in keys:
        v = s_base.get(k)
        if not isinstance(v, (int, float)) or isinstance(v, bool):
            continue
        vt = s_tight.get(k)
        e_int = v - vt if vt is not None else math.nan
        disc, order, method = None, None, ""
        reason = skip.get(base.summary_map.get(k, ""), "")
        if refined and not reason:
            f2, f4 = (s.get(k) for s in s_ref)
            if f2 is None or f4 is None or vt is None:
                disc, method = math.nan, "not finite"
            else:
                disc, order, method = richardson(vt, f2, f4, noise=abs(e_int))
        outs[k] = OutputError(float(v), disc, float(e_int), order, "not estimated" if reason else method,
                              units.get(k, ""), reason)
    names = [n for n in list(base.state_names) + list(base.output_names)
             if n not in skip and n in tight and all(n in r for r in refined)]
    series = {}
    for n in names:
        b, t = base[n], tight[n]
        e = b - t
        if refined:
            e = e + richardson_series(t, refined[0][n], refined[1][n], abs(b - t))
        series[n] = e
    return ErrorEstimate(outs, series, grid, rtol, wall_time_s, list(notes or []))
