"""Benchmarks (report figures, never pass/fail on time).

``granuflow bench core [--json]``: cost of one residual per state (ns/state) for chains of stirred tanks with
about 100, 1 000 and 10 000 states, the cost of one Jacobian relative to one residual, and the wall time of the
demo flowsheet (median of repeated runs).
``granuflow bench pbm [--json] [--repeats N] [--quick]``: population-balance work precision. Runs
<build>/tests/bench/granuflow_bench_pbm (next to this package) and the NumPy/SciPy baseline
tests/bench/scipy_fixed_pivot.py on the same cases; ``--json`` prints one record per run (keys PBM_KEYS plus
``code``), otherwise a summary: work-precision envelopes and the speed ratio at equal error vs SciPy LSODA.
``granuflow bench scene [--json] [--repeats N] [--no-scipy]``: wall time of the 60-min headline scene (paper 001)
at 10, 20 and 40 size classes, with and without breakage, with solver statistics and results at 60 min, against
the SciPy implementation tests/bench/scipy_gf25_batch.py (BDF, finite-difference Jacobian) run on the same variant
in the same run, and against issue 4's reference point (0.10 s at 10 classes, 0.17 s at 40).
"""
from __future__ import annotations

import json
import math
import os
import platform
import statistics
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))


def repo_root() -> str:
    """The repository: the working folder when it holds flowsheets/, else the one holding python/granuflow."""
    # the working folder when run from the repository, else the repository holding python/granuflow
    for cand in (os.getcwd(), os.path.abspath(os.path.join(HERE, "..", "..", ".."))):
        if os.path.exists(os.path.join(cand, "flowsheets")):
            return cand
    return os.getcwd()


def meta() -> dict:
    """Machine, CPU, cores, Python, commit and date for a benchmark record."""
    root = repo_root()
    try:
        commit = subprocess.run(["git", "-C", root, "rev-parse", "--short", "HEAD"], capture_output=True,
                                text=True, timeout=10).stdout.strip()
    except Exception:  # noqa: BLE001 - metadata only
        commit = ""
    return {"machine": platform.node(), "cpu": platform.processor() or platform.machine(), "cores": os.cpu_count(),
            "python": sys.version.split()[0], "commit": commit, "date": time.strftime("%Y-%m-%d %H:%M:%S")}


def tank_chain_text(n_tanks: int) -> str:
    """Scene text: a feed, n_tanks stirred tanks in series and a product sink (2 n_tanks + 3 states: temperature
    and composition per tank, the feed's stream; flows pass through and what is fed or collected is integrated as
    quadratures)."""
    lines = ["scene: tank_chain", "t_end: 100 s", "units:", "  feed: {type: liquid_feed, params: {mdot: 0.5}}"]
    lines += [f"  t{i}: {{type: stirred_tank, params: {{mass: 100, Q: 1000}}}}" for i in range(n_tanks)]
    lines += ["  product: {type: liquid_product}", "connections:", "  - feed.out -> t0.in"]
    lines += [f"  - t{i}.out -> t{i + 1}.in" for i in range(n_tanks - 1)]
    lines += [f"  - t{n_tanks - 1}.out -> product.in"]
    return "\n".join(lines) + "\n"


def bench_core(repeats: int, quick: bool = False, progress: bool = False) -> list[dict]:
    """Residual and Jacobian cost per state on tank chains of about 100, 1000 and 10000 states (``quick``: 100 and
    1000), and the wall time of the demo flowsheet."""
    from .flowsheet import load, load_text

    records = []
    for target in (100, 1000) if quick else (100, 1000, 10000):
        if progress:
            print(f"core: tank chain of about {target} states", file=sys.stderr, flush=True)
        n_tanks = max(1, (target - 3) // 2)
        fs = load_text(tank_chain_text(n_tanks), f"tank_chain_{n_tanks}")
        t = fs.time_residual(repeats)
        records.append({"bench": "residual", "states": t["states"], "units": n_tanks + 2,
                        "residual_ns_per_state": t["residual_s"] / t["states"] * 1e9,
                        "jacobian_over_residual": t["jacobian_s"] / t["residual_s"],
                        "jacobian_storage": "dense" if t["dense"] else "sparse", "nnz": t["nnz"], **meta()})
    demo = os.path.join(repo_root(), "flowsheets", "demo_tanks.yaml")
    fs = load(demo)
    walls = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        res = fs.simulate(warn=False)
        walls.append(time.perf_counter() - t0)
    records.append({"bench": "demo_flowsheet", "scene": demo, "states": len(res.state_names),
                    "wall_ms_median": statistics.median(walls) * 1e3, "solve_ms_median_inside": res.wall_time_s * 1e3,
                    "steps": res.stats["steps"], "repeats": repeats,
                    "command": "granuflow bench core", **meta()})
    return records


# -------------------------------------------------------------------------------------------------------- scene
# Issue 4's reference point, measured once on this project's 2-core machine by an independent Python/SciPy
# implementation (BDF, finite-difference Jacobian, rtol 1e-6), seconds per 60-min run. The bench also runs the
# repository's own SciPy implementation (tests/bench/scipy_gf25_batch.py) in the same run for a fair ratio.
ISSUE_REFERENCE_S = {10: 0.10, 40: 0.17}


def scene_variant_text(path: str, classes: int, breakage: bool = True) -> str:
    """The headline scene with `classes` size classes (the particle system's grid), breakage on or off."""
    import yaml

    from .textfile import yaml_loader

    with open(path, encoding="utf-8") as f:
        doc = yaml.load(f, Loader=yaml_loader(yaml))
    doc.setdefault("particles", {}).setdefault("settings", {})["classes"] = classes
    if not breakage:
        doc["units"]["bed"].setdefault("settings", {})["breakage"] = "none"
    return yaml.safe_dump(doc, sort_keys=False)


def bench_script(name: str, what: str, hint: str) -> str:
    """tests/bench/<name> of the source tree; FileNotFoundError naming ``what`` and ``hint`` if missing."""
    script = os.path.join(_source_dir(_build_dir()), "tests", "bench", name)
    if not os.path.exists(script):
        raise FileNotFoundError(f"{what} {script} does not exist (source tree of {_build_dir()}); {hint}")
    return script


def scipy_scene_script() -> str:
    """tests/bench/scipy_gf25_batch.py of the source tree; FileNotFoundError if missing."""
    return bench_script("scipy_gf25_batch.py", "the SciPy implementation of the headline scene",
                        "pass scipy=False to time granuflow only")


def load_script(path: str, name: str):
    """A benchmark script of tests/bench imported as a module (its functions called in this process)."""
    import importlib.util

    spec = importlib.util.spec_from_file_location(name, path)
    module = importlib.util.module_from_spec(spec)
    baseline(f"{name}.py", spec.loader.exec_module, module)
    return module


def baseline(label: str, fn, *args):
    """fn(*args) of a baseline run in this process; RuntimeError naming ``label`` if it fails, as json_lines does
    for a baseline run as its own process."""
    try:
        return fn(*args)
    except Exception as e:  # noqa: BLE001 - any failure of the baseline, named
        raise RuntimeError(f"{label} failed: {type(e).__name__}: {e}") from e


def bench_scene(repeats: int, classes=(10, 20, 40), scipy: bool = True, scipy_repeats: int = 3,
                progress: bool = False) -> list[dict]:
    """Wall time of the 60-min headline scene (median of at least ``repeats`` runs), solver statistics and results,
    per class count with and without breakage; with ``scipy``, the SciPy implementation of the same variant (median
    of ``scipy_repeats`` solves), its results and the speed ratio. The two are measured in alternating rounds
    (granuflow's runs of a round, then one SciPy solve), so that both medians come from the same stretch of time on a
    shared machine, whose speed drifts by tens of percent over seconds; ``speedup_rounds`` holds each round's ratio
    (its SciPy solve over the median of its granuflow runs)."""
    from .flowsheet import load_text

    scene = os.path.join(repo_root(), "flowsheets", "stoeckl_gf25_batch.yaml")
    sp = load_script(scipy_scene_script(), "scipy_gf25_batch") if scipy else None
    rounds = max(1, int(scipy_repeats)) if sp else 1
    per_round = max(1, math.ceil(repeats / rounds))
    records = []
    for n in classes:
        for breakage in (True, False):
            if progress:
                print(f"scene: {n} classes, breakage {'on' if breakage else 'off'}", file=sys.stderr, flush=True)
            fs = load_text(scene_variant_text(scene, n, breakage), f"stoeckl_gf25_batch_{n}")
            res = fs.simulate()  # warm-up: first-touch allocations
            # built and warmed up outside the rounds
            timed = baseline("scipy_gf25_batch.py", sp.Timed, n, breakage) if sp else None
            walls, ratios = [], []
            for _ in range(rounds):
                mine = []
                for _ in range(per_round):
                    t0 = time.perf_counter()
                    res = fs.simulate(warn=False)
                    mine.append(time.perf_counter() - t0)
                walls += mine
                if timed:
                    ratios.append(baseline("scipy_gf25_batch.py", timed.solve) / statistics.median(mine))
            values = res.summary_values()  # the core's numbers (also a d90 in the top class): integrators compared
            wall = statistics.median(walls)
            ref = ISSUE_REFERENCE_S.get(n) if breakage else None
            rec = {
                "bench": "scene", "classes": n, "breakage": breakage, "unknowns": res.stats["states"],
                "inlined_states": res.stats["explicit_states"], "wall_ms_median": wall * 1e3,
                "wall_ms_min": min(walls) * 1e3, "repeats": len(walls),
                **{k: res.stats[k] for k in ("steps", "residuals", "jacobians", "error_test_failures",
                                             "nonlinear_failures")},
                **{k: values[k] for k in ("d10_um", "d50_um", "d90_um", "bed_moisture", "T_gas_out_K")},
                "issue_reference_ms": ref * 1e3 if ref else None,
                "speedup_vs_issue_reference": ref / wall if ref else None,
                "command": "granuflow bench scene", **meta()}
            if timed:
                sp_rec = timed.record()
                rec.update({"scipy_ms_median": sp_rec["wall_s_median"] * 1e3, "scipy_repeats": sp_rec["repeats"],
                            "scipy_nfev": sp_rec.get("nfev"), "scipy_njev": sp_rec.get("njev"),
                            "speedup_vs_scipy": sp_rec["wall_s_median"] / wall, "speedup_rounds": ratios,
                            **{f"scipy_{k}": sp_rec[k] for k in ("d10_um", "d50_um", "d90_um", "bed_moisture",
                                                                 "T_gas_out_K")}})
            records.append(rec)
    return records


def rounds_range(ratios) -> str:
    """The spread of the per-round speed ratios, "x21.0-27.4" (one round: its ratio)."""
    if not ratios:
        return ""
    lo, hi = min(ratios), max(ratios)
    return f"x{lo:.1f}" if len(ratios) == 1 else f"x{lo:.1f}-{hi:.1f}"


def scene_summary(records) -> list[str]:
    r0 = records[0]
    same_run = "scipy_ms_median" in r0
    head = (f"Headline scene, 60 min, rtol/atol of the scene file: median of {r0['repeats']} runs "
            f"({r0['cores']} cores, commit {r0['commit']}); times are for information only.")
    if same_run:
        head += (f" SciPy: median of {r0['scipy_repeats']} solves, each after a round of granuflow's runs; speedup is"
                 " the ratio of the medians, rounds the range of each round's ratio.")
    lines = [head,
             "  classes breakage  unknowns+inlined  wall ms  steps residuals Jacobians   d50 um  moisture"
             + ("   SciPy ms  SciPy d50  speedup       rounds" if same_run else "") + "  vs issue reference"]
    for r in records:
        ref = (f"x{r['speedup_vs_issue_reference']:.1f} ({r['issue_reference_ms']:.0f} ms)"
               if r["speedup_vs_issue_reference"] else "")
        sp = (f" {r['scipy_ms_median']:10.1f} {r['scipy_d50_um']:10.1f} {'x%.1f' % r['speedup_vs_scipy']:>8s}"
              f" {rounds_range(r['speedup_rounds']):>12s}" if same_run else "")
        lines.append(f"  {r['classes']:7d} {'on' if r['breakage'] else 'off':8s} {r['unknowns']:8d}"
                     f" + {r['inlined_states']:<6d} {r['wall_ms_median']:8.2f} {r['steps']:6d}"
                     f" {r['residuals']:9d} {r['jacobians']:9d}"
                     f" {r['d50_um']:8.1f} {r['bed_moisture']:9.4f}{sp}  {ref}")
    return lines


# ---------------------------------------------------------------------------------------------------------- pbm
PBM_KEYS = ("case", "method", "integrator", "q", "classes", "rtol", "tau", "err_M0", "err_M2", "err_L1", "mass_drift",
            "solve_ms")
PBM_LEVELS = (0.05, 0.01, 0.001)


def _build_dir() -> str:
    """The CMake build folder of the running package (<build>/python/granuflow)."""
    return os.path.abspath(os.path.join(HERE, "..", ".."))


def _source_dir(build: str) -> str:
    """The source tree the build folder was configured from (CMakeCache.txt), else the repository found by
    repo_root()."""
    try:
        with open(os.path.join(build, "CMakeCache.txt")) as f:
            for line in f:
                if line.startswith("CMAKE_HOME_DIRECTORY:"):
                    return line.split("=", 1)[1].strip()
    except OSError:
        pass
    return repo_root()


def source_dir() -> str:
    """The source tree of the running package's build (benchmark scripts and scenes live there)."""
    return _source_dir(_build_dir())


def pbm_executable() -> str:
    """<build>/tests/bench/granuflow_bench_pbm next to the running package; FileNotFoundError if missing."""
    build = _build_dir()
    exe = os.path.join(build, "tests", "bench", "granuflow_bench_pbm")
    if not os.access(exe, os.X_OK):
        raise FileNotFoundError(
            f"the benchmark executable {exe} does not exist (the granuflow package in use is "
            f"{os.path.join(build, 'python', 'granuflow')}); build it with `ninja -C {build} granuflow_bench_pbm` "
            f"(configured with -DGRANUFLOW_BUILD_TESTS=ON)")
    return exe


def json_lines(cmd: list[str], label: str) -> list[dict]:
    """The JSON records a benchmark process prints one per line; RuntimeError naming ``label`` if it fails."""
    proc = subprocess.run(cmd, capture_output=True, text=True)
    if proc.returncode != 0:
        tail = " ".join(proc.stderr.split()[-60:])
        raise RuntimeError(f"{label} failed (exit {proc.returncode}): {' '.join(cmd)}: {tail}")
    return [json.loads(line) for line in proc.stdout.splitlines() if line.startswith("{")]


def bench_pbm(*, quick: bool = False, repeats: int = 5, scipy: bool = True, case: str | None = None,
              progress: bool = False) -> list[dict]:
    """Population-balance work-precision records: granuflow_bench_pbm (granuflow's schemes through the full
    framework) and, with ``scipy``, the NumPy/SciPy fixed-pivot baseline tests/bench/scipy_fixed_pivot.py on the
    same cases, grids and tolerances. One dict per run with the keys PBM_KEYS plus ``code`` ("granuflow" or
    "scipy"), solver counters and machine metadata. granuflow runs each scheme with the integrators ``auto``, ``ida``,
    ``bdf``, ``adams`` and ``erk`` (quick: auto, ida, adams, erk); q in {1, 2, 3, 4, 6, 8, 12}. ``quick``: q in
    {1, 2, 4}, rtol in {1e-2, 1e-4, 1e-6}. Times are medians of ``repeats`` solves; nothing here asserts on time."""
    flags = (["--quick"] if quick else []) + ["--repeats", str(int(repeats))] + (["--case", case] if case else [])
    exe = pbm_executable()
    if progress:
        print(f"running {exe} {' '.join(flags)}", file=sys.stderr, flush=True)
    records = json_lines([exe, "--json", *flags], "granuflow_bench_pbm")
    if scipy:
        script = bench_script("scipy_fixed_pivot.py", "the SciPy baseline", "pass scipy=False to run granuflow only")
        if progress:
            print(f"running {sys.executable} {script} {' '.join(flags)}", file=sys.stderr, flush=True)
        records += json_lines([sys.executable, script, "--json", *flags], "scipy_fixed_pivot.py")
    return records


def load_records(paths) -> list[dict]:
    """Records from JSON-lines files (output of ``--json``)."""
    recs = []
    for p in paths:
        with open(p) as f:
            recs += [json.loads(line) for line in f if line.startswith("{")]
    return recs


def label(r: dict) -> str:
    """A run's scheme and, for granuflow, its integrator: ``fixed_pivot/erk``, ``scipy_fp_LSODA``."""
    return f"{r['method']}/{r['integrator']}" if r.get("integrator") else r["method"]


def _usable(r: dict) -> bool:
    return r.get("err_M2") is not None and r.get("solve_ms") is not None and r.get("success", True)


def fastest(recs, case: str, code: str, level: float, method_prefix: str = "") -> dict | None:
    """The fastest run of ``code`` on ``case`` with |err_M2| <= level (any q and rtol; methods starting with
    ``method_prefix``), or None."""
    ok = [r for r in recs if r["case"] == case and r.get("code") == code and r["method"].startswith(method_prefix)
          and _usable(r) and abs(r["err_M2"]) <= level]
    return min(ok, key=lambda r: r["solve_ms"]) if ok else None


def envelope(recs, improvement: float = 0.0) -> list[dict]:
    """The work-precision curve of each (code, case, method): the runs that no faster run beats in |err_M2|
    (by more than the relative ``improvement``), in order of solve time."""
    out = []
    groups = sorted({(r.get("code", ""), r["case"], label(r)) for r in recs if _usable(r)})
    for code, case, method in groups:
        best = math.inf
        for r in sorted((r for r in recs if (r.get("code", ""), r["case"], label(r)) == (code, case, method)
                         and _usable(r)), key=lambda r: (r["solve_ms"], abs(r["err_M2"]))):
            if abs(r["err_M2"]) < best * (1.0 - improvement):
                best = abs(r["err_M2"])
                out.append(r)
    return out


def speed_ratios(recs, levels=PBM_LEVELS) -> list[dict]:
    """Speed at equal error: per case, error level and SciPy method, the fastest granuflow run and the fastest
    run of that SciPy method with |err_M2| <= level, and ratio = SciPy time / granuflow time (None where either
    code never reaches the level). Long format: one row per (case, level, baseline)."""
    rows = []
    for case in sorted({r["case"] for r in recs}):
        baselines = sorted({r["method"] for r in recs if r["case"] == case and r.get("code") == "scipy"},
                           key=lambda m: (not m.endswith("LSODA"), m))
        for level in levels:
            g = fastest(recs, case, "granuflow", level)
            for m in baselines:
                s = fastest(recs, case, "scipy", level, m)
                row = {"case": case, "level": level, "baseline": m}
                for tag, r in (("granuflow", g), ("baseline", s)):
                    row.update({f"{tag}_method": r and label(r), f"{tag}_q": r and r["q"],
                                f"{tag}_rtol": r and r["rtol"], f"{tag}_err_M2": r and r["err_M2"],
                                f"{tag}_ms": r and r["solve_ms"]})
                row["ratio"] = s["solve_ms"] / g["solve_ms"] if g and s else None
                rows.append(row)
    return rows


def _run_text(method, q, rtol, err, ms) -> str:
    if method is None:
        return "none"
    return f"{method} q={q} rtol={rtol:.0e} M2 {err:+.2e} {ms:.2f} ms"


def format_speed_ratios(rows) -> list[str]:
    """One line per (case, level): granuflow's fastest run, then each baseline with its ratio."""
    lines = []
    for key in dict.fromkeys((r["case"], r["level"]) for r in rows):
        group = [r for r in rows if (r["case"], r["level"]) == key]
        g = group[0]
        desc = ["granuflow: " + _run_text(g["granuflow_method"], g["granuflow_q"], g["granuflow_rtol"],
                                          g["granuflow_err_M2"], g["granuflow_ms"])]
        for r in group:
            ratio = f", x{r['ratio']:.1f}" if r["ratio"] is not None else ""
            desc.append(f"{r['baseline']}: " + _run_text(r["baseline_method"], r["baseline_q"], r["baseline_rtol"],
                                                         r["baseline_err_M2"], r["baseline_ms"]) + ratio)
        lines.append(f"{key[0]:9s} |err_M2| <= {key[1]:g}:  " + "  |  ".join(desc))
    return lines


def same_scheme_ratios(recs) -> list[dict]:
    """The same discretization in both codes (granuflow's fixed_pivot against scipy_fp_*, fv_upwind against
    scipy_upwind_*) at the same q and rtol, per granuflow integrator: SciPy time / granuflow time per pair, which
    isolates the cost of the implementation and integrator from the accuracy of the scheme."""
    pairs = {"scipy_fp_": "fixed_pivot", "scipy_upwind_": "fv_upwind"}
    mine = {}
    for r in recs:
        if r.get("code") == "granuflow" and r.get("solve_ms"):
            mine.setdefault((r["case"], r["method"], r["q"], r["rtol"]), []).append(r)
    rows = []
    for s in recs:
        if s.get("code") != "scipy" or not s.get("solve_ms") or not s.get("success", True):
            continue
        prefix = next((p for p in pairs if s["method"].startswith(p)), None)
        for g in (mine.get((s["case"], pairs[prefix], s["q"], s["rtol"]), []) if prefix else []):
            rows.append({"case": s["case"], "baseline": s["method"], "method": label(g), "q": s["q"],
                         "rtol": s["rtol"], "granuflow_ms": g["solve_ms"], "baseline_ms": s["solve_ms"],
                         "ratio": s["solve_ms"] / g["solve_ms"]})
    return rows


def auto_choices(recs) -> dict:
    """What ``auto`` ran, per case: {case: {integrator_ran: count}}."""
    out: dict = {}
    for r in recs:
        if r.get("integrator") == "auto":
            d = out.setdefault(r["case"], {})
            d[r.get("integrator_ran", "?")] = d.get(r.get("integrator_ran", "?"), 0) + 1
    return out


def targets(recs) -> list[dict]:
    """The speed targets of the integrator work (SciPy measured in the same run), one row each with the granuflow
    and SciPy runs compared, the ratio and the target: the constant kernel on the same discretization (fixed
    pivot q = 4) at each tolerance against LSODA; the constant kernel at |err_M2| <= 1 % and 0.1 % against the
    fastest SciPy setting; the sum kernel at <= 5 % against LSODA."""
    rows = []
    for rtol in sorted({r["rtol"] for r in recs if r["case"] == "constant" and r.get("q") == 4}, reverse=True):
        pick = [r for r in recs if r["case"] == "constant" and r.get("q") == 4 and r["rtol"] == rtol and _usable(r)]
        g = [r for r in pick if r.get("code") == "granuflow" and r["method"] == "fixed_pivot"]
        s = [r for r in pick if r.get("code") == "scipy" and r["method"] == "scipy_fp_LSODA"]
        if g and s:
            g0 = min(g, key=lambda r: r["solve_ms"])
            rows.append({"target": f"constant, fixed pivot q=4, rtol {rtol:g}: vs SciPy LSODA", "goal": 10.0,
                         "granuflow": g0, "baseline": s[0], "ratio": s[0]["solve_ms"] / g0["solve_ms"]})
    for case, level, goal, method in (("constant", 0.01, 50.0, ""), ("constant", 0.001, 20.0, ""),
                                      ("sum", 0.05, 20.0, "scipy_fp_LSODA")):
        g, b = fastest(recs, case, "granuflow", level), fastest(recs, case, "scipy", level, method)
        what = "SciPy LSODA" if method else "the fastest SciPy setting"
        rows.append({"target": f"{case}, |err_M2| <= {level:g}: vs {what}", "goal": goal, "granuflow": g,
                     "baseline": b, "ratio": b["solve_ms"] / g["solve_ms"] if g and b else None})
    return rows


def _fmt(v, spec: str) -> str:
    return "-" if v is None else format(v, spec)


def pbm_summary(recs, levels=PBM_LEVELS) -> list[str]:
    """The human-readable report of ``granuflow bench pbm``: per case and method the work-precision envelope,
    the speed ratio at equal error against SciPy's LSODA, and the ratio for the same discretization."""
    lines = []
    g = [r for r in recs if r.get("code") == "granuflow"]
    if g:
        r0 = g[0]
        drift = max(abs(r["mass_drift"]) for r in g if r.get("mass_drift") is not None)
        lines += [f"Population balance, work precision against the analytic solutions (N0 = v0 = 1): "
                  f"{len(g)} granuflow runs, {len(recs) - len(g)} SciPy runs, "
                  f"median of {r0.get('repeats')} solves each",
                  f"({r0.get('cpu', '')}, {r0.get('cores', '')} cores, commit {r0.get('commit', '')}). "
                  f"Largest |mass_drift| of granuflow's runs: {drift:.1e}.", ""]
    lines.append("Work-precision envelope, |err_M2| @ solve time (runs that no faster run beats by 10 % in |err_M2|):")
    env = envelope(recs, improvement=0.1)
    for case in sorted({r["case"] for r in env}):
        for method in sorted({label(r) for r in env if r["case"] == case}, key=lambda m: (m.startswith("scipy"), m)):
            pts = [r for r in env if r["case"] == case and label(r) == method]
            lines.append(f"  {case:9s} {method:22s} " + ", ".join(
                f"{abs(r['err_M2']):.1e} @ {r['solve_ms']:.2f} ms (q={r['q']})" for r in pts))
    rows = [r for r in speed_ratios(recs, levels) if r["baseline"].endswith("LSODA")]
    if rows:
        lines += ["", "Speed at equal error vs SciPy LSODA (fastest run with |err_M2| <= level; "
                  "ratio = SciPy / granuflow):",
                  f"  {'case':9s} {'level':>6s}  {'granuflow':28s} {'ms':>7s}  {'SciPy LSODA':27s} {'ms':>7s}  ratio"]
        for r in rows:
            gtxt = (f"{r['granuflow_method']} q={r['granuflow_q']} rtol={r['granuflow_rtol']:.0e}"
                    if r["granuflow_method"] else "not reached")
            if r["baseline_method"]:
                stxt = f"{r['baseline'].replace('scipy_', '')} q={r['baseline_q']} rtol={r['baseline_rtol']:.0e}"
            else:
                best = min((abs(x["err_M2"]) for x in recs if x["case"] == r["case"] and x["method"] == r["baseline"]
                            and _usable(x)), default=None)
                stxt = "not reached" + ("" if best is None else f" (best {best:.1e})")
            ratio = "-" if r["ratio"] is None else f"x{r['ratio']:.1f}"
            lines.append(f"  {r['case']:9s} {r['level']:6g}  {gtxt:28s} {_fmt(r['granuflow_ms'], '7.2f')}  "
                         f"{stxt:27s} {_fmt(r['baseline_ms'], '7.2f')}  {ratio}")
    same = same_scheme_ratios(recs)
    if same:
        lines += ["", "Same discretization and tolerances (fixed pivot; growth: first-order upwind), SciPy / granuflow "
                  "time over all q and rtol, per granuflow integrator:"]
        for case in sorted({r["case"] for r in same}):
            for base in sorted({r["baseline"] for r in same if r["case"] == case}):
                for meth in sorted({r["method"] for r in same if r["case"] == case and r["baseline"] == base}):
                    x = sorted(r["ratio"] for r in same
                               if r["case"] == case and r["baseline"] == base and r["method"] == meth)
                    lines.append(f"  {case:9s} {base:19s} {meth:22s} median x{statistics.median(x):.1f} "
                                 f"(x{x[0]:.1f} to x{x[-1]:.1f}, {len(x)} pairs)")
    auto = auto_choices(recs)
    if auto:
        lines += ["", "What solver.method auto ran (runs per integrator):"]
        lines += [f"  {case:9s} " + ", ".join(f"{k} {v}" for k, v in sorted(d.items()))
                  for case, d in sorted(auto.items())]
    rows = targets(recs)
    if rows:
        lines += ["", "Targets (ratio = SciPy time / granuflow time, same run):"]
        for r in rows:
            g, b = r["granuflow"], r["baseline"]
            gtxt = f"{label(g)} q={g['q']} rtol={g['rtol']:.0e} {g['solve_ms']:.2f} ms" if g else "not reached"
            btxt = f"{label(b)} q={b['q']} rtol={b['rtol']:.0e} {b['solve_ms']:.2f} ms" if b else "not reached"
            ratio = "-" if r["ratio"] is None else f"x{r['ratio']:.1f}"
            met = "" if r["ratio"] is None else (" (target met)" if r["ratio"] >= r["goal"] else " (below target)")
            lines.append(f"  {r['target']}: {ratio}, target x{r['goal']:g}{met}; granuflow {gtxt}; SciPy {btxt}")
    lines.append("Times are for information only; nothing asserts on them. `--json` prints every record.")
    return lines


# -------------------------------------------------------------------------------------------------------- sweep
def bench_sweep(*, n: int = 25, repeats: int = 3, workers: int = 2, dask: bool = True,
                progress: bool = False) -> list[dict]:
    """Throughput of an n x n contour map (paper 001 Fig. 17: d50,3 after 60 min over inlet temperature 40-80 degC
    and spray rate 60-120 g/min at 700 m3/h) with 1 worker thread, ``workers`` threads and, with ``dask``, a local
    Dask cluster of ``workers`` single-threaded worker processes. Modes are interleaved within each repeat; one
    record per mode (median simulations/s over the repeats, parallel efficiency = rate / (workers x rate with one
    worker)), with the load average before and after (the machine may be shared). Never asserts on time."""
    import numpy as np

    from . import design_space as ds
    from .flowsheet import load

    scene = os.path.join(repo_root(), "flowsheets", "stoeckl_gf25_batch.yaml")
    fs = load(scene)
    kw = dict(x=("inlet.T", "degC", 40, 80, n), y=("nozzle.mdot", "g/min", 60, 120, n), outputs=["d50_um"],
              progress=False)
    modes = [("threads", 1, "threads"), (f"threads_{workers}", workers, "threads")]
    cluster = client = None
    dask_startup = None
    if dask:
        try:
            from distributed import Client, LocalCluster
        except ImportError:
            dask = False
        else:
            t0 = time.perf_counter()
            cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                                   dashboard_address=None)
            client = Client(cluster)
            dask_startup = time.perf_counter() - t0
            modes.append((f"dask_{workers}", workers, client))
    load_before = os.getloadavg()
    walls: dict[str, list] = {m[0]: [] for m in modes}
    solves: dict[str, list] = {m[0]: [] for m in modes}
    d50 = {}
    try:
        ds.contour_map(fs, **{**kw, "x": ("inlet.T", "degC", 40, 80, 2), "y": ("nozzle.mdot", "g/min", 60, 120, 2)},
                       workers=workers)  # warm-up: imports, first clones
        if client is not None:
            ds.contour_map(fs, **{**kw, "x": ("inlet.T", "degC", 40, 80, 4)}, executor=client)
        for r in range(repeats):
            for name, w, exe in modes:
                if progress:
                    print(f"repeat {r + 1}/{repeats}: {name}", file=sys.stderr, flush=True)
                g = ds.contour_map(fs, **kw, workers=w, executor=exe)
                walls[name].append(g.wall_time_s)
                solves[name].append(g.solve_time_s / g.n_simulations)
                d50[name] = g["d50_um"]
    finally:
        if client is not None:
            client.close()
            cluster.close()
    load_after = os.getloadavg()
    sims = n * n
    base_rate = sims / statistics.median(walls["threads"])
    records = []
    for name, w, exe in modes:
        rate = sims / statistics.median(walls[name])
        records.append({
            "bench": "sweep", "mode": name, "workers": w, "grid": f"{n}x{n}", "simulations": sims,
            "repeats": repeats, "wall_s_median": statistics.median(walls[name]), "wall_s_all": walls[name],
            "sims_per_s": rate, "solve_ms_per_sim_median": statistics.median(solves[name]) * 1e3,
            "speedup": rate / base_rate, "parallel_efficiency": rate / (w * base_rate),
            "same_values_as_1_worker": bool(np.array_equal(d50[name], d50["threads"], equal_nan=True)),
            "dask_startup_s": dask_startup if name.startswith("dask") else None,
            "loadavg_before": list(load_before), "loadavg_after": list(load_after), "scene": scene,
            "command": "granuflow bench sweep", **meta()})
    return records


def sweep_summary(records) -> list[str]:
    r0 = records[0]
    lines = [f"Contour map {r0['grid']} (d50,3 after 60 min over inlet T x spray rate, GF25 batch scene), median of "
             f"{r0['repeats']} repeats ({r0['cores']} cores, commit {r0['commit']}):"]
    for r in records:
        lines.append(f"  {r['mode']:10s} {r['sims_per_s']:7.1f} simulations/s  (wall {r['wall_s_median']:.2f} s, "
                     f"solver {r['solve_ms_per_sim_median']:.2f} ms/simulation, speedup x{r['speedup']:.2f}, "
                     f"parallel efficiency {100 * r['parallel_efficiency']:.0f} %"
                     + (", same values" if r["same_values_as_1_worker"] else ", VALUES DIFFER") + ")")
    la, lb = r0["loadavg_before"], r0["loadavg_after"]
    lines.append(f"  load average before {la[0]:.2f} {la[1]:.2f} {la[2]:.2f}, after {lb[0]:.2f} {lb[1]:.2f} "
                 f"{lb[2]:.2f} (other processes share the cores); times are for information only.")
    return lines


def core_summary(records) -> list[str]:
    return ["  ".join(f"{k}={v:.4g}" if isinstance(v, float) else f"{k}={v}" for k, v in r.items()
                      if k not in ("machine", "cpu", "python", "date")) for r in records]
