"""Synthetic experiments and the paper-001 stages (Table 1 points, Fig. 10)."""
from __future__ import annotations

from typing import Any, Mapping, Sequence

import numpy as np

from .. import _core
from ..flowsheet import Flowsheet
from ..quantity import to_si
from .files import Experiment, ExperimentSet, FreeParameter, Observation, Stage, StagePlan, sigma_entry
from .paper001 import D_VALUES, TABLE1_LEVELS, TABLE5_SIGMA

ConfigError = _core.ConfigError


def table1_points() -> list[dict]:
    """The 15 runs of paper 001, Table 1: 8 cube corners (calibration), 6 face centres and the centre (validation).

    Each item: {"name", "kind", "use", "set": {param: "value unit"}}."""
    (vu, V), (tu, T), (mu, M) = (TABLE1_LEVELS[k] for k in ("inlet.V_dot", "inlet.T", "nozzle.mdot"))
    pts = []
    k = 0
    for m in (M[0], M[2]):
        for t in (T[0], T[2]):
            for v in (V[0], V[2]):
                k += 1
                pts.append((f"C{k}", "corner", v, t, m))
    faces = [(V[0], T[1], M[1]), (V[2], T[1], M[1]), (V[1], T[0], M[1]), (V[1], T[2], M[1]), (V[1], T[1], M[0]),
             (V[1], T[1], M[2])]
    pts += [(f"F{i + 1}", "face", *f) for i, f in enumerate(faces)]
    pts.append(("Z", "centre", V[1], T[1], M[1]))
    return [{"name": n, "kind": kind, "use": "calibration" if kind == "corner" else "validation",
             "set": {"inlet.V_dot": f"{v:g} {vu}", "inlet.T": f"{t:g} {tu}", "nozzle.mdot": f"{m:g} {mu}"}}
            for n, kind, v, t, m in pts]


def synthetic_experiments(flowsheet: Flowsheet, points: Sequence[Mapping], params: Mapping[str, float] | None = None,
                          *, times: Sequence[float] | None = None, observables: Sequence[str] | None = None,
                          sigma: Mapping[str, Mapping[str, float]] | None = None, seed: int | None = 0,
                          noise: bool = True, name: str = "synthetic", workers: int = 2,
                          options: Mapping[str, Any] | None = None) -> ExperimentSet:
    """Experiments simulated with the flowsheet at `points` (see :func:`table1_points`) and parameters `params`
    (SI), sampled at `times` (s; default every 5 min to 60 min), with Gaussian noise at `sigma` (default
    :data:`TABLE5_SIGMA`): data = model + sigma_abs * N(0,1), or model * (1 + sigma_rel * N(0,1)). `options`: the
    calibration options the simulations run with (for example a tighter ``rtol`` for noise-free checks)."""
    if options and "num_threads" in options:
        raise ConfigError(f"synthetic_experiments: options num_threads = {options['num_threads']!r} would override "
                          f"workers = {workers}; give the thread count as workers only")
    sigma = dict(sigma or TABLE5_SIGMA)
    observables = list(observables or (["gas.T", "bed.moisture"] + list(D_VALUES)))
    times = np.asarray(times if times is not None else np.arange(5, 61, 5) * 60.0, dtype=float)
    rng = np.random.default_rng(seed)
    exps = []
    for p in points:
        settings = {k: to_si(v, flowsheet.spec(k)["unit"], f"point {p.get('name')}.{k}") for k, v in p["set"].items()}
        obs = []
        for o in observables:
            if o not in sigma:
                raise ConfigError(f"sigma: no entry for observable {o} (given: {', '.join(sigma)})")
            si_unit = flowsheet.unit_of(o)
            sa, sr = sigma_entry(sigma[o], si_unit, f"sigma.{o}")
            obs.append(Observation(o, times.copy(), np.zeros(len(times)), sa, sr))
        exps.append(Experiment(str(p.get("name")), settings, obs, float(times[-1]), str(p.get("kind", "")),
                               str(p.get("use", "calibration"))))
    pred = flowsheet.predict_raw([e.to_core() for e in exps], dict(params or {}),
                                 {"num_threads": workers, **dict(options or {})})
    by = {(q["experiment"], q["observable"]): np.asarray(q["model"]) for q in pred}
    for e in exps:  # noise drawn in a fixed order: experiment, observable, time
        for o in e.observations:
            m = by[(e.name, o.name)]
            z = rng.standard_normal(len(m)) if noise else np.zeros(len(m))
            o.value = m + o.sigma_abs * z if o.sigma_abs > 0 else m * (1 + o.sigma_rel * z)
    return ExperimentSet(name, exps, flowsheet.path, f"synthetic: {len(exps)} runs, seed {seed}")


def paper001_stages() -> StagePlan:
    """The staged route of paper 001, Fig. 10, for the headline scene (the bounds of stages_paper001.yaml)."""
    hmt = [FreeParameter("wall.k_wall", "log", 1.0, 200.0), FreeParameter("droplets.k_evap", "log", 1e-5, 1.0),
           FreeParameter("bed.X_cr", "log", 0.01, 0.5)]
    size = [FreeParameter("bed.agg_ln_beta0", "none", -25.0, -10.0),
            FreeParameter("spray_zone.h_pen", "log", 1e-5, 5e-3), FreeParameter("bed.sel_k_break", "log", 1e-6, 1.0)]
    return StagePlan("paper001_fig10", [Stage("heat_and_mass_transfer", hmt, ["gas.T", "bed.moisture"]),
                                        Stage("size", size, list(D_VALUES)), Stage("all", hmt + size, [])])
