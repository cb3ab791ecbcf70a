"""The check every plain run makes of its size grid (issue 28): one solve on a grid twice as fine, at the same
tolerance and output times. Per summary output the grid error of the run is estimated at first order,
e = 2 (f(h) - f(h/2)) (exact for an error ∝ h; above the true error where the order is higher, as the headline
scene's 1.5: the safe side), and the run warns where |e| is above THRESHOLD of the value, naming the cure. The same
solve tells the two causes of mass in the top class apart (outputs.grid_end_warnings): a grid too coarse smears mass
into it, and that mass shrinks as the grid refines (extrapolated to zero); a grid too short holds there what grew
beyond it, and that stays.
"""
from __future__ import annotations

import math
import time

from .. import _core
from .names import display_name, not_corresponding

THRESHOLD = 0.02   # relative grid error above which a run warns (and the default accuracy target: the same 2 %)
# Python's simulate() checks by default flowsheets of up to this many unknowns: their grid twice as fine costs a few
# times the run (the headline: 70 unknowns, 10 ms). Larger ones (the 100-class loops, 700-800 unknowns over 300 h;
# the 2-D population, 1603, whose doubled grid has 4 times the unknowns and costs 6 times the run) are checked when
# asked (grid_check=True), so that loops in scripts and notebooks stay fast; `granuflow run` checks every scene.
PYTHON_MAX_STATES = 500
CURE_TARGET = "1%"


class GridCheck:
    """What the grid check found (a plain class, not a dataclass: the dataclasses module imports inspect, several
    milliseconds of a plain run that has 0.1 s in all)."""

    def __init__(self, grid: str, fine: str, errors: dict[str, float], end_fractions: dict[str, tuple[float, float]],
                 wall_time_s: float, suggest: str = "", notes: list[str] | None = None):
        self.grid = grid                      # the run's grid, e.g. "classes 10"
        self.fine = fine                      # the check's grid
        self.errors = errors                  # summary key -> estimated relative grid error (signed)
        self.end_fractions = end_fractions    # "bed.top_class" -> (final on the run's grid, on the fine one)
        self.wall_time_s = wall_time_s
        self.suggest = suggest                # e.g. "classes >= 80"
        self.notes = list(notes or [])

    def __repr__(self) -> str:
        return f"GridCheck(grid={self.grid!r}, fine={self.fine!r}, errors={self.errors!r}, suggest={self.suggest!r})"

    def end_cause(self, name: str) -> str | None:
        """"coarse" (smearing: the fraction vanishes when extrapolated to a fine grid), "range" (it stays), or
        None (not checked)."""
        if name not in self.end_fractions:
            return None
        f1, f2 = self.end_fractions[name]
        return "coarse" if 2 * f2 - f1 < 0.5 * max(f2, 1e-300) or f2 < 0.6 * f1 else "range"

    def warnings(self) -> list[str]:
        bad = {k: e for k, e in self.errors.items() if abs(e) > THRESHOLD}
        if not bad:
            return []
        parts = ", ".join(f"{display_name(k, '')[0]} ≈ {100 * e:+.2g} %" for k, e in
                          sorted(bad.items(), key=lambda x: -abs(x[1])))
        return [f"grid error on {self.grid} (first-order estimate from a solve on {self.fine}): {parts}; "
                f"use accuracy: {CURE_TARGET} or {self.suggest} (--no-grid-check skips this check)"]

    def to_json(self) -> dict:
        return {"grid": self.grid, "fine_grid": self.fine, "threshold": THRESHOLD, "order_assumed": 1,
                "errors": {k: (e if math.isfinite(e) else None) for k, e in self.errors.items()},
                "end_fractions": {k: {"grid": a, "fine_grid": b} for k, (a, b) in self.end_fractions.items()},
                "suggest": self.suggest, "wall_time_s": self.wall_time_s, "notes": list(self.notes)}


class Ahead:
    """The check's solve started before the run's, on a thread of its own: both solves release the GIL, so on a
    second core the run's solve costs the check no wall time (a tenth of a plain `granuflow run`). It is given the
    run's own arguments, which give the fine solve the run's output times and tolerances; :func:`check` uses it only
    where they match the result's (a run a stop event ended early does not), and solves again otherwise. The finer
    flowsheet is made here, in the caller's thread, before the run starts on the flowsheet it reads."""

    def __init__(self, fs, **kw):
        import threading

        self.fine_fs = fs.refined(2)
        self.fine = None
        self.cancelled = False
        self.t0 = time.perf_counter()
        self._kw = kw
        self._thread = threading.Thread(target=self._solve, name="granuflow grid check", daemon=True)
        self._thread.start()

    def _solve(self) -> None:
        if self.cancelled:
            return
        try:
            self.fine = self.fine_fs.simulate(**self._kw, warn=False, accuracy=False, grid_check=False)
        except (Exception, KeyboardInterrupt):  # noqa: BLE001 - check() solves again and reports what fails there
            # (an interrupt of the run stops this solve too: the caller's thread raises it)
            self.fine = None

    def cancel(self) -> None:
        """Stops the solve (an interrupt the caller's thread raised in Python, where the core's runs do not see it)."""
        self.cancelled = True
        _core.interrupt()

    def join(self) -> None:
        self._thread.join()

    def result_for(self, res):
        """(finer flowsheet, its result) when the solve ran on the result's output times and tolerances, else None."""
        self.join()
        f = self.fine
        if f is None or f.rtol != res.rtol or f.atol != res.atol or f._t_list() != res._t_list():
            return None
        return self.fine_fs, f


def check(fs, res, ahead: Ahead | None = None, **kw) -> GridCheck | None:
    """The grid check of ``res`` (a result of ``fs``); None when the scene has no size grid. ``ahead``: the check's
    solve, started before the run (:class:`Ahead`)."""
    if fs.grid() is None:
        return None
    t0 = time.perf_counter()
    done = ahead.result_for(res) if ahead is not None else None
    if done is not None:
        (fine_fs, fine), t0 = done, ahead.t0
    else:
        try:
            fine_fs = fs.refined(2)
            fine = fine_fs.simulate(**dict(kw, t_end=res._t_at(-1), t_out=res._t_list(), rtol=res.rtol,
                                           atol=res.atol), warn=False, accuracy=False, grid_check=False)
        except (_core.ConfigError, _core.SolverError) as e:
            return GridCheck(fs.grid_label(), "", {}, {}, time.perf_counter() - t0,
                             notes=[f"no grid check: {' '.join(str(e).split())}"])
    skip = not_corresponding(res, [fine])
    s1, s2 = res.summary_values(), fine.summary_values()
    errors = {}
    for k, v in s1.items():
        if fs.summary_map.get(k, "") in skip or not isinstance(v, (int, float)) or s2.get(k) is None or not v:
            continue
        errors[k] = 2.0 * (v - s2[k]) / abs(v)
    e1, e2 = res.grid_ends(), fine.grid_ends()
    ends = {k: (e1[k]["final"], e2[k]["final"]) for k in e1 if k.endswith("top_class") and k in e2}
    worst = max((abs(e) for e in errors.values()), default=0.0)
    g = fs.grid()
    factor = max(worst / THRESHOLD, 1.0)
    if g.get("grid") == "geometric":
        suggest = f"q >= {math.ceil(int(g['q']) * factor)}"
    else:
        suggest = f"classes >= {math.ceil((int(g['classes']) - 1) * factor) + 1}"
    return GridCheck(fs.grid_label(), fine_fs.grid_label(), errors, ends, time.perf_counter() - t0, suggest)
