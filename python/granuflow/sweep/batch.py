"""Sweep points solved in the C++ core, many per call (``_core.sweep_batch``): the threads solve with the GIL
released and each point is reduced in C++ to its row (the wanted final values, null where ``Result.summary`` is
null, and ``Result.warnings`` or the failure), so the interpreter never runs per point. The rows are bit-identical
to the per-point path (``run_sweep(..., batch=False)``: ``Flowsheet.simulate``, ``final_values``,
``Result.warnings``; tests/python/test_sweep_batch.py).

What the batch does not do goes through the per-point path: steady states, error estimates, ``raise_errors``, scenes
with an accuracy target (several solves a point) or with events (their unfired-event check reads the scene in
Python), solver keywords beyond t_end, t_out, n_out, rtol, atol, linear_solver, max_steps and method, and point values
that are not plain numbers (strings with a unit are parsed per point).
"""
from __future__ import annotations

import math
from numbers import Real
from typing import Any, Mapping, Sequence

from .. import _core, outputs as roles
from ..flowsheet import Flowsheet, sweep_batch_raw
from .executors import STATUS_FAILED, STATUS_OK

SIM_KEYS = ("t_end", "t_out", "n_out", "rtol", "atol", "linear_solver", "max_steps", "method")
# the constants of granuflow.outputs the C++ reductions use (defined there only)
RULES = {k: getattr(roles, k) for k in ("STANDARD_SUMMARY_KEYS", "BALANCE_QUANTITIES", "GRID_END_WARNING",
                                        "BALANCE_WARN_MIN", "BALANCE_WARN_FACTOR", "BALANCE_WARN_MAX", "BALANCE_FAIL")}


def _plain(v) -> bool:
    """A number the core takes as it is (SI), as Flowsheet.set would."""
    return isinstance(v, Real) and not isinstance(v, bool) and type(v).__name__ != "bool_"


def _plain_time(v) -> bool:
    return _plain(v) and math.isfinite(v) and v > 0


def _sim_ok(kw: Mapping[str, Any]) -> bool:
    """The solver keywords are ones the batch passes to the core unchanged (else simulate() checks them)."""
    for k, v in kw.items():
        if k not in SIM_KEYS:
            return False
        if v is None:
            continue
        if k == "t_end" and not _plain_time(v):
            return False
        if k in ("n_out", "max_steps") and not (isinstance(v, int) and not isinstance(v, bool)):
            return False
        if k in ("rtol", "atol") and not (_plain(v) and math.isfinite(v)):
            return False
        if k == "t_out" and not (isinstance(v, (list, tuple)) and v and all(_plain(t) and math.isfinite(t) for t in v)):
            return False
        if k in ("linear_solver", "method") and not isinstance(v, str):
            return False
    return True


def _in_order(point: Mapping, order: dict) -> bool:
    """The point names its parameters in the order they are set (the batch sets them in ``order``)."""
    pos = [order[k] for k in point]
    return pos == sorted(pos)


class BatchEvaluate:
    """An ``evaluate`` for the executors that also solves many points at once: ``batch(flowsheets, items)`` runs
    ``items`` (``(i, point)``) on ``len(flowsheets)`` threads, one flowsheet each. Calling it evaluates one point."""

    def __init__(self, params: Sequence[str], base: Mapping[str, float], outputs: Sequence[str],
                 sim_kwargs: Mapping[str, Any]):
        self.params, self.outputs = list(params), list(outputs)
        self.base = [float(base[k]) for k in self.params]
        self.sim_kwargs = {k: (list(v) if k == "t_out" else v) for k, v in sim_kwargs.items() if v is not None}
        self.on_progress = None  # called with the count of finished points of a running batch (a progress bar)

    def __getstate__(self):  # shipped to Dask workers without the local progress bar
        return {**self.__dict__, "on_progress": None}

    def __call__(self, fs: Flowsheet, item) -> dict:
        return self.batch([fs], [item])[0]

    def batch(self, flowsheets: Sequence[Flowsheet], items: Sequence[tuple[int, Mapping]]) -> list[dict]:
        import numpy as np

        col = {k: j for j, k in enumerate(self.params)}
        values = np.zeros((len(items), len(self.params)))
        given = np.zeros((len(items), len(self.params)), dtype=bool)
        for r, (_, point) in enumerate(items):
            for k, v in point.items():
                values[r, col[k]], given[r, col[k]] = v, True
        out = sweep_batch_raw(flowsheets, self.params, self.base, values, given, self.outputs, self.sim_kwargs, RULES,
                              self.on_progress)
        vals, prm, msgs = out["values"].tolist(), out["params"].tolist(), out["message"]
        rows = []
        for r, (i, _) in enumerate(items):
            row: dict[str, Any] = {"_i": i}
            if out["params_set"][r]:
                row.update(zip(self.params, prm[r]))
            if out["ok"][r]:
                row.update(zip(self.outputs, vals[r]))
                row["solve_time_s"] = float(out["solve_time_s"][r])
                row["status"], row["message"] = STATUS_OK, msgs[r]
            else:  # as the per-point path shows a SolverError or ConfigError
                row["status"], row["message"] = STATUS_FAILED, " ".join(msgs[r].split())
            row["wall_time_s"] = float(out["wall_time_s"][r])
            rows.append(row)
        return rows


def batch_evaluator(flowsheet: Flowsheet, points: Sequence[Mapping], params: Sequence[str], base: Mapping,
                    outputs: Sequence[str], sim_kwargs: Mapping[str, Any]) -> BatchEvaluate | None:
    """A :class:`BatchEvaluate` for these points, or None where the per-point path must run (module docstring)."""
    try:
        if flowsheet._accuracy_target(None) is not None:
            return None
    except _core.ConfigError:  # a scene accuracy the per-point path reports at every point
        return None
    if "events:" in flowsheet.text or not _sim_ok(sim_kwargs):
        return None
    order = {k: j for j, k in enumerate(params)}
    if not all(_plain(base[k]) for k in params):
        return None
    if not all(all(_plain(v) for v in p.values()) and _in_order(p, order) for p in points):
        return None
    return BatchEvaluate(params, base, outputs, sim_kwargs)
