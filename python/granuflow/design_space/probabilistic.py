"""Probabilistic design space: P(all constraints met) under parameter uncertainty."""
from __future__ import annotations

import math
import time
from dataclasses import dataclass
from typing import Any, Mapping, Sequence

import numpy as np

from .. import _core, outputs, sweep
from ..flowsheet import Flowsheet
from ..quantity import conversion
from .axes import Axis, map_axes, map_sim_kwargs, parse_constraints
from .contour import FeasibleWindow, feasible_window, grid_points

ConfigError = _core.ConfigError
SolverError = _core.SolverError


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
    smap = fs.summary_map
    if name in smap:
        si = fs.unit_of(smap[name])
        return smap[name], conversion(outputs.summary_unit(name, si), si)[0]
    return name, 1.0


class _LinearizedPoint:
    """Executor task of the linear method: nominal outputs and their Jacobian w.r.t. the uncertain parameters at one
    grid point (picklable, so it runs on Dask workers too)."""

    def __init__(self, base, params, outputs, sources, sim_kwargs, steps, use_core):
        self.base, self.params, self.outputs, self.sources = base, params, outputs, sources
        self.sim_kwargs, self.steps, self.use_core = sim_kwargs, steps, use_core

    def _values(self, fs) -> dict:
        return sweep.final_values(fs.simulate(**self.sim_kwargs, warn=False), self.outputs)

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
                dz = fs.output_sensitivities(list(self.params), t_end=t_end)
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
                               sensitivities: str = "auto") -> ProbabilityMap:
    """Probability that every constraint is met at each operating point when the model parameters ``params`` are
    normally distributed with ``mean`` (default: the flowsheet's values) and ``covariance`` (SI units, e.g. from a
    calibration).

    ``method="linear"``: the outputs are linearized in the parameters at every grid point, z ~ N(z0, J C J^T);
    P is the fraction of ``n_samples`` (default 20 000) draws of that normal distribution meeting all constraints
    (the same draws at every point, fixed ``seed``: the map is smooth and reproducible, and exactly 0 or 1 where
    the margin is many standard deviations). J comes from forward sensitivities (``Flowsheet.output_sensitivities``:
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
    fs, ax, ay = map_axes(flowsheet, x, y, fixed, t_end)
    cons = parse_constraints(constraints)
    if not cons:
        raise ConfigError("constraints: give at least one (e.g. {'d50_um': ('>=', 400)})")
    sweep.check_outputs(fs, [c.output for c in cons], where="constraints")
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
        sweep.file.set_or_raise(fs, p, float(m), f"mean[{p}]")
    rng = np.random.default_rng(seed)
    outputs = list(dict.fromkeys(c.output for c in cons))
    shape = (len(ay.values), len(ax.values))
    grid_pts = grid_points(ax, ay)
    sim_kwargs = map_sim_kwargs(simulate)
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
    task = _LinearizedPoint(base, params, outputs, sources, sim_kwargs, steps, use_core)
    rows = sweep.runner.collect(sweep.make_executor(executor, workers), task, fs, list(enumerate(grid_pts)), progress,
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
