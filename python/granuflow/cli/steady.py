"""granuflow steady: the steady state of a scene, solved directly (Newton, with pseudo-transient continuation when
Newton alone fails); steady.json (the summary keys at the steady state, the boundary flows and their closure, the
stability, iterations, method, wall time) and steady_psd.csv (the size distributions) in --out."""
from __future__ import annotations

import csv
import json
import os
import sys

from ..flowsheet import load
from ..result import BalanceError
from ..structure import apply as apply_sets
from ..steady import steady_psd_rows, steady_report
from .common import check_out_dir, json_value, parse_seconds, parse_sets


def _clean(v):
    if isinstance(v, dict):
        return {k: _clean(x) for k, x in v.items()}
    if isinstance(v, (list, tuple)):
        return [_clean(x) for x in v]
    return json_value(v)


def cmd_steady(args) -> int:
    fs = apply_sets(load(args.scene), parse_sets(args.set))  # settings rebuild the flowsheet
    t = parse_seconds(args.t, "--t") if args.t else 0.0
    check_out_dir(args.out)
    failure = None
    try:
        rep = steady_report(fs, t=t, stability=not args.no_stability)
    except BalanceError as e:  # write steady.json, then exit 3 naming the balance
        rep, failure = e.report, e
    raw = rep.pop("_raw")
    os.makedirs(args.out, exist_ok=True)
    with open(os.path.join(args.out, "steady.json"), "w") as f:
        json.dump(_clean(rep), f, indent=2, allow_nan=False)
    rows = steady_psd_rows(fs, raw)
    written = ["steady.json"]
    if rows:
        with open(os.path.join(args.out, "steady_psd.csv"), "w", newline="") as f:
            w = csv.writer(f)
            w.writerow(["unit", "class", "d_um", "mass [kg]", "mass_fraction [-]"])
            for r in rows:
                w.writerow([r["unit"], r["class"], f"{r['d_um']:.6g}", f"{r['mass_kg']:.9g}",
                            f"{r['mass_fraction']:.9g}"])
        written.append("steady_psd.csv")
    for w in rep["warnings"]:
        if failure is None or w not in str(failure):  # the failure itself is the last line
            print(f"granuflow: warning: {w}", file=sys.stderr)
    if not args.quiet:
        s = rep["solver"]
        stab = rep["stability"]
        how = ("" if stab is None else "; stable" if stab["stable"] else
               "; neutral (a zero eigenvalue: nothing flows)" if stab["stable"] is None else
               f"; UNSTABLE: the dynamics oscillate around it (growth rate {stab['max_real_eigenvalue_1_s']:.3g} 1/s"
               + (f", period {stab['oscillation_period_s']:.4g} s)" if stab["oscillation_period_s"] else ")"))
        print(f"{fs.name}: steady state by {s['method']} in {s['iterations']} iterations"
              + (f" after {s['pseudo_steps']} pseudo-transient steps" if s["pseudo_steps"] else "")
              + f", {s['wall_time_s'] * 1e3:.1f} ms{how}; wrote {', '.join(written)} to {args.out}")
        keys = [k for k in fs.summary_map]
        print(json.dumps({k: _clean(rep[k]) for k in keys}))
    if failure is not None:
        raise failure
    return 0
