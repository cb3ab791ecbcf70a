"""granuflow bench core|pbm|pbm2d|scene|sweep|loop|targets: speed against error, never pass/fail on time. Every
subcommand honours --quick (a reduced set, stated in its help) and --repeats; progress goes to stderr on a terminal
only."""
from __future__ import annotations

import json
import sys

from .. import progress as progress_bars
from .common import ConfigError, check_at_least, one_line, progress_option


def cmd_bench(args) -> int:
    """Runs the benchmark; a failing baseline (a SciPy script, the pbm executable) is one line and exit 1."""
    try:
        return _bench(args)
    except RuntimeError as e:
        print(f"granuflow: benchmark failed: {one_line(e)}", file=sys.stderr)
        return 1


def _bench(args) -> int:
    from .. import bench

    check_at_least("--repeats", args.repeats, 1, 10000)
    progress = progress_bars.wanted(progress_option(args)) and not args.json
    if args.what == "sweep":  # design-space throughput
        kw = {"n": 9, "repeats": 1, "dask": False} if args.quick else {"repeats": args.repeats}
        records, summary = bench.bench_sweep(progress=progress, **kw), bench.sweep_summary
    elif args.what == "scene":
        records = bench.bench_scene(args.repeats, classes=(10,) if args.quick else (10, 20, 40),
                                    scipy=not args.no_scipy,
                                    scipy_repeats=1 if args.quick else max(1, min(5, args.repeats)), progress=progress)
        summary = bench.scene_summary
    elif args.what == "pbm2d":
        from .. import bench_2d

        records = bench_2d.bench_pbm2d(quick=args.quick, repeats=args.repeats, scipy=not args.no_scipy,
                                       progress=progress)
        summary = bench_2d.summary
    elif args.what == "loop":  # paper 003's sieve-mill loop to steady state, against SciPy
        from .. import bench_loop

        records = bench_loop.bench_loop(classes=(50,) if args.quick else (50, 100, 200),
                                        repeats=1 if args.quick else max(1, min(3, args.repeats)),
                                        scipy=not args.no_scipy, progress=progress)
        summary = bench_loop.loop_summary
    elif args.what == "targets":  # issue 32: every speed target beside its baseline
        from .. import bench_targets

        for name in args.only or []:
            if name not in bench_targets.TARGETS:
                raise ConfigError(f"--only {name}: not a target; the targets are {', '.join(bench_targets.TARGETS)}")
        records = bench_targets.bench_targets(quick=args.quick, repeats=args.repeats, only=args.only,
                                              scipy=not args.no_scipy, progress=progress)
        summary = bench_targets.summary
        if args.write_json:
            with open(args.write_json, "w") as f:
                json.dump(records, f, indent=1)
    elif args.what == "pbm":
        records = bench.bench_pbm(quick=args.quick, repeats=args.repeats, progress=progress)
        summary = bench.pbm_summary
    else:
        records, summary = bench.bench_core(args.repeats, quick=args.quick, progress=progress), bench.core_summary
    for line in [json.dumps(r) for r in records] if args.json else summary(records):
        print(line)
    return 0
