"""granuflow contour."""
from __future__ import annotations

import json
import os
import sys
from typing import Any

import numpy as np

from .. import sweep
from ..design_space import contour_map, feasible_window, make_axis, parse_constraints
from ..flowsheet import load
from ..plots.design_space import plot_contour, plot_feasible_window
from .common import (check_out_dir, check_workers, json_value, parse_seconds, parse_sets, progress_option,
                     with_unit_headers)


def _at(grid, i) -> str:
    """Where a grid point is, for messages: "particles.classes = 10, bed.aggregation = kapur"."""
    def one(ax, k):
        return f"{ax.param} = " + (ax.labels[k] if ax.labels else f"{ax.values[k]:g} {ax.unit}".strip())
    return f"{one(grid.x, i[1])}, {one(grid.y, i[0])}"


def cmd_contour(args) -> int:
    """``granuflow contour SCENE --x P:U:LO:HI:N --y ... --output O [--constraint "O>=V"] --out DIR``: writes
    contour.csv (one row per grid point; with constraints their margins and ``feasible``), contour.json (metadata,
    feasible window ranges and outline), contour_<output>.png and, with constraints, feasible_window.png and
    feasible_window.csv (the outline polygons). Returns 3 if every point failed, else 0."""
    fs = load(args.scene)
    fixed = parse_sets(args.set)
    t_end = None if args.t_end is None else parse_seconds(args.t_end)
    check_workers(args.workers)
    cons = parse_constraints(args.constraint or [])
    sweep.check_outputs(fs, list(args.output or ["d50_um"]), where="--output")
    for raw, c in zip(args.constraint or [], cons):
        sweep.check_outputs(fs, [c.output], where=f"--constraint '{raw}'")
    make_axis(fs, args.x, "--x")
    make_axis(fs, args.y, "--y")
    check_out_dir(args.out)
    outputs = list(dict.fromkeys(list(args.output or ["d50_um"]) + [c.output for c in cons]))
    executor: Any = args.executor
    client = None
    if args.dask:
        from distributed import Client

        client = executor = Client(args.dask)
    try:
        grid = contour_map(fs, args.x, args.y, outputs, fixed=fixed, t_end=t_end, workers=args.workers,
                           executor=executor, progress=progress_option(args), error_estimate=args.error_estimate,
                           steady=args.steady)
    finally:
        if client is not None:
            client.close()
    os.makedirs(args.out, exist_ok=True)
    df = grid.to_dataframe()
    written = ["contour.csv", "contour.json"]
    win = None
    if cons:
        win = feasible_window(grid, cons)
        wdf = win.to_dataframe()
        for c in wdf.columns[2:]:
            df[c] = wdf[c].to_numpy()
        win.outline_dataframe().to_csv(os.path.join(args.out, "feasible_window.csv"), index=False)
        plot_feasible_window(win, os.path.join(args.out, "feasible_window.png"), grid=grid, background=outputs[0])
        written += ["feasible_window.csv", "feasible_window.png"]
    with_unit_headers(df).to_csv(os.path.join(args.out, "contour.csv"), index=False)
    for o in grid.outputs:  # with --error-estimate also each output's estimated error (d50_um_err)
        if np.isfinite(grid[o]).sum() >= (4 if min(grid.shape) >= 2 else 2):  # a map, or a profile of >= 2 points
            plot_contour(grid, o, os.path.join(args.out, f"contour_{o}.png"), window=win)
            written.append(f"contour_{o}.png")
    n_failed = int((~grid.ok).sum())
    meta = {"scene": os.path.abspath(args.scene), "x": {"param": grid.x.param, "unit": grid.x.unit,
                                                        "values": list(grid.x.labels) or grid.x.values.tolist()},
            "y": {"param": grid.y.param, "unit": grid.y.unit, "values": list(grid.y.labels) or grid.y.values.tolist()},
            "outputs": list(grid.outputs), "fixed": fixed, "t_end_s": None if grid.steady else grid.t_end_s,
            "steady_state": bool(args.steady), "n_points": grid.n_simulations,
            "n_failed": n_failed, "wall_time_s": grid.wall_time_s,
            "simulations_per_s": json_value(grid.simulations_per_s),
            "constraints": [str(c) for c in cons], "units": dict(df.attrs.get("units", {}))}
    if win is not None:
        meta["feasible_fraction"] = win.fraction
        meta["feasible_ranges"] = win.ranges()
        meta["outline"] = [ring.tolist() for ring in win.outline]
    with open(os.path.join(args.out, "contour.json"), "w") as f:
        json.dump(meta, f, indent=2, allow_nan=False)
    if not args.quiet:
        print(f"{fs.name}: {grid.n_simulations} points ({n_failed} failed) in {grid.wall_time_s:.2f} s "
              f"({grid.simulations_per_s:.0f} simulations/s)"
              + (f"; feasible window: {100 * win.fraction:.0f} % of the grid, {win.ranges()}" if win else "")
              + f"; wrote {', '.join(written)} to {args.out}")
    warned = grid.ok & (grid.message != "")
    if warned.any():
        i = np.argwhere(warned)[0]
        print(f"granuflow: {int(warned.sum())} of {grid.n_simulations} points warn (see contour.csv, message); "
              f"first: {_at(grid, i)}: {grid.message[tuple(i)]}", file=sys.stderr)
    if n_failed:
        i = np.argwhere(~grid.ok)[0]
        print(f"granuflow: {n_failed} of {grid.n_simulations} points failed; first: {_at(grid, i)}: "
              f"{grid.message[tuple(i)]}", file=sys.stderr)
    return 3 if n_failed == grid.n_simulations else 0
