"""granuflow sweep."""
from __future__ import annotations

import json
import os
import sys

from .common import (EXIT_SOLVER, check_out_dir, check_workers, json_value, parse_seconds, parse_sets,
                     progress_option, with_unit_headers)


def cmd_sweep(args) -> int:
    """Run a sweep file; write DIR/sweep.csv and DIR/sweep.json. Exit 3 only if every point failed."""
    import time

    from .. import sweep as sw

    spec = sw.load_sweep(args.sweepfile)
    overrides = parse_sets(args.set)
    check_workers(args.workers)
    fs = spec.flowsheet(overrides)
    if args.t_end is not None:
        fs.set_t_end(parse_seconds(args.t_end))
    check_out_dir(args.out)
    t0 = time.perf_counter()
    df = spec.run(flowsheet=fs, workers=args.workers, executor=args.executor,
                  progress=progress_option(args), raise_errors=args.fail_fast, error_estimate=args.error_estimate)
    wall = time.perf_counter() - t0
    n_failed = int((df["status"] != sw.STATUS_OK).sum())
    effects = None
    if n_failed < len(df):
        try:
            effects = sw.main_effects(df)
        except ValueError:
            effects = None
    os.makedirs(args.out, exist_ok=True)
    with_unit_headers(df).to_csv(os.path.join(args.out, "sweep.csv"), index=False)
    meta = dict(df.attrs)
    record = {**meta, "sweep_file": os.path.abspath(args.sweepfile), "t_end_s": fs.t_end,
              "overrides": overrides, "n_points": len(df), "n_failed": n_failed, "wall_time_s": wall,
              "points": [{k: json_value(v) for k, v in row.items()} for row in df.to_dict(orient="records")],
              "main_effects": None if effects is None else
              {v: {o: json_value(x) for o, x in r.items()} for v, r in effects.to_dict(orient="index").items()}}
    with open(os.path.join(args.out, "sweep.json"), "w") as f:
        json.dump(record, f, indent=2, allow_nan=False)
    if not args.quiet:
        import pandas as pd

        cols = [c for c in df.columns if c not in ("message", "solve_time_s")]
        with pd.option_context("display.width", 200, "display.max_columns", None):
            print(df[cols].to_string(index=False, float_format=lambda x: f"{x:.4g}"))
            if effects is not None:
                print("main effects over the cube corners (mean at high level - mean at low level):")
                print(effects.to_string(float_format=lambda x: f"{x:.4g}"))
        print(f"{spec.name}: {len(df)} points ({n_failed} failed) in {wall:.2f} s; "
              f"wrote sweep.csv, sweep.json to {args.out}")
    warned = df.loc[(df["status"] == sw.STATUS_OK) & (df["message"] != "")]
    if len(warned):
        print(f"granuflow: {len(warned)} of {len(df)} points warn (see sweep.csv, message); first: "
              f"{warned.iloc[0]['point']}: {warned.iloc[0]['message']}", file=sys.stderr)
    if n_failed:
        first = df.loc[df["status"] != sw.STATUS_OK].iloc[0]
        print(f"granuflow: {n_failed} of {len(df)} points failed; first: {first['point']}: {first['message']}",
              file=sys.stderr)
    return EXIT_SOLVER if n_failed == len(df) else 0
