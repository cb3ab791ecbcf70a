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


def _finite(v):
    return float(v) if v is not None and math.isfinite(v) else None


def _value(raw: dict, name: str) -> float:
    if name in raw["outputs"]:
        return raw["outputs"][name]
    return raw["y"][name]


def _summary(fs: Flowsheet, raw: dict) -> tuple[dict, dict]:
    values, units = {}, {}
    for key, src in fs.summary_map.items():
        si = fs.unit_of(src)
        shown = outputs_mod.summary_unit(key, si)
        values[key] = _finite(float(from_si(_value(raw, src), shown, si)))
        units[key] = shown
    return values, units


# Flows below this (kg/s, W) are round-off of a steady state with nothing flowing, not a flow to close a balance on.
NO_FLOW = 1e-15


def boundary_balance(raw: dict) -> dict:
    """Per quantity the flows in and out and their closure ``rel`` = |in - out| / max; where nothing flows (both
    below NO_FLOW) the closure is 0 and ``note`` says so, never 1 from 0 against 7e-37."""
    out = {}
    for q, f in sorted(raw["boundary_flows"].items()):
        scale = max(abs(f["in"]), abs(f["out"]))
        if scale < NO_FLOW:
            out[q] = {"in": f["in"], "out": f["out"], "rel": 0.0,
                      "note": f"nothing flows across the boundary (in and out below {NO_FLOW:g})"}
        else:
            out[q] = {"in": f["in"], "out": f["out"], "rel": abs(f["in"] - f["out"]) / scale}
    return out


def _stability(raw: dict) -> dict | None:
    s = raw.get("stability")
    if not s:
        return None
    re, im = s["max_real_eigenvalue"], s["imag_of_max"]
    return {"max_real_eigenvalue_1_s": re, "imag_1_s": im,
            "oscillation_period_s": 2.0 * math.pi / im if im > 0 else None,
            "stable": bool(re < 0.0), "time_s": s["time_s"]}


def steady_report(fs: Flowsheet, *, t: float = 0.0, stability: bool = True, ftol: float = 1e-10) -> dict:
    """The steady state of ``fs`` (inputs at time ``t``) as the contents of steady.json: ``scene``, ``t_s``, every
    summary key of the scene (in its summary unit), ``balance`` (per quantity the flows in and out across the
    flowsheet's boundary, per second, and ``rel`` = |in - out| / max), ``stability`` (the eigenvalue of the
    linearized dynamics with the largest real part: ``stable``, ``oscillation_period_s``; None for sparse systems),
    ``solver`` (``method``, ``iterations``, ``pseudo_steps``, ``residual_norm``, ``wall_time_s``, ``conserved``,
    ``warnings``) and ``units``."""
    raw = fs.steady_state(t=float(t), ftol=ftol, stability=stability)
    values, units = _summary(fs, raw)
    rep = {"scene": fs.name, "t_s": float(t), **values, "balance": boundary_balance(raw), "stability": _stability(raw),
           "solver": {k: raw[k] for k in ("method", "iterations", "pseudo_steps", "residual_norm", "wall_time_s",
                                          "conserved", "warnings")}}
    rep["units"] = {"t_s": "s", **units, "balance": "kg/s (solids, water), W (energy); rel: -",
                    "stability": "1/s, s", "solver": "wall_time_s: s"}
    rep["_raw"] = raw
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
