"""granuflow calibrate."""
from __future__ import annotations

import sys

from .common import check_at_least, check_out_dir, check_workers, progress_option


def cmd_calibrate(args) -> int:
    """Staged calibration (granuflow.calibration): report.json/.txt, CSV tables and parity plots (not with
    --no-plots) in DIR. Calibrates on the runs marked `use: calibration`, validates on `use: validation`."""
    from .. import calibration as cal

    exps = cal.load_experiments(args.experiments)
    fs = exps.flowsheet()
    plan = cal.load_stages(args.stages, fs)
    if not exps.calibration:
        raise cal.ConfigError(f"{args.experiments}: no run has `use: calibration`")
    options = dict(plan.options)
    check_workers(args.workers)
    check_at_least("--starts", args.starts, 1, 10000)
    check_at_least("--spread", args.spread, 0)
    check_out_dir(args.out)
    cal.check_stage_data(plan, exps.calibration, args.stages, args.experiments)
    if args.workers is not None:
        options["num_threads"] = args.workers
    if args.starts > 1:
        # the scene's values where the stage file gives no start, within the stages' bounds (as a single start)
        bounds = cal.stage_bounds(plan, fs)
        center = {**{n: min(max(fs.get(n), lo), hi) for n, (lo, hi) in bounds.items()}, **plan.start}
        starts = [center] + cal.random_starts(plan, args.starts - 1, center=center, spread=args.spread, seed=args.seed,
                                              flowsheet=fs)
        results = cal.multi_start(fs, exps.calibration, plan, starts, options=options, workers=args.workers,
                                  progress=progress_option(args))
        res = cal.best(results)
        failed = sum(not isinstance(r, cal.CalibrationResult) for r in results)
        if not args.quiet:
            print(f"{len(starts)} starts ({failed} failed); best cost {res.cost:.6g} from {res.label}")
    else:
        res = cal.calibrate(fs, exps.calibration, plan, options=options, label="staged",
                            progress=progress_option(args))
    comparison = None
    if args.compare:
        comparison = cal.calibrate(fs, exps.calibration, plan.simultaneous(), start=plan.start, options=options,
                                   label="all parameters at once", progress=progress_option(args))
    for w in res.warnings:  # also in report.json and report.txt; exit 0: the calibration is what was asked for
        print(f"granuflow: warning: {w}", file=sys.stderr)
    rep = cal.report(fs, res, exps.calibration, exps.validation, comparison=comparison, options=options,
                     error_estimate=args.error_estimate)
    written = rep.write(args.out, plots=not args.no_plots)
    if not args.quiet:
        print(res.full_report())
        if comparison is not None:
            print(f"all at once: cost {comparison.cost:.6g}, {comparison.simulations} simulations "
                  f"({comparison.sensitivity_solves} sensitivity solves), {comparison.wall_time_s:.2f} s")
        print(rep.fit_text())
        print(f"wrote {', '.join(written)} to {args.out}")
    return 0
