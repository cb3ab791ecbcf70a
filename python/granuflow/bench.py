"""Benchmarks (report figures, never pass/fail on time).

``granuflow bench core [--json]``: cost of one residual per state (ns/state) for chains of stirred tanks with
about 100, 1 000 and 10 000 states, the cost of one Jacobian relative to one residual, and the wall time of the
demo flowsheet (median of repeated runs).
``granuflow bench pbm [--json]``: population-balance work-precision records (tests/bench/).
"""
from __future__ import annotations

import json
import os
import platform
import statistics
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))


def _repo_root() -> str:
    # build/python/granuflow -> repo root is recorded by CMake next to the launcher; fall back to cwd
    for cand in (os.getcwd(), os.path.abspath(os.path.join(HERE, "..", "..", ".."))):
        if os.path.exists(os.path.join(cand, "flowsheets")):
            return cand
    return os.getcwd()


def _meta() -> dict:
    root = _repo_root()
    try:
        commit = subprocess.run(["git", "-C", root, "rev-parse", "--short", "HEAD"], capture_output=True,
                                text=True, timeout=10).stdout.strip()
    except Exception:  # noqa: BLE001 - metadata only
        commit = ""
    return {"machine": platform.node(), "cpu": platform.processor() or platform.machine(), "cores": os.cpu_count(),
            "python": sys.version.split()[0], "commit": commit, "date": time.strftime("%Y-%m-%d %H:%M:%S")}


def tank_chain_text(n_tanks: int) -> str:
    """Scene text: a feed, n_tanks stirred tanks in series and a product sink (4 n_tanks + 9 states)."""
    lines = ["scene: tank_chain", "t_end: 100 s", "units:", "  feed: {type: liquid_feed, params: {mdot: 0.5}}"]
    lines += [f"  t{i}: {{type: stirred_tank, params: {{mass: 100, Q: 1000}}}}" for i in range(n_tanks)]
    lines += ["  product: {type: liquid_product}", "connections:", "  - feed.out -> t0.in"]
    lines += [f"  - t{i}.out -> t{i + 1}.in" for i in range(n_tanks - 1)]
    lines += [f"  - t{n_tanks - 1}.out -> product.in"]
    return "\n".join(lines) + "\n"


def bench_core(repeats: int) -> list[dict]:
    from . import load, load_text

    records = []
    for target in (100, 1000, 10000):
        n_tanks = max(1, (target - 9) // 4)
        fs = load_text(tank_chain_text(n_tanks), f"tank_chain_{n_tanks}")
        t = fs._scene.time_residual(repeats)
        records.append({"bench": "residual", "states": t["states"], "units": n_tanks + 2,
                        "residual_ns_per_state": t["residual_s"] / t["states"] * 1e9,
                        "jacobian_over_residual": t["jacobian_s"] / t["residual_s"],
                        "jacobian_storage": "dense" if t["dense"] else "sparse", "nnz": t["nnz"], **_meta()})
    demo = os.path.join(_repo_root(), "flowsheets", "demo_tanks.yaml")
    fs = load(demo)
    walls = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        res = fs.simulate()
        walls.append(time.perf_counter() - t0)
    records.append({"bench": "demo_flowsheet", "scene": demo, "states": len(res.state_names),
                    "wall_ms_median": statistics.median(walls) * 1e3, "solve_ms_median_inside": res.wall_time_s * 1e3,
                    "steps": res.stats["steps"], "repeats": repeats,
                    "command": "granuflow bench core", **_meta()})
    return records


def bench_pbm(args) -> list[dict]:
    root = _repo_root()
    exe = None
    for cand in ("build/tests/bench/granuflow_bench_pbm", "build/tests/bench/granuflow_bench_pbm"):
        if os.path.exists(os.path.join(root, cand)):
            exe = os.path.join(root, cand)
    records = []
    if exe:
        out = subprocess.run([exe, "--json"], capture_output=True, text=True, check=True).stdout
        records += [json.loads(l) for l in out.splitlines() if l.startswith("{")]
    script = os.path.join(root, "tests", "bench", "scipy_fixed_pivot.py")
    if os.path.exists(script):
        out = subprocess.run(["/usr/bin/python3", script, "--json"], capture_output=True, text=True, check=True).stdout
        records += [json.loads(l) for l in out.splitlines() if l.startswith("{")]
    return records


def main(args) -> int:
    records = bench_core(args.repeats) if args.what == "core" else bench_pbm(args)
    if args.json:
        for r in records:
            print(json.dumps(r))
    else:
        for r in records:
            print("  ".join(f"{k}={v:.4g}" if isinstance(v, float) else f"{k}={v}" for k, v in r.items()
                            if k not in ("machine", "cpu", "python", "date")))
    return 0
