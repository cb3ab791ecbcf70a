"""``granuflow bench loop``: the sieve-mill loop of flowsheets/continuous_layering_sieve_mill.yaml (paper 003,
section 7.5.1) at its first operating point (spray 200 kg/h, no step), at 50, 100 and 200 size classes:

* granuflow's dynamic run from the seed bed to the steady state (300 h, rtol 1e-6 of the scene), median of repeats;
* granuflow's direct steady-state solve (Newton; pseudo-transient continuation where Newton fails), median;
* the NumPy/SciPy implementation tests/bench/scipy_sieve_mill_loop.py (solve_ivp BDF, finite-difference Jacobian)
  on the same variant, in the same run.

Each record holds the wall times, the solver statistics, the product's d10/d50/d90, bed mass and recycle ratio of
each, and the two ratios the issue names: SciPy time / granuflow dynamic time and granuflow dynamic time / direct
steady-state time. Times are for information, never pass/fail.
"""
from __future__ import annotations

import statistics
import sys
import time

from . import bench  # its helpers (the source tree, the machine, running a JSON-lines script) serve every bench
from .quantity import from_si

T_END_H = 300.0  # the loop settles in about 40 h; 300 h brings d50 within 1e-9 of the steady state
SPRAY = 200.0 / 3600.0  # kg/s, the scene's spray before its step


def loop_flowsheet(classes: int):
    """The scene at ``classes`` size classes with the spray held at its first value."""
    import os

    from .flowsheet import load_text

    path = os.path.join(bench.repo_root(), "flowsheets", "continuous_layering_sieve_mill.yaml")
    text = open(path).read()
    if "classes: 100" not in text:
        raise ValueError(f"{path}: particles: settings: classes: 100 not found (the bench varies it)")
    fs = load_text(text.replace("classes: 100", f"classes: {int(classes)}"), f"continuous_layering_{classes}")
    fs.set_input("gran.m_spray", [0.0], [SPRAY])
    return fs


def _loop_values(get) -> dict:
    prod, disc = get("product.mdot"), get("gran.discharge_mdot")

    def um(k):
        return float(from_si(get(k), "um", "m"))

    return {"d10_um": um("product.d10"), "d50_um": um("product.d50"), "d90_um": um("product.d90"),
            "bed_mass_kg": get("gran.mass"),
            "product_kg_h": prod * 3600.0, "recycle_kg_h": (disc - prod) * 3600.0,
            "recycle_ratio": (disc - prod) / prod if prod > 0 else None}


def bench_loop(*, classes=(50, 100, 200), repeats: int = 3, scipy: bool = True, scipy_repeats: int = 1,
               progress: bool = False) -> list[dict]:
    """One record per class count (see the module's docstring)."""
    from .steady import steady_report

    script = bench.bench_script("scipy_sieve_mill_loop.py", "the SciPy implementation of the sieve-mill loop",
                                "use --no-scipy to time granuflow only") if scipy else None
    records = []
    for n in classes:
        if progress:
            print(f"loop: {n} classes", file=sys.stderr, flush=True)
        fs = loop_flowsheet(n)
        res = fs.simulate(t_end=T_END_H * 3600.0, n_out=2, warn=False)  # warm-up
        walls = []
        for _ in range(repeats):
            t0 = time.perf_counter()
            res = fs.simulate(t_end=T_END_H * 3600.0, n_out=2, warn=False)
            walls.append(time.perf_counter() - t0)
        dyn = _loop_values(lambda k: float(res[k][-1]))
        steady_report(fs, stability=False)  # warm-up
        swalls, rep = [], None
        for _ in range(repeats):
            t0 = time.perf_counter()
            rep = steady_report(fs, stability=False)
            swalls.append(time.perf_counter() - t0)
        raw = rep["_raw"]
        st = _loop_values(lambda k: float(raw["outputs"][k] if k in raw["outputs"] else raw["y"][k]))
        wall, swall = statistics.median(walls), statistics.median(swalls)
        rec = {"bench": "loop", "classes": n, "t_end_h": T_END_H, "repeats": repeats,
               "unknowns": res.stats["states"], "inlined_states": res.stats["explicit_states"],
               "dynamic_s_median": wall, **{f"dynamic_{k}": res.stats[k] for k in (
                   "steps", "residuals", "jacobians", "error_test_failures", "nonlinear_failures", "method")},
               **{f"dynamic_{k}": v for k, v in dyn.items()},
               "steady_s_median": swall, "steady_method": rep["solver"]["method"],
               "steady_iterations": rep["solver"]["iterations"], "steady_pseudo_steps": rep["solver"]["pseudo_steps"],
               **{f"steady_{k}": v for k, v in st.items()},
               "steady_solids_balance_rel": rep["balance"]["solids"]["rel"],
               "dynamic_vs_steady_d50_rel": abs(dyn["d50_um"] / st["d50_um"] - 1.0),
               "dynamic_vs_steady_bed_rel": abs(dyn["bed_mass_kg"] / st["bed_mass_kg"] - 1.0),
               "steady_speedup_vs_dynamic": wall / swall, "command": "granuflow bench loop", **bench.meta()}
        if script:
            sp = bench.json_lines([sys.executable, script, "--json", "--classes", str(n), "--t-end", str(T_END_H),
                                   "--repeats", str(int(scipy_repeats))], "scipy_sieve_mill_loop.py")[0]
            rec.update({"scipy_s_median": sp["wall_s_median"], "scipy_nfev": sp.get("nfev"),
                        "scipy_njev": sp.get("njev"), "scipy_nlu": sp.get("nlu"),
                        **{f"scipy_{k}": sp[k] for k in ("d10_um", "d50_um", "d90_um", "bed_mass_kg")},
                        "speedup_vs_scipy": sp["wall_s_median"] / wall})
        records.append(rec)
    return records


def loop_summary(records) -> list[str]:
    r0 = records[0]
    with_scipy = "scipy_s_median" in r0
    lines = [f"Sieve-mill loop to steady state ({r0['t_end_h']:g} h dynamic run; direct steady-state solve): median "
             f"of {r0['repeats']} runs ({r0['cores']} cores, commit {r0['commit']}); times for information only.",
             "  classes  dynamic s  steps  Jacs | steady s  method            its | dyn/steady"
             + ("  |   SciPy s  nfev   njev  SciPy/dyn" if with_scipy else "")]
    for r in records:
        meth = "newton" if r["steady_method"] == "newton" else "ptc+newton"
        sp = (f"  | {r['scipy_s_median']:9.2f} {r['scipy_nfev']:5d} {r['scipy_njev']:6d} "
              f"{'x%.1f' % r['speedup_vs_scipy']:>10s}" if with_scipy else "")
        lines.append(f"  {r['classes']:7d} {r['dynamic_s_median']:10.3f} {r['dynamic_steps']:6d} "
                     f"{r['dynamic_jacobians']:5d} | {r['steady_s_median']:8.4f}  {meth:16s} "
                     f"{r['steady_iterations']:4d}"
                     f" | {'x%.1f' % r['steady_speedup_vs_dynamic']:>10s}{sp}")
    lines.append("  steady state (direct solve):  classes  d10 um    d50 um    d90 um   bed kg  recycle ratio  "
                 "|d50 dyn/steady - 1|" + ("  SciPy d50 um" if with_scipy else ""))
    for r in records:
        lines.append(f"  {'':29s} {r['classes']:7d} {r['steady_d10_um']:8.2f} {r['steady_d50_um']:9.2f} "
                     f"{r['steady_d90_um']:9.2f} {r['steady_bed_mass_kg']:8.3f} {r['steady_recycle_ratio']:13.4f}  "
                     f"{r['dynamic_vs_steady_d50_rel']:.1e}" + (f"  {r['scipy_d50_um']:12.2f}" if with_scipy else ""))
    return lines
