"""A result as accurate as asked for (issue 28): ``accuracy:`` in a scene, ``granuflow run --accuracy 1%``,
``simulate(accuracy=0.01)``.

The target is a relative error per summary output (one number for every output, or a mapping per output). The
size grid is refined and the tolerance tightened until the estimated numerical error of every targeted output is
below it; the answer is the solve on the last grid (a real solution, not an extrapolated value), with the estimate
it reached. To be cheap, every solve serves the estimate:

* the tolerance first: the scene's grid at k rtol (k = 100, or 10 where that would pass 1e-3), cheaper than a
  tighter solve (the error of IDAS grows about in proportion to rtol: e_int(rtol) = (f(k rtol) - f(rtol)) / (k - 1));
  when that is above a fifth of the target the solves below use an rtol tightened by the powers of ten it needs;
* three grids (refined 1, 2 and 3 times the scene's, or 1/2, 3/4 and 1 of a grid of 40 classes or more) give every
  output's observed order p and constant C of f(h) = f(0) + C h^p (h: the spacing of the grid, any ratios);
* the grid predicted adequate, h = (target * safety / C)^(1/p), is solved next (at most 3 times finer per step), and
  the estimate at it is the fit through it and the two grids before; until every output is below its target.

Scenes without a size grid are refined in tolerance only.
"""
from __future__ import annotations

import math
import re
import time
from dataclasses import dataclass, field

from .. import _core
from .estimate import MIN_RTOL, ORDER_RANGE, display_name, not_corresponding

ConfigError = _core.ConfigError
SAFETY = 0.7           # the predicted grid aims at this fraction of the target
TOL_SHARE = 0.2        # the integration error may take this share of the target
MAX_SOLVES = 8         # grid solves at most
MAX_GROWTH = 3.0       # a new grid at most this much finer than the finest so far
COARSE_FROM = 40       # grids with this many classes (or more) are estimated from coarser ones


def parse_target(value, where: str = "accuracy") -> dict[str, float]:
    """``0.01``, ``"1%"``, ``"1 %"`` -> {"*": 0.01}; a mapping {summary key: such a value} per output."""
    if isinstance(value, dict):
        if not value:
            raise ConfigError(f"{where} = {{}}: expected a relative error (e.g. 1%) or a mapping of summary key -> "
                              "relative error")
        return {str(k): _fraction(v, f"{where}.{k}") for k, v in value.items()}
    return {"*": _fraction(value, where)}


def _fraction(v, where: str) -> float:
    x = None
    if isinstance(v, (int, float)) and not isinstance(v, bool):
        x = float(v)
    elif isinstance(v, str):
        m = re.fullmatch(r"\s*([0-9.eE+-]+)\s*(%?)\s*", v)
        if m:
            try:
                x = float(m.group(1)) / (100.0 if m.group(2) else 1.0)
            except ValueError:
                x = None
    if x is None or not (math.isfinite(x) and 1e-8 <= x <= 0.5):
        raise ConfigError(f"{where} = {v!r}: expected a relative error between 1e-6 % and 50 %, e.g. 1% or 0.01")
    return x


def spacing(fs) -> float:
    """The grid's spacing (relative measure h): 1/(classes - 1) of a log-diameter grid, 1/q of a geometric one."""
    g = fs.grid()
    return 1.0 / int(g["q"]) if g.get("grid") == "geometric" else 1.0 / (int(g["classes"]) - 1)


def fit(hs, fs_, noise: float = 0.0) -> tuple[float, float | None, str]:
    """(error of the value on the finest grid, observed order, method) from values ``fs_`` on grids of spacings
    ``hs`` (coarse to fine, any ratios): f(h) = f(0) + C h^p through the three."""
    (h1, h2, h3), (f1, f2, f3) = hs, fs_
    if not all(math.isfinite(v) for v in fs_):
        return math.nan, None, "not finite"
    d1, d2 = f1 - f2, f2 - f3
    tiny = max(2.0 * noise, 1e-14 * max(abs(v) for v in fs_))
    if abs(d1) <= tiny and abs(d2) <= tiny:
        return d2, None, "converged"
    if d1 * d2 > 0 and abs(d2) > tiny:
        def ratio(p):
            return (h1 ** p - h2 ** p) / (h2 ** p - h3 ** p)
        lo, hi = ORDER_RANGE
        want = d1 / d2
        if want <= ratio(lo):
            p = lo
        elif want >= ratio(hi):
            p = hi
        else:
            a, b = lo, hi
            for _ in range(60):
                m = 0.5 * (a + b)
                a, b = (m, b) if ratio(m) < want else (a, m)
            p = 0.5 * (a + b)
        c = d2 / (h2 ** p - h3 ** p)
        return c * h3 ** p, p, "richardson"
    return math.copysign(abs(f1 - f3) + abs(d2), f2 - f3 if d2 else f1 - f3), None, "bound"


@dataclass
class Accuracy:
    """What an accuracy target reached (summary.json ``accuracy``)."""
    target: dict[str, float]
    reached: bool
    grid: str
    rtol: float
    outputs: dict[str, dict]
    grids: list[str]
    solves: int
    cost_relative: float
    wall_time_s: float
    notes: list[str] = field(default_factory=list)

    def to_json(self) -> dict:
        return {"target": dict(self.target), "reached": self.reached, "grid": self.grid, "rtol": self.rtol,
                "outputs": {k: {x: _num(v) for x, v in o.items()} for k, o in self.outputs.items()},
                "grids": list(self.grids), "solves": self.solves,
                "cost_relative": self.cost_relative, "wall_time_s": self.wall_time_s, "notes": list(self.notes)}

    def lines(self) -> list[str]:
        head = (f"accuracy {'reached' if self.reached else 'NOT reached'} on {self.grid or 'the scene grid'}, "
                f"rtol {self.rtol:g}: {self.solves} solves ({', '.join(self.grids)}), "
                f"{self.cost_relative:.1f} x the cost of the scene's own grid")
        out = [head]
        for k, o in self.outputs.items():
            name, unit = display_name(k, o["unit"])
            u = f" {unit}" if unit else ""
            if o.get("not_estimated"):
                out.append(f"  {name} = {o['value']:.6g}{u}: not estimated ({o['not_estimated']})")
                continue
            out.append(f"  {name} = {o['value']:.6g}{u}; estimated error {o['error']:+.3g}{u} "
                       f"({100 * o['relative']:.3g} %, target {100 * o['target']:.3g} %; grid {o['grid']:+.3g}, "
                       f"tolerance {o['tolerance']:+.3g})")
        return out + [f"  note: {n}" for n in self.notes]


def solve(fs, target: dict[str, float], **kw):
    """The result of ``fs`` on the grid and tolerance that meet ``target`` (parse_target), with ``.accuracy``."""
    t0 = time.perf_counter()
    run = dict(kw, warn=False, accuracy=False, grid_check=False)
    t_b = time.perf_counter()
    base = fs.simulate(**run)
    base_cost = time.perf_counter() - t_b
    run.setdefault("t_end", float(base.t[-1]))
    run["t_out"] = [float(t) for t in base.t]
    s0 = base.summary_values()
    units = base.summary["units"]
    numeric = [k for k in fs.summary_keys()
               if isinstance(s0.get(k), (int, float)) and not isinstance(s0.get(k), bool)]
    if "*" in target:
        goals = {k: target["*"] for k in numeric}
    else:
        unknown = [k for k in target if k not in numeric]
        if unknown:
            raise ConfigError(f"accuracy: {unknown[0]}: not a summary output of this scene with a value (outputs: "
                              f"{', '.join(numeric)})")
        goals = dict(target)
    notes: list[str] = []
    levels, rtol, e_int, extra = _start(fs, base, run, goals, s0, notes)
    rtol0 = base.rtol

    def level(factor):
        f = fs.regridded(factor)
        levels.append((spacing(f), f, f.simulate(**run)))
        levels.sort(key=lambda x: -x[0])

    out, reached = {}, False
    if fs.grid() is None:
        answer_fs = fs
        answer = base if rtol == rtol0 else fs.simulate(**run)
        for k, g in goals.items():
            v = answer.summary_values()[k]
            out[k] = _entry(v, units.get(k, ""), g, None, e_int[k], None, "tolerance only")
        reached = all(o["relative"] <= o["target"] for o in out.values())
    else:
        skip = not_corresponding(levels[-1][2], [levels[0][2]])
        for k in list(goals):
            reason = skip.get(fs.summary_map.get(k, ""), "")
            if reason:
                out[k] = {"unit": units.get(k, ""), "not_estimated": reason}
                del goals[k]
        while True:
            (h1, _, r1), (h2, _, r2), (h3, f3, r3) = levels[-3:]
            est = {}
            for k, g in goals.items():
                vals = [r.summary_values()[k] for r in (r1, r2, r3)]
                if any(v is None for v in vals):
                    est[k] = (math.nan, None, "not finite")
                    continue
                est[k] = fit((h1, h2, h3), vals, abs(e_int[k]))
            v3 = r3.summary_values()
            rel = {k: abs(est[k][0] + e_int[k]) / abs(v3[k]) if v3[k] else math.inf
                   for k in goals}
            reached = all(rel[k] <= goals[k] for k in goals)
            if reached or len(levels) >= MAX_SOLVES:
                break
            grow = 1.25
            for k, g in goals.items():
                if rel[k] > g:
                    p = est[k][1] or 1.0
                    grow = max(grow, (rel[k] / (SAFETY * g)) ** (1.0 / p) if math.isfinite(rel[k]) else MAX_GROWTH)
            factor = (1.0 / h3) * min(grow, MAX_GROWTH) / (1.0 / spacing(fs))
            try:
                level(factor)
            except ConfigError as e:
                notes.append(f"no finer grid: {' '.join(str(e).split())}")
                break
            except _core.SolverError as e:
                notes.append(f"a solve on a finer grid failed: {' '.join(str(e).split())}")
                break
        answer_fs, answer = f3, r3
        for k, o in out.items():  # the values not estimated: the answer's own
            o["value"] = r3.summary_values()[k]
        for k, g in goals.items():
            err, p, method = est[k]
            out[k] = _entry(r3.summary_values()[k], units.get(k, ""), g, err, e_int[k], p, method)
    wall = time.perf_counter() - t0
    grids = [f.grid_label() for _, f, _ in levels] if levels else []
    solves = (len(levels) + extra) if levels else 2 + (rtol != rtol0)
    rep = Accuracy(dict(target), reached, answer_fs.grid_label(), rtol, out, grids, solves,
                   wall / base_cost if base_cost > 0 else math.nan, wall, notes)
    answer.accuracy = rep
    if not reached:
        worst = [k for k, o in out.items() if not o.get("not_estimated") and not o["relative"] <= o["target"]]
        answer.extra_warnings.append(
            f"accuracy target not reached on {rep.grid}: " + ", ".join(
                f"{display_name(k, '')[0]} ≈ {100 * out[k]['relative']:.2g} % (target {100 * out[k]['target']:.2g} %)"
                for k in worst) + (f" ({notes[-1]})" if notes else ""))
    return answer


def _start(fs, base, run: dict, goals: dict, s0: dict, notes: list):
    """The tolerance check and the first three grids: (levels, rtol, integration error per key, extra solves)."""
    levels = []  # (spacing, flowsheet, result)
    rtol0, atol0 = base.rtol, base.atol
    kl = 100.0 if rtol0 * 100 <= 1e-3 else 10.0
    loose_run = dict(run, rtol=rtol0 * kl, atol=atol0 * kl)
    # the first grids and the tolerance check are independent: solved side by side (simulate releases the GIL),
    # the grids copied here first (building a flowsheet holds it)
    first: list = []
    if fs.grid() is not None:
        try:
            first = [(f, fs.regridded(f)) for f in ((0.5, 0.75) if int(fs.grid()["classes"]) >= COARSE_FROM
                                                    else (2, 3))]
        except ConfigError as e:  # a coarser grid the scene does not allow (a pivot it needs): refine instead
            notes.append(f"no coarser grid ({' '.join(str(e).split())}): refined 2 and 3 times")
            first = [(f, fs.regridded(f)) for f in (2, 3)]
    from concurrent.futures import ThreadPoolExecutor  # only a run with an accuracy target: not on run's path

    with ThreadPoolExecutor(max_workers=2) as ex:
        futures = [ex.submit(f.simulate, **run) for _, f in first]
        try:
            loose = fs.simulate(**loose_run).summary_values()
            solved = [(spacing(f), f, fut.result()) for (_, f), fut in zip(first, futures)]
        except KeyboardInterrupt:  # the pool's solves stop as well, or leaving the block would wait for them
            _core.interrupt()
            raise
    e_int = {k: (loose[k] - s0[k]) / (kl - 1) if loose.get(k) is not None else math.inf for k in goals}
    need = min((TOL_SHARE * goals[k] * abs(s0[k]) / abs(e) for k, e in e_int.items() if e and s0[k]),
               default=math.inf)
    rtol = rtol0
    if need < 1:  # the grids at the tighter tolerance (rare: the first ones are solved again)
        rtol = max(rtol0 * 10.0 ** math.floor(math.log10(need)), MIN_RTOL)
        run.update(rtol=rtol, atol=atol0 * rtol / rtol0)
        notes.append(f"tolerance tightened from rtol {rtol0:g} to {rtol:g}")
        solved = [(h, f, f.simulate(**run)) for h, f, _ in solved]
    e_int = {k: e * rtol / rtol0 for k, e in e_int.items()}
    levels += solved + [(spacing(fs), fs, base if rtol == rtol0 else fs.simulate(**run))] if first else []
    levels.sort(key=lambda x: -x[0])

    extra = 1 + (len(solved) + 1 if rtol != rtol0 else 0)
    return levels, rtol, e_int, extra


def _entry(value, unit, goal, grid, tol, order, method) -> dict:
    total = tol + (grid if grid is not None else 0.0)
    rel = abs(total) / abs(value) if value and math.isfinite(total) else math.inf

    def num(x):
        return float(x) if x is not None and math.isfinite(x) else None
    return {"value": num(value), "unit": unit, "target": goal, "error": num(total), "grid": num(grid),
            "tolerance": num(tol), "relative": rel, "order": num(order), "method": method}


def _num(v):
    return None if isinstance(v, float) and not math.isfinite(v) else v
