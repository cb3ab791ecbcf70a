"""granuflow run for a scene with ``engine: monte_carlo``: summary.json (values with confidence intervals, cost),
timeseries.csv, psd.csv and the plots (growth.png, psd.png) in --out."""
from __future__ import annotations

import json
import os

from ..montecarlo.scene import Scene
from ..quantity import ConfigError
from .common import check_out_dir, parse_seconds, parse_sets


def cmd_run_monte_carlo(args) -> int:
    for option, given in (("--accuracy", args.accuracy), ("--error-estimate", args.error_estimate)):
        if given:
            raise ConfigError(f"{option}: a monte_carlo scene has no discretization error to estimate; its "
                              "uncertainty is the confidence interval over the replicas (monte_carlo.replicas)")
    scene = Scene(args.scene)
    scene.apply_sets(parse_sets(args.set))
    t_end = parse_seconds(args.t_end) if args.t_end is not None else None
    check_out_dir(args.out)
    res = scene.run(t_end)
    os.makedirs(args.out, exist_ok=True)
    summary = {"scene": scene.name, **res.summary}
    with open(os.path.join(args.out, "summary.json"), "w") as f:
        json.dump(summary, f, indent=2, allow_nan=False)
    res.to_csv(os.path.join(args.out, "timeseries.csv"))
    res.psd_to_csv(os.path.join(args.out, "psd.csv"))
    written = ["summary.json", "timeseries.csv", "psd.csv"]
    if not args.no_plots:
        from ..montecarlo.plots import plot_growth, plot_psd

        plot_growth(res, os.path.join(args.out, "growth.png"))
        plot_psd(res, os.path.join(args.out, "psd.png"))
        written += ["growth.png", "psd.png"]
    if not args.quiet:
        cost = summary["cost"]
        print(f"{scene.name}: {res.t[-1]:g} s simulated, {res.raw['replicas']} replicas in {cost['wall_time_s']:.2f} s "
              f"({cost['events_per_s_per_core']:.3g} events/s per core, {cost['bytes_per_primary_particle']:.3g} "
              f"bytes per primary particle); wrote {', '.join(written)} to {args.out}")
        print(json.dumps({k: summary[k] for k in ("d_mean_over_d0", "d50_over_d0", "number", "dried_unused_share")}))
    return 0
