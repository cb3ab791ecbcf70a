"""Constrained optimization of operating variables with NLopt."""
from __future__ import annotations

import math
import re
import time
from dataclasses import dataclass
from typing import Any, Mapping

import numpy as np

from .. import _core, sweep
from ..flowsheet import Flowsheet
from .axes import T_END, fixed_flowsheet, make_axis, map_sim_kwargs, parse_constraints

ConfigError = _core.ConfigError
SolverError = _core.SolverError

# algorithms that take inequality constraints themselves; AUGLAG* wrap a local algorithm and add them
_CONSTRAINED = {"LN_COBYLA", "LD_MMA", "LD_CCSAQ", "LD_SLSQP", "GN_ISRES", "GN_ORIG_DIRECT", "GN_ORIG_DIRECT_L",
                "GN_AGS", "AUGLAG", "AUGLAG_EQ", "LN_AUGLAG", "LN_AUGLAG_EQ", "LD_AUGLAG", "LD_AUGLAG_EQ"}
_NEEDS_LOCAL = {"AUGLAG", "AUGLAG_EQ", "LN_AUGLAG", "LN_AUGLAG_EQ", "LD_AUGLAG", "LD_AUGLAG_EQ", "G_MLSL",
                "G_MLSL_LDS", "GN_MLSL", "GN_MLSL_LDS", "GD_MLSL", "GD_MLSL_LDS"}
_C_SAFETY = 1e-6  # relative margin NLopt is asked to keep (solver noise at rtol 1e-6 is of that order)
_RESULTS = ("SUCCESS", "STOPVAL_REACHED", "FTOL_REACHED", "XTOL_REACHED", "MAXEVAL_REACHED", "MAXTIME_REACHED",
            "FAILURE", "INVALID_ARGS", "OUT_OF_MEMORY", "ROUNDOFF_LIMITED", "FORCED_STOP")


def _nlopt():
    try:
        import nlopt
    except ImportError:
        raise ImportError("granuflow.design_space.optimize needs NLopt's Python bindings: "
                          "apt-get install python3-nlopt") from None
    return nlopt


def nlopt_algorithms() -> dict:
    """NLopt's algorithms by name -> description, e.g. ``{"LN_COBYLA": "COBYLA (...)", ...}``. Prefixes: G global,
    L local; N derivative-free, D gradient-based (gradients by forward differences here)."""
    nlopt = _nlopt()
    names = [n for n in dir(nlopt) if re.match(r"^(G|L)[ND]?_[A-Z0-9_]+$", n) or n.startswith("AUGLAG")]
    return {n: nlopt.algorithm_name(getattr(nlopt, n)) for n in sorted(names)}


def _algorithm(name: str, role: str = "algorithm"):
    algos = nlopt_algorithms()
    if not isinstance(name, str) or name.upper() not in algos:
        local = ", ".join(n for n in algos if n.startswith("L"))
        glob = ", ".join(n for n in algos if n.startswith("G"))
        other = ", ".join(n for n in algos if n.startswith("A"))
        raise ConfigError(f"{role} = {name!r}: unknown NLopt algorithm (local: {local}; global: {glob}; "
                          f"augmented Lagrangian: {other})")
    return name.upper()


@dataclass(frozen=True)
class OptimizationResult:
    """The outcome of :func:`optimize`.

    ``x``: the optimum, variable -> value in its edge unit (``x_si`` in SI); ``value``: the objective there;
    ``outputs``: the simulated outputs there; ``constraints``: str(constraint) -> {"value", "margin", "met"};
    ``feasible``: all met; ``n_simulations``: simulations run (including finite-difference gradients);
    ``nlopt_result``: NLopt's result code as text (``XTOL_REACHED``, ``MAXEVAL_REACHED``, ... or the exception
    NLopt stopped with, e.g. ``ROUNDOFF_LIMITED``); ``history``: every evaluation as a DataFrame."""

    x: dict
    x_si: dict
    units: dict
    objective: str
    maximize: bool
    value: float
    outputs: dict
    constraints: dict
    feasible: bool
    n_simulations: int
    n_evaluations: int
    nlopt_result: str
    message: str
    algorithm: str
    local_algorithm: str | None
    wall_time_s: float
    history: Any = None

    def __repr__(self) -> str:
        xs = ", ".join(f"{k} = {v:.5g} {self.units[k]}".rstrip() for k, v in self.x.items())
        return (f"<OptimizationResult {self.algorithm}: {'max' if self.maximize else 'min'} {self.objective} = "
                f"{self.value:.6g} at {xs}; feasible={self.feasible}; {self.n_simulations} simulations; "
                f"{self.nlopt_result}>")


class _Problem:
    """Evaluations in scaled variables u in [0, 1]^n, cached (NLopt asks the objective and each constraint at the
    same point)."""

    def __init__(self, fs, axes, objective, maximize, constraints, outputs, sim_kwargs):
        self.fs, self.axes, self.objective, self.maximize = fs, axes, objective, maximize
        self.constraints, self.outputs, self.sim_kwargs = constraints, outputs, sim_kwargs
        self.cache: dict[tuple, dict] = {}
        self.rows: list[dict] = []
        self.n_sim = 0
        self.worst = -math.inf if maximize else math.inf

    def si(self, u) -> dict:
        return {a.param: float(a.si[0] + (a.si[-1] - a.si[0]) * min(max(float(ui), 0.0), 1.0))
                for a, ui in zip(self.axes, u)}

    def evaluate(self, u, kind: str = "point") -> dict:
        key = tuple(float(v) for v in u)
        hit = self.cache.get(key)
        if hit is not None:
            return hit
        xs = self.si(u)
        kw = dict(self.sim_kwargs)
        row: dict[str, Any] = {"kind": kind}
        for a in self.axes:
            row[a.column] = float(a.from_si(xs[a.param]))
        status, message, values = sweep.STATUS_OK, "", {}
        try:
            for p, v in xs.items():
                if p == T_END:
                    kw["t_end"] = v
                else:
                    self.fs.set(p, v)
            if self.outputs:
                self.n_sim += 1
                values = sweep.final_values(self.fs.simulate(**kw, warn=False), self.outputs)
        except (SolverError, ConfigError) as e:
            status, message = sweep.STATUS_FAILED, " ".join(str(e).split())
            values = {o: math.nan for o in self.outputs}
        if self.objective in xs:
            axis = next(a for a in self.axes if a.param == self.objective)
            f = float(axis.from_si(xs[self.objective]))
        else:
            f = values.get(self.objective, math.nan)
        margins = [float(c.margin(values.get(c.output, math.nan))) for c in self.constraints]
        met = [bool(c.satisfied(values.get(c.output, math.nan))) for c in self.constraints]
        if math.isfinite(f):
            self.worst = min(self.worst, f) if self.maximize else max(self.worst, f)
        row.update(values)
        row.update({"objective": f, "feasible": all(met) and status == sweep.STATUS_OK, "status": status,
                    "message": message})
        rec = {"u": key, "f": f, "margins": margins, "met": met, "values": values, "status": status, "row": row}
        self.cache[key] = rec
        self.rows.append(row)
        return rec

    def f_for_nlopt(self, rec) -> float:
        """Objective as NLopt sees it: failures get the worst value seen, pushed further away."""
        f = rec["f"]
        if math.isfinite(f):
            return f
        w = self.worst if math.isfinite(self.worst) else 0.0
        return w - (abs(w) + 1.0) if self.maximize else w + (abs(w) + 1.0)

    @staticmethod
    def c_for_nlopt(rec, i) -> float:
        """Constraint i as NLopt wants it (<= 0 when met): minus the relative margin, shifted by _C_SAFETY so that
        a point NLopt ends on (active constraint) meets the constraint itself; failures count as violated."""
        m = rec["margins"][i]
        return _C_SAFETY - m if math.isfinite(m) else 1.0


def optimize(flowsheet: Flowsheet, objective: str, variables, constraints=None, *, maximize: bool = False,
             algorithm: str = "LN_COBYLA", local_algorithm: str | None = None, x0: Mapping[str, float] | None = None,
             fixed: Mapping[str, float | str] | None = None, t_end: float | str | None = None,
             xtol_rel: float = 1e-4, ftol_rel: float | None = None, maxeval: int = 200,
             maxtime: float | None = None, population: int | None = None, seed: int | None = 0,
             fd_step: float = 1e-3, simulate: Mapping[str, Any] | None = None) -> OptimizationResult:
    """Optimize ``objective`` over ``variables`` subject to ``constraints`` on outputs, with NLopt.

    Parameters
    ----------
    flowsheet : Flowsheet
        The scene; not modified.
    objective : str
        A variable (``"nozzle.mdot"``: the largest spray rate; ``"t_end"``: the shortest batch) or an output
        (summary key or state/output name).
    variables : sequence or mapping
        ``(param, unit, lo, hi)`` or ``"param:unit:lo:hi"`` per variable (or ``{param: (unit, lo, hi)}``);
        ``param`` may be ``"t_end"`` (the end time of the run). NLopt works in the variables scaled to [0, 1].
    constraints : mapping or sequence, optional
        ``{"d50_um": (">=", 400)}`` or ``["d50_um>=400", ...]``; passed to NLopt as inequality constraints on the
        relative margins (a strict ``<`` is handled as ``<=`` by the optimizer, checked strictly in the result).
    maximize : bool
        Maximize instead of minimize.
    algorithm : str
        Any NLopt algorithm by name: local ``LN_COBYLA`` (default), ``LD_SLSQP``, ``LD_MMA``, ...; global
        ``GN_ISRES``, ``GN_ORIG_DIRECT_L``, ``GN_AGS``, ...; with constraints only those that handle them or
        ``AUGLAG``/``LN_AUGLAG``/``LD_AUGLAG`` around ``local_algorithm``. ``LD_*``/``GD_*`` get gradients by
        forward differences of step ``fd_step`` (scaled units; one simulation per variable).
    local_algorithm : str, optional
        Subsidiary algorithm of AUGLAG* and MLSL (default ``LN_BOBYQA``, or ``LD_LBFGS`` for LD_AUGLAG/GD_MLSL).
    x0 : mapping, optional
        Start, variable -> value in its edge unit (default: the flowsheet's value, or mid-range if that is outside
        the bounds).
    fixed, t_end, simulate
        As :func:`contour_map`.
    xtol_rel, ftol_rel, maxeval, maxtime, population, seed
        NLopt stopping criteria; ``population`` for ISRES/CRS/ESCH/MLSL; ``seed`` for NLopt's random numbers.

    Returns
    -------
    OptimizationResult
        If NLopt stops with a point that is not feasible (or with an exception such as ROUNDOFF_LIMITED), the best
        feasible point evaluated is returned and ``message`` says so.
    """
    nlopt = _nlopt()
    algo = _algorithm(algorithm)
    cons = parse_constraints(constraints)
    local = None
    if algo in _NEEDS_LOCAL:
        default = "LD_LBFGS" if algo.startswith(("LD_", "GD_")) else "LN_BOBYQA"
        local = _algorithm(local_algorithm or default, "local_algorithm")
    elif local_algorithm is not None:
        raise ConfigError(f"local_algorithm = {local_algorithm!r}: only for AUGLAG* and *MLSL* algorithms "
                          f"(algorithm = {algo})")
    if cons and algo not in _CONSTRAINED:
        raise ConfigError(f"algorithm = {algo}: NLopt's {algo} does not take constraints; use one that does "
                          f"({', '.join(sorted(_CONSTRAINED - {'AUGLAG_EQ', 'LN_AUGLAG_EQ', 'LD_AUGLAG_EQ'}))}) "
                          f"or algorithm='AUGLAG' with local_algorithm='{algo}'")
    fs = fixed_flowsheet(flowsheet, fixed, t_end)
    if isinstance(variables, Mapping):  # {param: (unit, lo, hi)}
        variables = [(k, *v) for k, v in variables.items()]
    elif isinstance(variables, str) or (isinstance(variables, tuple) and len(variables) >= 3
                                        and isinstance(variables[0], str) and isinstance(variables[2], (int, float))):
        variables = [variables]  # a single variable
    axes = [make_axis(fs, v, f"variables[{i}]", with_n=False, allow_t_end=True) for i, v in enumerate(variables)]
    if not axes:
        raise ConfigError("variables: give at least one (param, unit, lo, hi)")
    if len({a.param for a in axes}) != len(axes):
        raise ConfigError("variables: a parameter is given twice")
    for a in axes:
        if fixed and a.param in fixed:
            raise ConfigError(f"fixed: {a.param} is also a variable")
    var_names = [a.param for a in axes]
    outputs = [c.output for c in cons]
    if objective not in var_names:
        if objective in fs.params or objective == T_END:
            raise ConfigError(f"objective = '{objective}': a parameter that is not a variable is constant "
                              f"(variables: {', '.join(var_names)})")
        outputs = [objective] + outputs
    outputs = sweep.check_outputs(fs, list(dict.fromkeys(outputs)), where="objective/constraints")
    for k in (x0 or {}):
        if k not in var_names:
            raise ConfigError(f"x0: '{k}' is not a variable ({', '.join(var_names)})")
    u0 = []
    for a in axes:
        if x0 and a.param in x0:
            v = float(x0[a.param])
            if not a.lo <= v <= a.hi:
                raise ConfigError(f"x0: {a.param} = {v:g} {a.unit}: outside {a.lo:g} ... {a.hi:g}")
        else:
            v = float(a.from_si(fs.t_end if a.param == T_END else fs.get(a.param)))
            if not a.lo <= v <= a.hi:
                v = 0.5 * (a.lo + a.hi)
        u0.append((v - a.lo) / (a.hi - a.lo))
    if not (isinstance(maxeval, int) and maxeval >= 1):
        raise ConfigError(f"maxeval = {maxeval!r}: expected an integer >= 1")
    if not 0 < fd_step < 0.5:
        raise ConfigError(f"fd_step = {fd_step!r}: expected 0 < fd_step < 0.5 (scaled units)")

    prob = _Problem(fs, axes, objective, maximize, cons, outputs, map_sim_kwargs(simulate))
    n = len(axes)
    n_eval = [0]

    def grad_of(u, value_of):
        g = np.empty(n)
        f0 = value_of(prob.evaluate(u))
        for i in range(n):
            up = np.array(u, dtype=float)
            h = fd_step if up[i] + fd_step <= 1.0 else -fd_step
            up[i] += h
            g[i] = (value_of(prob.evaluate(up, kind="gradient")) - f0) / h
        return g

    def f_obj(u, grad):
        n_eval[0] += 1
        rec = prob.evaluate(u)
        if grad.size > 0:
            grad[:] = grad_of(u, prob.f_for_nlopt)
        return prob.f_for_nlopt(rec)

    def make_c(i):
        def f_c(u, grad):
            rec = prob.evaluate(u)
            if grad.size > 0:
                grad[:] = grad_of(u, lambda r: _Problem.c_for_nlopt(r, i))
            return _Problem.c_for_nlopt(rec, i)
        return f_c

    opt = nlopt.opt(getattr(nlopt, algo), n)
    opt.set_lower_bounds([0.0] * n)
    opt.set_upper_bounds([1.0] * n)
    if maximize:
        opt.set_max_objective(f_obj)
    else:
        opt.set_min_objective(f_obj)
    for i in range(len(cons)):
        opt.add_inequality_constraint(make_c(i), 0.5 * _C_SAFETY)
    opt.set_xtol_rel(xtol_rel)
    if ftol_rel is not None:
        opt.set_ftol_rel(ftol_rel)
    opt.set_maxeval(maxeval)
    if maxtime is not None:
        opt.set_maxtime(float(maxtime))
    if population is not None:
        opt.set_population(int(population))
    opt.set_initial_step([0.1] * n)
    if local is not None:
        lo_opt = nlopt.opt(getattr(nlopt, local), n)
        lo_opt.set_xtol_rel(xtol_rel)
        lo_opt.set_maxeval(maxeval)
        opt.set_local_optimizer(lo_opt)
    if seed is not None:
        nlopt.srand(int(seed))

    t0 = time.perf_counter()
    names = {getattr(nlopt, r): r for r in _RESULTS}
    message = ""
    u_best = None
    try:
        u_best = opt.optimize(list(u0))
        code = names.get(opt.last_optimize_result(), str(opt.last_optimize_result()))
    except nlopt.RoundoffLimited:
        code = "ROUNDOFF_LIMITED"
    except nlopt.ForcedStop:
        code = "FORCED_STOP"
    except (RuntimeError, ValueError) as e:  # NLopt's generic failure / invalid arguments
        if isinstance(e, ConfigError):
            raise
        code = "FAILURE" if isinstance(e, RuntimeError) else "INVALID_ARGS"
        message = f"NLopt: {e}. "
    wall = time.perf_counter() - t0

    rec = prob.evaluate(u_best) if u_best is not None else None
    ok = rec is not None and rec["status"] == sweep.STATUS_OK and all(rec["met"])
    if not ok:
        feas = [r for r in prob.cache.values() if r["status"] == sweep.STATUS_OK and all(r["met"])
                and math.isfinite(r["f"])]
        if feas:
            best = (max if maximize else min)(feas, key=lambda r: r["f"])
            message += ("NLopt's final point is infeasible; returning the best feasible point evaluated."
                        if rec is not None else "returning the best feasible point evaluated.")
            rec = best
        elif rec is None:
            if not prob.cache:  # NLopt stopped before its first evaluation
                prob.evaluate(u0)
            rec = min(prob.cache.values(), key=lambda r: -min(r["margins"], default=0.0)
                      if all(map(math.isfinite, r["margins"])) else math.inf)
            message += "no feasible point found; returning the least infeasible point evaluated."
        else:
            message += "no feasible point found."
    xs = prob.si(rec["u"])
    x = {a.param: float(a.from_si(xs[a.param])) for a in axes}
    import pandas as pd

    history = pd.DataFrame(prob.rows)
    return OptimizationResult(
        x=x, x_si=xs, units={a.param: a.unit for a in axes}, objective=objective, maximize=maximize,
        value=float(rec["f"]), outputs=dict(rec["values"]),
        constraints={str(c): {"value": rec["values"].get(c.output, math.nan), "margin": rec["margins"][i],
                              "met": rec["met"][i]} for i, c in enumerate(cons)},
        feasible=rec["status"] == sweep.STATUS_OK and all(rec["met"]), n_simulations=prob.n_sim,
        n_evaluations=n_eval[0], nlopt_result=code, message=message.strip(), algorithm=algo, local_algorithm=local,
        wall_time_s=wall, history=history)
