"""The generic runner: simulate a flowsheet once per point and collect final values."""
from __future__ import annotations

import math
import time
from typing import Any, Callable, Mapping, Sequence

from .. import _core, outputs as roles, progress as progress_bars, structure
from ..flowsheet import Flowsheet
from ..quantity import si_or_nan
from .executors import STATUS_FAILED, STATUS_OK, make_executor

ConfigError = _core.ConfigError
SolverError = _core.SolverError

DEFAULT_OUTPUTS = roles.DEFAULT_SWEEP_OUTPUTS

# ------------------------------------------------------------------------------------------------
# the generic runner
# ------------------------------------------------------------------------------------------------


def check_outputs(flowsheet: Flowsheet, outputs: Sequence[str], where: str = "outputs") -> list[str]:
    """``outputs`` if each is a summary key or a state/output name of the flowsheet; ConfigError naming ``where``."""
    summary_keys = flowsheet.summary_keys()
    names = set(flowsheet.state_names) | set(flowsheet.output_names)
    out = []
    for o in outputs:
        if not isinstance(o, str) or (o not in summary_keys and o not in names):
            raise ConfigError(f"{where}: '{o}' is neither a summary key of scene '{flowsheet.name}' "
                              f"(allowed: {', '.join(summary_keys)}) nor a state or output name (e.g. bed.T)")
        out.append(o)
    return out


def final_errors(res, outputs: Sequence[str]) -> dict[str, float]:
    """The estimated numerical error (total, signed; NaN where none) of ``outputs`` at the final time, as
    ``{"<output>_err": value}``, from a result simulated with ``error_estimate=True``."""
    ee = res.error_estimate
    out = {}
    for o in outputs:
        if o in ee.outputs:
            v = ee.outputs[o].total
        else:
            series = ee.error(o)
            v = float(series[-1]) if series is not None else math.nan
        out[error_column(o)] = float(v) if v is not None else math.nan
    return out


def error_column(output: str) -> str:
    """The column of an output's estimated numerical error: ``d50_um`` -> ``d50_um_err``."""
    return f"{output}_err"


def final_values(res, outputs: Sequence[str]) -> dict[str, float]:
    """``outputs`` of a result at its final time: summary keys, else states and reported outputs; NaN where the
    summary has no value (null in summary.json)."""
    # The summary's numbers without the rest of Result.summary (a sweep point's Python time is the GIL's): the
    # core's values, null where a percentile lies in an end class of the size grid (as in summary.json).
    values, clipped = res.summary_values(), res.end_class_percentiles()
    out = {}
    for o in outputs:
        if o in values or o in roles.STANDARD_SUMMARY_KEYS:
            v = None if o in clipped else values.get(o)
        else:
            v = float(res[o][-1])
        out[o] = math.nan if v is None else float(v)
    return out


def collect(exe, evaluate: Callable[[Flowsheet, Any], dict], flowsheet: Flowsheet, items: Sequence[Any],
            progress: bool | None, desc: str) -> list[dict]:
    """The rows of ``exe.map_unordered(evaluate, flowsheet, items)`` in the order of ``items``, with a progress bar
    counting the failed ones. Items are ``(i, ...)`` and every row carries ``"_i": i`` and ``"status"``."""
    bar = progress_bars.bar(progress, len(items), desc)
    rows = []
    n_failed = 0
    if bar is not None and hasattr(evaluate, "batch"):  # a batch counts its points while it runs
        evaluate.on_progress = lambda k: bar.update(k - bar.n) if k > bar.n else None
    try:
        for row in exe.map_unordered(evaluate, flowsheet, items):
            rows.append(row)
            n_failed += row["status"] != STATUS_OK
            if bar is not None:
                if len(rows) > bar.n:
                    bar.update(len(rows) - bar.n)
                if n_failed:
                    bar.set_postfix(failed=n_failed)
    finally:
        if hasattr(evaluate, "batch"):
            evaluate.on_progress = None
        if bar is not None:
            bar.refresh()  # tqdm throttles redraws: show the final count before the bar goes
            bar.close()
    rows.sort(key=lambda r: r["_i"])
    return rows


def run_sweep(flowsheet: Flowsheet, points: Sequence[Mapping[str, float | str]],
              outputs: Sequence[str] = DEFAULT_OUTPUTS, *, names: Sequence[str] | None = None,
              workers: int | None = None, progress: bool | None = None, executor: str | Any = "threads",
              t_end: float | None = None, raise_errors: bool = False, simulate: Mapping[str, Any] | None = None,
              desc: str = "sweep", error_estimate: bool = False, steady: bool = False, batch: bool = True):
    """Simulate ``flowsheet`` once per point and collect ``outputs``.

    ``points``: one mapping per run, ``{"unit.param": value}`` with SI floats or strings with a unit; parameters
    not named keep the flowsheet's value. ``outputs``: summary keys (``d50_um``, ...) or state/output names (final
    value). Returns a pandas DataFrame, one row per point in the order given: ``point`` (``names[i]`` or ``i``),
    one column per parameter (its SI value), the outputs, ``wall_time_s`` (this point, including setup),
    ``solve_time_s`` (the integrator alone), ``status`` ("ok" or "failed") and ``message`` (why a point failed, or
    what an ok point's result warns of: ``Result.warnings``).

    A point whose solve fails (``SolverError``) or whose values are rejected (``ConfigError``) is recorded with
    status "failed" and the message; with ``raise_errors=True`` the first failure is raised instead.
    ``progress``: tqdm bar on stderr (default: only when stderr is a terminal). ``simulate``: keyword arguments
    of ``Flowsheet.simulate`` (``rtol``, ``atol``, ...). ``error_estimate``: every point re-solved as
    ``simulate(error_estimate=True)`` (four solves instead of one), and a column ``<output>_err`` per output with its
    estimated numerical error (signed: value minus the converged answer; granuflow.accuracy). ``steady``: solve each
    point's steady state (:func:`granuflow.steady.steady_values`, inputs at t = 0) instead of simulating; a point
    without one fails (error estimates are not made for steady states). ``batch`` (default): plain runs are solved
    and reduced to their rows in the C++ core, many points per call, without the interpreter per point
    (:mod:`granuflow.sweep.batch`; the same rows as ``batch=False``, which takes every point through
    ``Flowsheet.simulate`` and ``Result``).
    """
    import numpy as np
    import pandas as pd

    points = [dict(p) for p in points]
    if names is None:
        names = list(range(len(points)))
    if len(names) != len(points):
        raise ConfigError(f"names: {len(names)} names for {len(points)} points")
    outputs = check_outputs(flowsheet, list(outputs))
    params = list(dict.fromkeys(k for p in points for k in p))
    structural = [k for k in params if structure.is_setting(flowsheet, k, next(p[k] for p in points if k in p))]
    if structural:  # settings shape the flowsheet: one build per structure, its points on it
        return _run_by_structure(flowsheet, points, outputs, structural, names, raise_errors=raise_errors,
                                 workers=workers, progress=progress, executor=executor, t_end=t_end,
                                 simulate=simulate, desc=desc, error_estimate=error_estimate, steady=steady,
                                 batch=batch)
    known = set(flowsheet.params)
    for k in params:
        if k not in known:
            raise ConfigError(f"unknown parameter '{k}' (parameters: {', '.join(flowsheet.params)})")
    sim_kwargs = dict(simulate or {})
    if t_end is not None:
        sim_kwargs["t_end"] = float(t_end)
    base = {k: flowsheet.get(k) for k in params}

    def evaluate(fs: Flowsheet, item) -> dict:
        i, point = item
        t0 = time.perf_counter()
        row: dict[str, Any] = {"_i": i}
        try:
            fs.update(base)  # a worker's clone may carry the previous point's values
            fs.update(point)
            for k in params:
                row[k] = fs.get(k)
            if steady:
                from ..steady import steady_values

                t1 = time.perf_counter()
                row.update(steady_values(fs, outputs))
                if error_estimate:
                    row.update({error_column(o): float("nan") for o in outputs})
                row["solve_time_s"] = time.perf_counter() - t1
                row["status"], row["message"] = STATUS_OK, ""
            else:
                res = fs.simulate(**sim_kwargs, warn=False, error_estimate=bool(error_estimate))
                row.update(final_values(res, outputs))
                if error_estimate:
                    row.update(final_errors(res, outputs))
                row["solve_time_s"] = res.wall_time_s
                # an ok point's message holds what its result warns of (a size grid that clips the distribution)
                row["status"], row["message"] = STATUS_OK, "; ".join(f"warning: {w}" for w in res.warnings)
        except (SolverError, ConfigError) as e:
            if raise_errors:
                raise
            row["status"], row["message"] = STATUS_FAILED, " ".join(str(e).split())
        row["wall_time_s"] = time.perf_counter() - t0
        return row

    if batch and not (steady or error_estimate or raise_errors):
        from .batch import batch_evaluator

        evaluate = batch_evaluator(flowsheet, points, params, base, outputs, sim_kwargs) or evaluate
    rows = collect(make_executor(executor, workers), evaluate, flowsheet, list(enumerate(points)), progress, desc)
    errs = [error_column(o) for o in outputs] if error_estimate else []
    cols = ["point"] + params + outputs + errs + ["wall_time_s", "solve_time_s", "status", "message"]
    data = []
    for r in rows:
        d = {c: r.get(c, np.nan) for c in cols}
        d["point"] = names[r["_i"]]
        if r["status"] != STATUS_OK:  # parameter values as requested, where they could be read
            for k in params:
                if isinstance(d[k], float) and math.isnan(d[k]):
                    d[k] = si_or_nan(points[r["_i"]].get(k, base[k]), flowsheet.spec(k)["unit"], k)
        data.append(d)
    df = pd.DataFrame(data, columns=cols)
    df.attrs["units"] = {**{k: flowsheet.spec(k)["unit"] for k in params},
                         **{o: flowsheet.value_unit(o) for o in outputs},
                         **{error_column(o): flowsheet.value_unit(o) for o in outputs if error_estimate},
                         "wall_time_s": "s", "solve_time_s": "s"}
    return df


def _run_by_structure(flowsheet: Flowsheet, points: list[dict], outputs: list[str], structural: list[str],
                      names: Sequence, *, raise_errors: bool, **kwargs):
    """:func:`run_sweep` over points that also set unit settings (``particles.classes``): the points are grouped
    by their settings, every group runs on its own flowsheet built once (points sharing a structure share the
    build), and the rows come back in the order of ``points`` with one column per setting (its value as given)."""
    import numpy as np
    import pandas as pd

    groups: dict[tuple, list[int]] = {}
    for i, p in enumerate(points):
        groups.setdefault(tuple((k, structure.setting_text(p[k])) for k in structural if k in p), []).append(i)
    frames = []
    for key, idx in groups.items():
        settings = dict(key)
        try:
            fs = structure.with_settings(flowsheet, settings, "point")
            sub = run_sweep(fs, [{k: v for k, v in points[i].items() if k not in structural} for i in idx], outputs,
                            names=[names[i] for i in idx], raise_errors=raise_errors,
                            **{**kwargs, "desc": f"{kwargs['desc']} ({', '.join(f'{k}={v}' for k, v in key)})"})
        except ConfigError as e:  # a structure the loader refuses: its points fail, the others run
            if raise_errors:
                raise
            sub = pd.DataFrame({"point": [names[i] for i in idx], **{o: np.nan for o in outputs},
                                "status": STATUS_FAILED, "message": " ".join(str(e).split())})
        for j, k in enumerate(structural):
            sub.insert(1 + j, k, [points[i].get(k) for i in idx])
        sub["_i"] = idx
        frames.append(sub)
    units = next((f.attrs["units"] for f in frames if f.attrs.get("units")), {})
    df = pd.concat(frames, ignore_index=True).sort_values("_i").drop(columns="_i").reset_index(drop=True)
    df.attrs["units"] = {**{k: "" for k in structural}, **units}
    return df
