#!/usr/bin/python3
"""Speed at equal error from the JSON records of granuflow_bench_pbm and scipy_fixed_pivot.py.

    build/tests/bench/granuflow_bench_pbm --json > granuflow.jsonl
    /usr/bin/python3 tests/bench/scipy_fixed_pivot.py --json > scipy.jsonl
    PYTHONPATH=build/python /usr/bin/python3 tests/bench/pbm_speed_ratio.py granuflow.jsonl scipy.jsonl \
        [--levels 0.05 0.01 0.001]

For each case and error level: the fastest run of each code whose |err_M2| is at most the level (any method,
q and rtol), and the ratio of the SciPy time to granuflow's. The logic lives in granuflow.bench (speed_ratios,
format_speed_ratios), which `granuflow bench pbm` also uses; this script only reads files.
"""
from __future__ import annotations

import argparse
import os
import sys


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("files", nargs="+", help="JSON-lines files (--json output of either benchmark)")
    ap.add_argument("--levels", type=float, nargs="+", default=[0.05, 0.01, 0.001])
    args = ap.parse_args()
    try:
        from granuflow import bench
    except ImportError:  # run from the repository without PYTHONPATH: the default build folder
        sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "build", "python"))
        from granuflow import bench
    recs = bench.load_records(args.files)
    print("\n".join(bench.format_speed_ratios(bench.speed_ratios(recs, args.levels))))


if __name__ == "__main__":
    main()
