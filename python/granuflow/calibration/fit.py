"""Staged calibration (Ceres in the C++ core), predictions and multi-start."""
from __future__ import annotations

import concurrent.futures as cf
import math
import os
from typing import Any, Iterable, Mapping, Sequence

import numpy as np

from .. import _core
from .. import progress as progress_bars
from ..flowsheet import Flowsheet
from .files import Experiment, Stage, StagePlan, all_free

ConfigError = _core.ConfigError
CalibrationError = _core.CalibrationError
# the columns of an estimates table (estimates.csv), after the parameter's name
ESTIMATE_COLUMNS = ("start", "value", "se", "rel_se", "transform", "lower", "upper", "at_bound", "identifiable", "flag")


class CalibrationResult:
    """The outcome of :func:`calibrate`: numpy arrays and dicts; DataFrames on request (pandas imported lazily).

    Attributes: ``stages`` (list of dicts: estimates, covariance, correlation, history), ``parameters`` (final
    values, SI), ``simulations``, ``sensitivity_solves``, ``wall_time_s``, ``status``, ``message``.
    """

    def __init__(self, raw: dict, *, label: str = ""):
        self.raw = raw
        self.label = label
        self.stages = raw["stages"]
        self.parameters = dict(raw["parameters"])
        self.simulations = int(raw["simulations"])
        self.sensitivity_solves = int(raw["sensitivity_solves"])
        self.wall_time_s = float(raw["wall_time_s"])
        self.status = raw["status"]
        self.message = raw["message"]
        # a stage left in a flat region of the loss, restarts from lower points, retried sensitivity solves, data no
        # stage uses; multi_start() adds how this start compares with the others
        self.warnings: list[str] = list(raw.get("warnings", []))

    def brief(self) -> str:
        return self.raw["brief"]

    def full_report(self) -> str:
        return self.raw["full_report"]

    def __repr__(self) -> str:
        return f"<granuflow.CalibrationResult {self.brief()}>"

    @property
    def final(self) -> dict:
        return self.stages[-1]

    @property
    def cost(self) -> float:
        return float(self.final["cost"])

    @property
    def flagged(self) -> list[str]:
        """Parameters of the last stage the data cannot identify (not reported as recovered)."""
        return [e["name"] for e in self.final["estimates"] if not e["identifiable"]]

    def estimate(self, name: str) -> dict:
        for e in self.final["estimates"]:
            if e["name"] == name:
                return e
        raise KeyError(name)

    def estimates_frame(self, stage: int | str = -1):
        import pandas as pd

        st = self._stage(stage)
        df = pd.DataFrame(st["estimates"]).set_index("name")
        return df[list(ESTIMATE_COLUMNS)]

    @property
    def estimates(self):
        """Final estimates: start, value, standard error (SI), relative SE, bounds, identifiability flag."""
        return self.estimates_frame(-1)

    @property
    def correlation(self):
        import pandas as pd

        st = self.final
        names = [e["name"] for e in st["estimates"]]
        return pd.DataFrame(np.asarray(st["correlation"]), index=names, columns=names)

    def history_rows(self) -> list[dict]:
        """:attr:`history` as one dict per stage (the stage's name under ``"stage"``)."""
        rows = []
        for s in self.stages:
            row = {"stage": s["name"], "observables": " ".join(s["observables"]) or "all",
                   "initial_cost": s["initial_cost"], "cost": s["cost"], "chi2_reduced": s["chi2_reduced"],
                   "residuals": s["residuals"], "iterations": s["iterations"], "passes": s["passes"],
                   "simulations": s["simulations"], "sensitivity_solves": s["sensitivity_solves"],
                   "wall_time_s": s["wall_time_s"], "jacobian": s["jacobian_method"], "termination": s["termination"]}
            for e in s["estimates"]:
                row[e["name"]] = e["value"]
            rows.append(row)
        return rows

    @property
    def history(self):
        """Stage by stage: cost, iterations, reweighting passes, simulations, sensitivity solves, time, parameters."""
        import pandas as pd

        return pd.DataFrame(self.history_rows()).set_index("stage")

    @property
    def profiles(self) -> list[dict]:
        return list(self.final["profiles"])

    def _stage(self, stage: int | str) -> dict:
        if isinstance(stage, str):
            for s in self.stages:
                if s["name"] == stage:
                    return s
            raise KeyError(stage)
        return self.stages[stage]

    def to_json(self) -> dict:
        def clean(x):
            if isinstance(x, dict):
                return {k: clean(v) for k, v in x.items()}
            if isinstance(x, (list, tuple)):
                return [clean(v) for v in x]
            if isinstance(x, np.ndarray):
                return clean(x.tolist())
            if isinstance(x, float) and not math.isfinite(x):
                return None
            return x

        return clean({k: v for k, v in self.raw.items() if k != "full_report"})


def _core_list(exps: Iterable[Experiment]) -> list[dict]:
    return [e.to_core() for e in exps]


def _options(options: Mapping[str, Any] | None) -> dict:
    # Every core: the experiments are solved in parallel, and the estimates do not depend on how many threads solve
    # them (Ceres itself runs on one); the core uses no more threads than there are experiments.
    return {"num_threads": os.cpu_count() or 1, **dict(options or {})}


def calibrate(flowsheet: Flowsheet, experiments: Sequence[Experiment], stages: Sequence[Stage] | StagePlan, *,
              start: Mapping[str, float] | None = None, options: Mapping[str, Any] | None = None,
              label: str = "", progress: bool | None = None) -> CalibrationResult:
    """Run the stages in order (each from the previous estimates) on the C++ core; the GIL is released.

    ``options``: CalibrationOptions fields (``num_threads`` default: the number of cores, ``sigma_basis``,
    ``jacobian``, ``rtol``, ``profile``, ...). Unknown keys raise ConfigError; a failed stage raises CalibrationError.
    ``progress``: a bar on stderr that names the stage, its Levenberg-Marquardt iteration, ½χ² and the simulations
    so far (None: only on a terminal). Ctrl-C ends the calibration with KeyboardInterrupt.
    """
    if isinstance(stages, StagePlan):
        start = {**stages.start, **dict(start or {})}
        options = {**stages.options, **dict(options or {})}
        stages = stages.stages
    bar = progress_bars.bar(progress, len(stages), "calibration", unit="stage")
    try:
        raw = flowsheet.calibrate_raw(_core_list(experiments), [s.to_core() for s in stages], _options(options),
                                      {k: float(v) for k, v in dict(start or {}).items()},
                                      _StageBar(bar, [s.name for s in stages]) if bar is not None else None)
    finally:
        if bar is not None:
            bar.close()
    return CalibrationResult(raw, label=label)


class _StageBar:
    """The core's progress reports (after every Ceres iteration) on a bar of the stages: the stage being solved, its
    iteration, ½χ² and the simulations of that least-squares solve; a profile or restart shows under its own name."""

    def __init__(self, bar, names: Sequence[str]):
        self.bar, self.names, self.done = bar, list(names), 0

    def __call__(self, stage: str, iteration: int, cost: float, simulations: int, sensitivity_solves: int) -> None:
        if stage in self.names:
            k = self.names.index(stage)
            if k > self.done:
                self.bar.update(k - self.done)
                self.done = k
        self.bar.set_postfix_str(f"{stage}: iteration {iteration}, ½χ² {cost:.6g}, "
                                 f"{simulations + sensitivity_solves} solves", refresh=True)


def predict(flowsheet: Flowsheet, experiments: Sequence[Experiment], params: Mapping[str, float] | None = None, *,
            options: Mapping[str, Any] | None = None) -> list[dict]:
    """Model at the sampled times: list of {experiment, observable, t, data, model, sigma} (SI)."""
    return flowsheet.predict_raw(_core_list(experiments), dict(params or {}), _options(options))


def stage_bounds(stages: Sequence[Stage] | StagePlan, flowsheet: Flowsheet | None = None) -> dict[str, tuple]:
    """Per free parameter (lower, upper) in SI that every stage freeing it accepts (the declared bounds of
    `flowsheet` where a stage gives none; ±inf without a flowsheet)."""
    if isinstance(stages, StagePlan):
        stages = stages.stages
    out: dict[str, tuple] = {}
    for s in stages:
        for f in s.free:
            spec = flowsheet.spec(f.name) if flowsheet is not None else {"lower": -math.inf, "upper": math.inf}
            lo = spec["lower"] if f.lower is None else f.lower
            hi = spec["upper"] if f.upper is None else f.upper
            plo, phi = out.get(f.name, (-math.inf, math.inf))
            out[f.name] = (max(lo, plo), min(hi, phi))
    return out


def random_starts(stages: Sequence[Stage] | StagePlan, n: int, *, center: Mapping[str, float], spread: float = 1.0,
                  seed: int | None = 0, flowsheet: Flowsheet | None = None) -> list[dict[str, float]]:
    """`n` start points: each free parameter drawn uniformly within ±`spread` of `center` (in ln units for
    log-transformed and logarithmic parameters, relative otherwise), clipped to the bounds of every stage that
    frees it (and to the declared bounds of `flowsheet`, when given)."""
    if isinstance(stages, StagePlan):
        stages = stages.stages
    bounds = stage_bounds(stages, flowsheet)
    rng = np.random.default_rng(seed)
    starts = []
    for _ in range(n):
        p = {}
        for f in all_free(stages):
            name = f.name
            c = float(center[name])
            u = rng.uniform(-spread, spread)
            if f.transform == "log":
                v = c * math.exp(u)
            elif f.logarithmic or (f.logarithmic is None and name.split(".")[-1].startswith("ln_")):
                v = c + u
            else:
                v = c * (1 + u)
            lo, hi = bounds[name]
            p[name] = min(max(v, lo), hi)
        starts.append(p)
    return starts


def multi_start(flowsheet: Flowsheet, experiments: Sequence[Experiment], stages: Sequence[Stage] | StagePlan,
                starts: Sequence[Mapping[str, float]], *, options: Mapping[str, Any] | None = None,
                workers: int | None = None, progress: bool | None = None) -> list[CalibrationResult | Exception]:
    """Calibrate from every start in parallel threads (each calibration single-threaded; the C++ side releases
    the GIL), with a tqdm progress bar on stderr (default: when stderr is a terminal). Returns the results in
    the order of `starts`; a start whose calibration failed gives its exception. Best: min by ``.cost``."""
    plan_opts: dict = {}
    plan_start: dict = {}
    if isinstance(stages, StagePlan):
        plan_opts, plan_start, stages = stages.options, stages.start, stages.stages
    workers = workers or min(len(starts), os.cpu_count() or 1)
    opts = {**plan_opts, **dict(options or {}), "num_threads": 1}
    bar = progress_bars.bar(progress, len(starts), "calibration starts", unit="start")
    results: list[CalibrationResult | Exception | None] = [None] * len(starts)

    def one(i: int):
        return calibrate(flowsheet, experiments, stages, start={**plan_start, **dict(starts[i])}, options=opts,
                         label=f"start {i}", progress=False)  # the starts have a bar of their own

    try:
        with cf.ThreadPoolExecutor(max_workers=workers, thread_name_prefix="granuflow-calib") as pool:
            futs = {pool.submit(one, i): i for i in range(len(starts))}
            try:
                for fut in cf.as_completed(futs):
                    i = futs[fut]
                    try:
                        results[i] = fut.result()
                    except (CalibrationError, _core.SolverError, ConfigError) as e:
                        results[i] = e
                    if bar is not None:
                        bar.update(1)
            except KeyboardInterrupt:  # the other starts stop as well (else the pool waits for them)
                for f in futs:
                    f.cancel()
                _core.interrupt()
                raise
    finally:  # an interrupted or failed multi-start leaves no bar behind (tqdm would draw the next one below it)
        if bar is not None:
            bar.close()
    return results  # type: ignore[return-value]


def best(results: Sequence[CalibrationResult | Exception]) -> CalibrationResult:
    """The start of lowest final cost; it carries :func:`compare_starts`' verdict in its warnings."""
    ok = [r for r in results if isinstance(r, CalibrationResult)]
    if not ok:
        raise CalibrationError(f"every start failed; first: {results[0] if results else 'no starts'}")
    winner = min(ok, key=lambda r: r.cost)
    for w in compare_starts(results):
        if w not in winner.warnings:
            winner.warnings.append(w)
    return winner


def compare_starts(results: Sequence[CalibrationResult | Exception], delta_chi2: float = 3.84) -> list[str]:
    """What the starts of a multi-start say together: the starts that failed, and those that ended more than
    ``delta_chi2`` (χ², default the 95 % level of one parameter) above the best, each a local minimum or a flat
    region the calibration could not leave (their estimates are not the answer)."""
    ok = [r for r in results if isinstance(r, CalibrationResult)]
    out = []
    failed = [i for i, r in enumerate(results) if not isinstance(r, CalibrationResult)]
    if failed:
        first = " ".join(str(results[failed[0]]).split())
        out.append(f"{len(failed)} of {len(results)} starts failed (start {', '.join(map(str, failed[:6]))}"
                   f"{', ...' if len(failed) > 6 else ''}); first: {first[:200]}")
    if len(ok) < 2:
        return out
    low = min(r.cost for r in ok)
    above = [(r.label or f"start {i}", 2 * (r.cost - low)) for i, r in enumerate(results)
             if isinstance(r, CalibrationResult) and 2 * (r.cost - low) > delta_chi2]
    if above:
        shown = ", ".join(f"{name} (Δχ² = {d:.3g})" for name, d in above[:6]) + (", ..." if len(above) > 6 else "")
        out.append(f"{len(above)} of {len(ok)} starts ended more than Δχ² = {delta_chi2:g} above the best: {shown}; "
                   "each stopped in a local minimum or a flat region of the loss")
    return out
