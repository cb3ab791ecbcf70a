"""granuflow run: one simulation; summary.json, timeseries.csv and the scene's plots in --out.

Kept fast as a whole process: the core only; matplotlib (and with it NumPy) is imported only when plots are drawn
(``--no-plots`` skips them), pandas not at all."""
from __future__ import annotations

import json
import os
import stat
import sys

from ..flowsheet import load
from ..structure import apply as apply_sets
from ..plots.spec import plot_specs
from ..result import BalanceError
from .common import check_out_dir, parse_seconds, parse_sets, parse_times


def _draw(res, specs, out: str) -> list[str]:
    from ..plots import plot_psd, plot_series

    written = []
    has_psd = bool(res.psd_units())
    for k, spec in enumerate(specs):
        if spec.get("kind") == "psd":
            if has_psd:
                name = spec.get("file", "psd.png")
                times = [t * 60.0 for t in spec["times_min"]] if "times_min" in spec else None
                late = [t / 60.0 for t in times or [] if t > res.t[-1] * (1 + 1e-12)]
                if times is not None:
                    times = [t for t in times if t <= res.t[-1] * (1 + 1e-12)] or None
                plot_psd(res, os.path.join(out, name), times)
                written.append(name + (f" (times after the run's end left out: {', '.join(f'{t:g}' for t in late)} min)"
                                       if late else ""))
            continue
        name = spec.get("file", f"plot_{k}.png")
        plot_series(res, spec, os.path.join(out, name))
        written.append(name)
    if has_psd and not any(s.get("kind") == "psd" for s in specs):
        plot_psd(res, os.path.join(out, "psd.png"))
        written.append("psd.png")
    return written


def _accuracy_option(text):
    """--accuracy: None (the scene's), False ('off'), a relative error ('1%') or per key ('d50_um=1%,d90_um=3%')."""
    if text is None:
        return None
    if text.strip().lower() in ("off", "none", "false"):
        return False
    if "=" in text:
        return dict(item.split("=", 1) for item in text.split(",") if item.strip())
    return text


def _may_be_monte_carlo(path: str) -> bool:
    """False when the scene file cannot ask for the Monte Carlo engine: its text does not name it (nor escapes a
    character, which could spell it), so its YAML need not be parsed twice, once here in pure Python."""
    try:
        st = os.stat(path)
        if not stat.S_ISREG(st.st_mode) or st.st_size > 1 << 20:
            return True  # a fifo would block, a device never end: the loader names what is wrong with it
        with open(path, "rb") as f:
            data = f.read()
    except OSError:
        return True
    return b"monte_carlo" in data or b"\\" in data


def cmd_run(args) -> int:
    if _may_be_monte_carlo(args.scene):
        from ..montecarlo.scene import is_scene as is_monte_carlo

        if is_monte_carlo(args.scene):  # engine: monte_carlo (docs/monte_carlo.md)
            from .run_montecarlo import cmd_run_monte_carlo

            return cmd_run_monte_carlo(args)
    fs = apply_sets(load(args.scene), parse_sets(args.set))  # settings rebuild the flowsheet
    specs = plot_specs(fs, drawing=not args.no_plots)  # against the scene file's own t_end
    if args.t_end is not None:
        fs.set_t_end(parse_seconds(args.t_end))
    check_out_dir(args.out)
    ckpt = {}
    if args.checkpoint_at is not None:
        ckpt["checkpoints"] = parse_times(args.checkpoint_at, "--checkpoint-at")
    if args.checkpoint_at is not None or fs.scene_checkpoints:
        os.makedirs(args.out, exist_ok=True)
        ckpt["checkpoint_dir"] = args.out
    if args.restart is not None:
        ckpt["restart"] = args.restart
    failure = None
    try:
        res = fs.simulate(warn=False, error_estimate=args.error_estimate, accuracy=_accuracy_option(args.accuracy),
                          grid_check=not args.no_grid_check and fs.scene_accuracy is not False, **ckpt)
    except BalanceError as e:  # a unit lost mass: write what happened, then exit 3 naming the balance
        res, failure = e.result, e
    for w in res.warnings:  # also in summary.json; exit 0 (but for a failed balance): the run is what was asked for
        if failure is None or w not in str(failure):  # the failure itself is the last line
            print(f"granuflow: warning: {w}", file=sys.stderr)
    os.makedirs(args.out, exist_ok=True)
    summary = res.summary
    with open(os.path.join(args.out, "summary.json"), "w") as f:
        json.dump(summary, f, indent=2, allow_nan=False)
    res.to_csv(os.path.join(args.out, "timeseries.csv"))
    written = ["summary.json", "timeseries.csv"]
    if not args.no_plots:
        written += _draw(res, specs, args.out)
    if not args.quiet:
        print(f"{fs.name}: {res._t_at(-1):g} s simulated in {res.wall_time_s * 1e3:.1f} ms "
              f"({res.stats['steps']} steps); wrote {', '.join(written)} to {args.out}")
        print(json.dumps({k: summary[k] for k in summary
                          if k not in ("solver", "units", "grid_end", "warnings", "error_estimate", "accuracy",
                                       "grid_check", "material")}, indent=None))
        if res.accuracy is not None:
            for line in res.accuracy.lines():
                print(line)
        if res.error_estimate is not None:
            ee = res.error_estimate
            print(f"estimated numerical error ({ee.grid or 'no size grid'}; rtol {ee.rtol[0]:g} vs {ee.rtol[1]:g}; "
                  f"{ee.wall_time_s:.2f} s of re-solves):")
            for line in ee.lines():
                print("  " + line)
    if failure is not None:
        raise failure
    return 0
