"""Command line: ``granuflow run SCENE --out DIR [--set unit.param=value ...] [--t-end SECONDS]``,
``granuflow sweep SWEEPFILE --out DIR [--workers N] [--set unit.param=value ...]``,
``granuflow calibrate EXPERIMENTS --stages STAGES --out DIR [--starts N] [--workers N] [--compare]``.

Exit codes: 0 success, 2 bad input (scene, option, parameter), 3 solver failure. A failure prints one line
on stderr naming what went wrong.
"""
from __future__ import annotations

import argparse
import json
import os
import sys

EXIT_BAD_INPUT = 2
EXIT_SOLVER = 3


class _Parser(argparse.ArgumentParser):
    def error(self, message):  # argparse exits 2 too, but with a usage block; keep it to one line
        print(f"granuflow: {message}", file=sys.stderr)
        sys.exit(EXIT_BAD_INPUT)


def _parse_seconds(text: str) -> float:
    from .sweep import _parse_time

    return _parse_time(text, "--t-end")


def parse_sets(items) -> dict:
    """``--set unit.param=value`` options as {name: value text}; a malformed one is bad input."""
    from ._core import ConfigError

    overrides = {}
    for item in items or []:
        if "=" not in item:
            raise ConfigError(f"--set '{item}': expected unit.param=value")
        name, value = item.split("=", 1)
        overrides[name.strip()] = value.strip()
    return overrides


def check_workers(workers) -> None:
    _check_at_least("--workers", workers, 1)


def _check_at_least(option: str, value, lower) -> None:
    from ._core import ConfigError

    if value is not None and not value >= lower:
        raise ConfigError(f"{option} = {value}: expected a number >= {lower}")


_SERIES_KEYS = ("title", "y", "unit", "ylabel", "file")
_PSD_KEYS = ("kind", "times_min", "file")


def check_out_dir(out: str, option: str = "--out") -> None:
    """The output folder: an existing folder or a path that can be created (not an existing file)."""
    from ._core import ConfigError

    if os.path.exists(out) and not os.path.isdir(out):
        raise ConfigError(f"{option} = '{out}': an existing file, not a folder (give a folder to write to)")
    parent = out
    while parent and not os.path.exists(parent):
        parent = os.path.dirname(parent.rstrip(os.sep))
    if parent and not os.path.isdir(parent):
        raise ConfigError(f"{option} = '{out}': '{parent}' is a file, not a folder (give a folder to write to)")


def _plot_file(name, where: str, formats: list[str]) -> str:
    """A plot's `file:`: a plain file name (no folder) with an extension matplotlib writes."""
    from ._core import ConfigError

    if not isinstance(name, str) or not name.strip():
        raise ConfigError(f"{where} = {name!r}: expected a file name such as plot.png")
    if name != os.path.basename(name) or "/" in name or "\\" in name or name in (".", "..") or os.path.isabs(name):
        raise ConfigError(f"{where} = '{name}': expected a plain file name inside the output folder "
                          "(no folder part, e.g. plot.png)")
    ext = os.path.splitext(name)[1].lstrip(".").lower()
    if ext not in formats:
        raise ConfigError(f"{where} = '{name}': extension '{ext}' is not an image format matplotlib writes "
                          f"(allowed: {', '.join(formats)})")
    return name


def _plot_specs(fs) -> list[dict]:
    """The scene's ``plots:`` list, checked before the run: each ``kind: psd`` (``times_min`` within the scene's
    t_end; a shorter ``--t-end`` leaves the later times out of the plot and says so) or
    with ``y``, a list of names, and a ``unit`` that fits them; ``file`` a plain image file name."""
    import math

    from . import plots
    from ._core import ConfigError, observable_unit

    specs = fs.extra.get("plots") or []
    where = f"{fs.path or fs.name}: plots"
    if not isinstance(specs, list):
        raise ConfigError(f"{where}: expected a list of plot mappings, got {specs!r}")
    known = set(fs.state_names) | set(fs.output_names)
    formats = plots.supported_formats() if specs else []
    t_end_min = fs.t_end / 60.0
    for k, spec in enumerate(specs):
        w = f"{where}[{k}]"
        if isinstance(spec, dict) and "kind" in spec:
            if spec["kind"] != "psd":
                raise ConfigError(f"{w}.kind = {spec['kind']!r}: not one of psd (or leave kind out and give y)")
            for key in spec:
                if key not in _PSD_KEYS:
                    raise ConfigError(f"{w}: unknown key '{key}' (allowed for kind psd: {', '.join(_PSD_KEYS)})")
            if "file" in spec:
                _plot_file(spec["file"], f"{w}.file", formats)
            if "times_min" in spec:
                times = spec["times_min"]
                if not isinstance(times, list) or not times:
                    raise ConfigError(f"{w}.times_min = {times!r}: expected a non-empty list of times in minutes")
                for i, t in enumerate(times):
                    ok = isinstance(t, (int, float)) and not isinstance(t, bool) and math.isfinite(t)
                    if not ok or not 0 <= t <= t_end_min * (1 + 1e-12):
                        raise ConfigError(f"{w}.times_min[{i}] = {t!r}: expected a time in minutes within "
                                          f"[0, {t_end_min:g}] (the scene's t_end)")
            continue
        if not isinstance(spec, dict) or not isinstance(spec.get("y"), list):
            raise ConfigError(f"{w} = {spec!r}: expected a mapping with y: [state or output names] "
                              "(or kind: psd)")
        for key in spec:
            if key not in _SERIES_KEYS:
                raise ConfigError(f"{w}: unknown key '{key}' (allowed: {', '.join(_SERIES_KEYS)}; or kind: psd)")
        unit = spec.get("unit", "")
        if unit is None:
            unit = ""
        if not isinstance(unit, str):
            raise ConfigError(f"{w}.unit = {unit!r}: expected a unit name (allowed: {', '.join(plots.display_units())})")
        for n in spec["y"]:
            if n not in known:
                raise ConfigError(f"{w}.y: '{n}' is neither a state nor an output of scene '{fs.name}'")
            try:
                plots.conversion(unit, observable_unit(fs._scene, n))
            except ValueError as e:
                raise ConfigError(f"{w}.unit = '{unit}' for {n}: {e}") from None
        if "file" in spec:
            _plot_file(spec["file"], f"{w}.file", formats)
    return specs


def cmd_run(args) -> int:
    from . import load, plots

    fs = load(args.scene)
    fs.update(parse_sets(args.set))
    specs = _plot_specs(fs)  # against the scene file's own t_end
    if args.t_end:
        fs.set_t_end(_parse_seconds(args.t_end))
    check_out_dir(args.out)
    res = fs.simulate()
    os.makedirs(args.out, exist_ok=True)
    summary = res.summary
    with open(os.path.join(args.out, "summary.json"), "w") as f:
        json.dump(summary, f, indent=2, allow_nan=False)
    res.timeseries.to_csv(os.path.join(args.out, "timeseries.csv"))
    written = ["summary.json", "timeseries.csv"]
    has_psd = bool(res.psd_units())
    for k, spec in enumerate(specs):
        if spec.get("kind") == "psd":
            if has_psd:
                name = spec.get("file", "psd.png")
                times = [t * 60.0 for t in spec["times_min"]] if "times_min" in spec else None
                late = [t / 60.0 for t in times or [] if t > res.t[-1] * (1 + 1e-12)]
                if times is not None:
                    times = [t for t in times if t <= res.t[-1] * (1 + 1e-12)] or None
                plots.plot_psd(res, os.path.join(args.out, name), times)
                written.append(name + (f" (times after the run's end left out: {', '.join(f'{t:g}' for t in late)} min)"
                                       if late else ""))
            continue
        name = spec.get("file", f"plot_{k}.png")
        plots.plot_series(res, spec, os.path.join(args.out, name))
        written.append(name)
    if has_psd and not any(s.get("kind") == "psd" for s in specs):
        plots.plot_psd(res, os.path.join(args.out, "psd.png"))
        written.append("psd.png")
    if not args.quiet:
        print(f"{fs.name}: {res.t[-1]:g} s simulated in {res.wall_time_s * 1e3:.1f} ms "
              f"({res.stats['steps']} steps); wrote {', '.join(written)} to {args.out}")
        print(json.dumps({k: summary[k] for k in summary if k not in ("solver",)}, indent=None))
    return 0


def cmd_sweep(args) -> int:
    """Run a sweep file; write DIR/sweep.csv and DIR/sweep.json. Exit 3 only if every point failed."""
    import time

    from . import sweep as sw

    spec = sw.load_sweep(args.sweepfile)
    overrides = parse_sets(args.set)
    check_workers(args.workers)
    fs = spec.flowsheet(overrides)
    if args.t_end:
        fs.set_t_end(_parse_seconds(args.t_end))
    check_out_dir(args.out)
    t0 = time.perf_counter()
    df = spec.run(flowsheet=fs, workers=args.workers, executor=args.executor,
                  progress=False if args.no_progress else None, raise_errors=args.fail_fast)
    wall = time.perf_counter() - t0
    n_failed = int((df["status"] != sw.STATUS_OK).sum())
    effects = None
    if n_failed < len(df):
        try:
            effects = sw.main_effects(df)
        except ValueError:
            effects = None
    os.makedirs(args.out, exist_ok=True)
    df.to_csv(os.path.join(args.out, "sweep.csv"), index=False)
    meta = dict(df.attrs)
    record = {**meta, "sweep_file": os.path.abspath(args.sweepfile), "t_end_s": fs.t_end,
              "overrides": overrides, "n_points": len(df), "n_failed": n_failed, "wall_time_s": wall,
              "points": [{k: _json_value(v) for k, v in row.items()} for row in df.to_dict(orient="records")],
              "main_effects": None if effects is None else
              {v: {o: _json_value(x) for o, x in r.items()} for v, r in effects.to_dict(orient="index").items()}}
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
    if n_failed:
        first = df.loc[df["status"] != sw.STATUS_OK].iloc[0]
        print(f"granuflow: {n_failed} of {len(df)} points failed; first: {first['point']}: {first['message']}",
              file=sys.stderr)
    return EXIT_SOLVER if n_failed == len(df) else 0


def _json_value(v):
    import math

    if hasattr(v, "item"):
        v = v.item()
    if isinstance(v, float) and not math.isfinite(v):
        return None
    return v


def cmd_units(args) -> int:
    from . import unit_types

    for name, desc in unit_types().items():
        print(f"{name:24s} {desc}")
    return 0


def cmd_describe(args) -> int:
    from . import load

    import pandas as pd

    with pd.option_context("display.max_rows", None, "display.width", 200, "display.max_colwidth", 60):
        print(load(args.scene).describe())
    return 0


def cmd_bench(args) -> int:
    from . import bench

    _check_at_least("--repeats", args.repeats, 1)
    return bench.main(args)


def cmd_calibrate(args) -> int:
    """Staged calibration (granuflow.calibration): report.json/.txt, CSV tables and parity plots in DIR.
    Calibrates on the runs marked `use: calibration`, validates on `use: validation`."""
    from . import calibration as cal

    exps = cal.load_experiments(args.experiments)
    fs = exps.flowsheet()
    plan = cal.load_stages(args.stages, fs)
    if not exps.calibration:
        raise cal.ConfigError(f"{args.experiments}: no run has `use: calibration`")
    options = dict(plan.options)
    check_workers(args.workers)
    _check_at_least("--starts", args.starts, 1)
    _check_at_least("--spread", args.spread, 0)
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
                                  progress=False if args.no_progress else None)
        res = cal.best(results)
        failed = sum(not isinstance(r, cal.CalibrationResult) for r in results)
        if not args.quiet:
            print(f"{len(starts)} starts ({failed} failed); best cost {res.cost:.6g} from {res.label}")
    else:
        res = cal.calibrate(fs, exps.calibration, plan, options=options, label="staged")
    comparison = None
    if args.compare:
        comparison = cal.calibrate(fs, exps.calibration, plan.simultaneous(), start=plan.start, options=options,
                                   label="all parameters at once")
    rep = cal.report(fs, res, exps.calibration, exps.validation, comparison=comparison)
    written = rep.write(args.out)
    if not args.quiet:
        print(res.full_report())
        if comparison is not None:
            print(f"all at once: cost {comparison.cost:.6g}, {comparison.simulations} simulations "
                  f"({comparison.sensitivity_solves} sensitivity solves), {comparison.wall_time_s:.2f} s")
        print(rep.fit.to_string(float_format=lambda x: f"{x:.4g}"))
        print(f"wrote {', '.join(written)} to {args.out}")
    return 0


def cmd_contour(args) -> int:
    from . import design_space

    return design_space.contour_command(args)


def _add_batch_options(p) -> None:
    """Options shared by the commands that run many points (sweep, contour)."""
    p.add_argument("--workers", type=int, help="parallel solves (default: number of cores)")
    p.add_argument("--set", action="append", metavar="UNIT.PARAM=VALUE",
                   help="override a scene parameter for every point (unit allowed)")
    p.add_argument("--t-end", help="end time of every run in seconds (or with a unit, e.g. '60 min')")
    p.add_argument("--executor", default="threads", choices=["threads", "serial"])
    p.add_argument("--no-progress", action="store_true", help="no progress bar (default: only on a terminal)")
    p.add_argument("--quiet", action="store_true")


def main(argv=None) -> int:
    p = _Parser(prog="granuflow", description="spray fluidized-bed flowsheet simulation")
    sub = p.add_subparsers(dest="cmd", required=True, parser_class=_Parser)
    r = sub.add_parser("run", help="simulate a scene and write summary.json, CSV and plots")
    r.add_argument("scene")
    r.add_argument("--out", required=True, help="output folder (created)")
    r.add_argument("--set", action="append", metavar="UNIT.PARAM=VALUE", help="override a parameter (unit allowed)")
    r.add_argument("--t-end", help="end time in seconds (or with a unit, e.g. '60 min')")
    r.add_argument("--quiet", action="store_true")
    r.set_defaults(func=cmd_run)
    w = sub.add_parser("sweep", help="run a sweep file; write sweep.csv and sweep.json")
    w.add_argument("sweepfile")
    w.add_argument("--out", required=True, help="output folder (created)")
    _add_batch_options(w)
    w.add_argument("--fail-fast", action="store_true", help="stop at the first failed point (exit 3)")
    w.set_defaults(func=cmd_sweep)
    k = sub.add_parser("contour", help="contour map of outputs over two parameters; feasible window; CSV and PNG")
    k.add_argument("scene")
    k.add_argument("--x", required=True, metavar="UNIT.PARAM:UNIT:LO:HI:N", help="e.g. inlet.T:degC:40:80:15 (N: 1 to 401 points)")
    k.add_argument("--y", required=True, metavar="UNIT.PARAM:UNIT:LO:HI:N", help="e.g. nozzle.mdot:g/min:60:120:15 (N: 1 to 401 points)")
    k.add_argument("--output", action="append", help="summary key or state/output name (repeatable; default d50_um)")
    k.add_argument("--constraint", action="append", metavar="OUTPUT>=VALUE", help='e.g. "bed_moisture_wet<0.04"')
    k.add_argument("--out", required=True, help="output folder (created)")
    _add_batch_options(k)
    k.add_argument("--dask", metavar="ADDRESS", help="run on the Dask scheduler at ADDRESS (tcp://host:8786)")
    k.set_defaults(func=cmd_contour)
    u = sub.add_parser("units", help="list the built-in unit types")
    u.set_defaults(func=cmd_units)
    d = sub.add_parser("describe", help="list a scene's parameters with units, bounds and sources")
    d.add_argument("scene")
    d.set_defaults(func=cmd_describe)
    b = sub.add_parser("bench", help="benchmarks: speed against error (never pass/fail on time)")
    b.add_argument("what", choices=["core", "pbm", "scene", "sweep"])
    b.add_argument("--json", action="store_true", help="print JSON records")
    b.add_argument("--repeats", type=int, default=7)
    b.add_argument("--quick", action="store_true", help="pbm: a reduced set (q 1, 2, 4; rtol 1e-4, 1e-6)")
    b.add_argument("--no-scipy", action="store_true", help="scene: time granuflow only")
    b.set_defaults(func=cmd_bench)
    c = sub.add_parser("calibrate", help="staged calibration against experiments; report, tables, parity plots")
    c.add_argument("experiments", help="experiment file (YAML, see granuflow.calibration)")
    c.add_argument("--stages", required=True, help="stage file (YAML): free parameters, bounds, observables")
    c.add_argument("--out", required=True, help="output folder (created)")
    c.add_argument("--workers", type=int, help="threads: experiments in parallel, or starts with --starts")
    c.add_argument("--starts", type=int, default=1, help="multi-start: number of starts (the first is the file's)")
    c.add_argument("--spread", type=float, default=1.0, help="multi-start: ± spread in ln units around the start")
    c.add_argument("--seed", type=int, default=0, help="multi-start: random seed")
    c.add_argument("--compare", action="store_true", help="also fit all parameters at once from the same start")
    c.add_argument("--no-progress", action="store_true", help="no progress bar (default: only on a terminal)")
    c.add_argument("--quiet", action="store_true")
    c.set_defaults(func=cmd_calibrate)
    args = p.parse_args(argv)

    from . import _core

    try:
        return args.func(args)
    except (_core.ConfigError, FileNotFoundError) as e:
        print(f"granuflow: bad input: {_one_line(e)}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except (_core.SolverError, _core.CalibrationError) as e:
        print(f"granuflow: solver failure: {_one_line(e)}", file=sys.stderr)
        return EXIT_SOLVER


def _one_line(e: BaseException) -> str:
    return " ".join(str(e).split())
