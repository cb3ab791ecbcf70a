"""Steady states as reports: the scene's summary keys evaluated at the steady state, the flows across the
flowsheet's boundary and their closure, the stability of the steady state, and the solver's record.

``granuflow steady SCENE --out DIR`` writes :func:`steady_report` to ``steady.json`` and the size distributions at
the steady state to ``steady_psd.csv``; :func:`steady_values` gives the values of summary keys or output names at the
steady state (design-space maps computed from steady-state solves instead of long transients).

Python::

    import granuflow as gf
    from granuflow.steady import steady_report

    rep = steady_report(gf.load("flowsheets/continuous_layering_sieve_mill.yaml"))
    rep["d50_um"], rep["balance"]["solids"]["rel"], rep["stability"]["stable"], rep["solver"]["iterations"]

A flowsheet without a steady state (a batch being sprayed: its hold-up grows at a constant rate) raises
``SolverError`` saying so; so does a solve that fails.
"""
from __future__ import annotations

import math
from typing import Mapping, Sequence

import numpy as np

from . import outputs as outputs_mod
from .flowsheet import Flowsheet
from .quantity import from_si
from .result import BalanceError


def _finite(v):
    return float(v) if v is not None and math.isfinite(v) else None


def _value(raw: dict, name: str) -> float:
    if name in raw["outputs"]:
        return raw["outputs"][name]
    return raw["y"][name]


def _summary(fs: Flowsheet, raw: dict) -> tuple[dict, dict, dict]:
    values, units, reasons = {}, {}, {}
    for key, src in fs.summary_map.items():
        si = fs.unit_of(src)
        shown = outputs_mod.summary_unit(key, si)
        values[key] = _finite(float(from_si(_value(raw, src), shown, si)))
        units[key] = shown
        if values[key] is None:
            reasons[key] = outputs_mod.null_reason(src, si, "at the steady state")
    return values, units, reasons


# Flows below this (kg/s, W) are round-off of a steady state with nothing flowing, not a flow to close a balance on.
NO_FLOW = 1e-15
# Growth rates below this (1/s, a time scale of 30 000 years) are round-off of a zero eigenvalue.
NEUTRAL_RATE = 1e-12


def boundary_balance(raw: dict) -> dict:
    """Per quantity the flows in and out and their closure ``rel`` = |in - out| / max; where nothing flows (both
    below NO_FLOW) the closure is undefined: ``rel`` is None and ``note`` says why, never 1 from 0 against 7e-37."""
    out = {}
    for q, f in sorted(raw["boundary_flows"].items()):
        scale = max(abs(f["in"]), abs(f["out"]))
        if scale < NO_FLOW:
            out[q] = {"in": f["in"], "out": f["out"], "rel": None,
                      "note": f"undefined: nothing flows across the boundary (in and out below {NO_FLOW:g})"}
        else:
            out[q] = {"in": f["in"], "out": f["out"], "rel": abs(f["in"] - f["out"]) / scale}
    return out


def _stability(raw: dict) -> dict | None:
    s = raw.get("stability")
    if not s:
        return None
    re, im = s["max_real_eigenvalue"], s["imag_of_max"]
    out = {"max_real_eigenvalue_1_s": re, "imag_1_s": im,
           "oscillation_period_s": 2.0 * math.pi / im if im > 0 else None,
           "stable": bool(re < 0.0), "time_s": s["time_s"]}
    if abs(re) < NEUTRAL_RATE and im < NEUTRAL_RATE:  # round-off of a zero eigenvalue is no growth nor decay
        out["stable"] = None
        out["note"] = (f"neutral: the largest eigenvalue is zero to round-off (|{re:.3g}| < {NEUTRAL_RATE:g} 1/s): a "
                       "quantity nothing changes, e.g. a hold-up with nothing flowing in or out")
    return out


def steady_report(fs: Flowsheet, *, t: float = 0.0, stability: bool = True, ftol: float = 1e-10) -> dict:
    """The steady state of ``fs`` (inputs at time ``t``) as the contents of steady.json: ``scene``, ``t_s``, every
    summary key of the scene (in its summary unit), ``balance`` (per quantity the flows in and out across the
    flowsheet's boundary, per second, and ``rel`` = |in - out| / max), ``stability`` (the eigenvalue of the
    linearized dynamics with the largest real part: ``stable``, ``oscillation_period_s``; None for sparse systems),
    ``solver`` (``method``, ``iterations``, ``pseudo_steps``, ``residual_norm``, ``wall_time_s``, ``conserved``,
    ``warnings``), ``warnings`` (a controller missing its set point, the trivial root; an end class of a size grid
    holding more than GRID_END_WARNING of the mass, as a run warns; a boundary balance closing worse than
    outputs.balance_limits allows) and ``units``. Raises :class:`~granuflow.result.BalanceError` (with the report as
    ``.report``) when a closure is above outputs.BALANCE_FAIL."""
    raw = fs.steady_state(t=float(t), ftol=ftol, stability=stability)
    values, units, reasons = _summary(fs, raw)
    rep = {"scene": fs.name, "t_s": float(t), **values, "null_reasons": reasons, "balance": boundary_balance(raw),
           "stability": _stability(raw),
           "solver": {k: raw[k] for k in ("method", "iterations", "pseudo_steps", "residual_norm", "wall_time_s",
                                          "conserved", "warnings")}}
    # what the solve found (a controller that misses its set point, the trivial root), and every check a run makes on
    # its grids, on the steady state too
    rep["warnings"] = list(raw["warnings"])
    rep["warnings"] += outputs_mod.grid_end_warnings(steady_grid_ends(fs, raw), "at the steady state")
    # and the balance guard: a steady state whose boundary flows do not close loses or makes mass (BalanceError)
    warns, fails = outputs_mod.balance_findings(rep["balance"], None, "at the steady state")
    rep["warnings"] += warns
    rep["units"] = {"t_s": "s", **units, "balance": "kg/s (solids, water), W (energy); rel: -",
                    "stability": "1/s, s", "solver": "wall_time_s: s"}
    rep["_raw"] = raw
    if fails:
        name, value = max(outputs_mod.balance_closures(rep["balance"]).items(), key=lambda kv: kv[1])
        raise BalanceError(f"{fs.name}: {fails[0]}", name, value, float(t), report=rep)
    return rep


def steady_values(fs: Flowsheet, names: Sequence[str], *, t: float = 0.0) -> dict[str, float]:
    """Values of summary keys (in their summary unit) or state/output names (SI) at the steady state."""
    raw = fs.steady_state(t=float(t))
    smap = fs.summary_map
    out = {}
    for n in names:
        if n in smap:
            si = fs.unit_of(smap[n])
            out[n] = float(from_si(_value(raw, smap[n]), outputs_mod.summary_unit(n, si), si))
        else:
            out[n] = float(_value(raw, n))
    return out


def steady_grid_ends(fs: Flowsheet, raw: Mapping) -> dict[str, dict]:
    """The mass fraction in the end classes of each size grid at the steady state, as
    :meth:`granuflow.Result.grid_ends` gives it for a run (``initial`` 0: a steady state has no start of its own)."""
    roles, names = fs.output_roles, fs.output_names
    out: dict[str, dict] = {}
    units = outputs_mod.psd_units(roles)
    for unit in units:
        dcols, mcols = outputs_mod.psd_columns(roles, unit)
        m = np.array([raw["outputs"][names[j]] for j in mcols])
        total = m.sum()
        for end, k in (("bottom_class", 0), ("top_class", -1)):
            f = float(m[k] / total) if total > 0 else 0.0
            out[f"{unit}.{end}"] = {"initial": 0.0, "final": f, "max": f,
                                    "d_um": float(from_si(raw["outputs"][names[dcols[k]]], "um", "m"))}
    for j, name in outputs_mod.grid_end_columns(roles, names):
        if roles[j][3] not in units:
            v = float(raw["outputs"][name])
            out[name] = {"initial": 0.0, "final": v, "max": v, "d_um": None}
    return out


def steady_psd_rows(fs: Flowsheet, raw: Mapping) -> list[dict]:
    """One row per size class of every unit that reports a size distribution, at the steady state."""
    roles = fs.output_roles
    names = fs.output_names
    rows = []
    for unit in outputs_mod.psd_units(roles):
        dcols, mcols = outputs_mod.psd_columns(roles, unit)
        m = np.array([raw["outputs"][names[j]] for j in mcols])
        total = m.sum()
        for i, (jd, jm) in enumerate(zip(dcols, mcols)):
            rows.append({"unit": unit, "class": i, "d_um": float(from_si(raw["outputs"][names[jd]], "um", "m")),
                         "mass_kg": raw["outputs"][names[jm]],
                         "mass_fraction": raw["outputs"][names[jm]] / total if total > 0 else 0.0})
    return rows
