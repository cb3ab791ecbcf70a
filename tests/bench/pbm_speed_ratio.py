#!/usr/bin/python3
"""Speed at equal error from the JSON records of granuflow_bench_pbm and scipy_fixed_pivot.py.

    build/tests/bench/granuflow_bench_pbm --json > granuflow.jsonl
    /usr/bin/python3 tests/bench/scipy_fixed_pivot.py --json > scipy.jsonl
    /usr/bin/python3 tests/bench/pbm_speed_ratio.py granuflow.jsonl scipy.jsonl [--levels 0.05 0.01 0.001]

For each case and error level: the fastest run of each code whose |err_M2| is at most the level (any method,
q and rtol), and the ratio of the SciPy time to granuflow's. The work-precision curve is the lower envelope of
solve_ms over |err_M2| of the records.
"""
from __future__ import annotations

import argparse
import json


def load(paths):
    recs = []
    for p in paths:
        with open(p) as f:
            recs += [json.loads(l) for l in f if l.startswith("{")]
    return recs


def fastest(recs, case, code, level, method_prefix=""):
    ok = [r for r in recs if r["case"] == case and r.get("code") == code and r["method"].startswith(method_prefix)
          and r["err_M2"] is not None and abs(r["err_M2"]) <= level and r.get("success", True)]
    return min(ok, key=lambda r: r["solve_ms"]) if ok else None


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("files", nargs="+")
    ap.add_argument("--levels", type=float, nargs="+", default=[0.05, 0.01, 0.001])
    args = ap.parse_args()
    recs = load(args.files)
    for case in sorted({r["case"] for r in recs}):
        for level in args.levels:
            g = fastest(recs, case, "granuflow", level)
            rows = [("granuflow", g)]
            for m in ("scipy_fp_LSODA", "scipy_fp_BDF", "scipy_upwind_LSODA", "scipy_upwind_BDF"):
                s = fastest(recs, case, "scipy", level, m)
                if s or m.startswith("scipy_fp") != (case == "growth"):
                    rows.append((m, s))
            desc = []
            for name, r in rows:
                if r is None:
                    desc.append(f"{name}: none")
                else:
                    ratio = f", x{r['solve_ms'] / g['solve_ms']:.1f}" if g and name != "granuflow" else ""
                    desc.append(f"{name}: {r['method']} q={r['q']} rtol={r['rtol']:.0e} "
                                f"M2 {r['err_M2']:+.2e} {r['solve_ms']:.2f} ms{ratio}")
            print(f"{case:9s} |err_M2| <= {level:g}:  " + "  |  ".join(desc))


if __name__ == "__main__":
    main()
