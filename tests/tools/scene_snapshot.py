"""Bit-for-bit snapshots of every shipped scene, for refactorings that must not change a result.

    PYTHONPATH=build/python /usr/bin/python3 tests/tools/scene_snapshot.py write OUT.npz
    PYTHONPATH=build/python /usr/bin/python3 tests/tools/scene_snapshot.py compare OLD.npz NEW.npz

`write` runs every scene in flowsheets/ (and the experiment scenes of the calibration folder) with its own settings,
plus variants that take the other integrator paths: sensitivities (IDAS and CVODES), the ODE methods on an ODE scene,
sparse and GMRES linear solvers, and the headline on finer grids. It stores times, states, derivatives, outputs,
sensitivities and the solver's counts of each. `compare` lists every run whose arrays or counts differ at all (with
the largest relative difference), and exits 1 if any does. Timings are not compared.
"""
from __future__ import annotations

import glob
import os
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
COUNTS = ("steps", "residuals", "jacobians", "linear_setups", "nonlinear_iterations", "error_test_failures",
          "nonlinear_failures", "reinits", "newton_starts", "calcic_starts", "states", "quadratures",
          "linear_iterations", "preconditioner_setups", "linear_failures")


# Two stirred tanks in series whose feed steps up at 100 s: the first tank's residence time falls from 50000 s to
# 0.1 s, so auto starts an explicit method that runs out of its step budget and hands the run to BDF.
STIFFENING_TANKS = """
scene: stiffening_tanks
t_end: 10000 s
output: {times: [0 s, 10 s, 5000 s, 10000 s]}
solver: {rtol: 1e-6, atol: 1e-10}
units:
  feed: {type: liquid_feed, params: {T: 60 degC, w: 0.2}}
  t0: {type: stirred_tank, params: {mass: 0.05, T0: 20 degC, w0: 0.0}}
  t1: {type: stirred_tank, params: {mass: 100, T0: 20 degC, w0: 0.0}}
  product: {type: liquid_product}
connections: [feed.out -> t0.in, t0.out -> t1.in, t1.out -> product.in]
inputs:
  feed.mdot: {interp: step, times: [0 s, 100 s], values: [1e-6 kg/s, 0.5 kg/s]}
"""


def is_scene(path):
    with open(path, encoding="utf-8") as f:
        # sweep files name a scene and vary it; a Monte Carlo scene (engine: monte_carlo) is no flowsheet
        return not any(line.startswith(("variables:", "engine: monte_carlo")) for line in f)


def variants():
    """(label, scene path or text, set-values, simulate keyword arguments)."""
    scenes = [p for p in sorted(glob.glob(os.path.join(ROOT, "flowsheets", "*.yaml"))) if is_scene(p)]
    out = [(os.path.relpath(p, ROOT), p, {}, {}) for p in scenes]
    head = os.path.join(ROOT, "flowsheets", "stoeckl_gf25_batch.yaml")
    pbm = os.path.join(ROOT, "flowsheets", "pbm_constant_kernel.yaml")
    tanks = os.path.join(ROOT, "flowsheets", "demo_tanks.yaml")
    loop = os.path.join(ROOT, "flowsheets", "continuous_layering_sieve_mill.yaml")
    out += [
        ("headline sens", head, {}, {"sensitivities": ["bed.agg_ln_beta0"]}),
        ("headline sens 3", head, {}, {"sensitivities": None}),
        ("headline 40 classes", head, {"refine": 4}, {}),
        ("headline sparse", head, {}, {"linear_solver": "sparse"}),
        ("pbm ida", pbm, {}, {"method": "ida"}),
        ("pbm bdf", pbm, {}, {"method": "bdf"}),
        ("pbm adams", pbm, {}, {"method": "adams"}),
        ("pbm erk", pbm, {}, {"method": "erk"}),
        ("tanks bdf", tanks, {}, {"method": "bdf"}),
        ("tanks bdf sens", tanks, {}, {"method": "bdf", "sensitivities": ["tank1.Q"]}),
        ("pbm auto sens", pbm, {}, {"sensitivities": None}),
        ("pbm bdf sens", pbm, {}, {"method": "bdf", "sensitivities": None}),
        ("pbm ida sens", pbm, {}, {"method": "ida", "sensitivities": None}),
        ("stiffening tanks auto", STIFFENING_TANKS, {}, {}),
        ("stiffening tanks bdf", STIFFENING_TANKS, {}, {"method": "bdf"}),
        ("tanks ida", tanks, {}, {"method": "ida"}),
        ("loop gmres", loop, {}, {"linear_solver": "gmres"}),
        ("loop sparse", loop, {}, {"linear_solver": "sparse"}),
    ]
    return out


def sens_params(fs, k):
    """The first k parameters of the flowsheet that a sensitivity run accepts (constants, not inputs)."""
    return [p for p in fs.params if not p.startswith("particles.")][:k]


def run_one(path, values, kwargs):
    import granuflow as gf
    fs = gf.load(path) if path.endswith(".yaml") else gf.load_text(path, "snapshot scene")
    values = dict(values)
    if "refine" in values:
        fs = fs.refined(values.pop("refine"))
    for k, v in values.items():
        fs.set(k, v)
    kwargs = dict(kwargs)
    if "sensitivities" in kwargs and kwargs["sensitivities"] is None:
        kwargs["sensitivities"] = sens_params(fs, 3)
    r = fs.simulate(warn=False, **kwargs)
    arrays = {"t": r.t, "y": r.y, "yp": r.yp, "outputs": r.outputs}
    if r.sens is not None and np.size(r.sens):
        arrays["sens"] = r.sens
    if r.output_sens is not None and np.size(r.output_sens):
        arrays["output_sens"] = r.output_sens
    arrays["counts"] = np.array([float(r.stats.get(c, -1)) for c in COUNTS])
    return arrays, str(r.stats.get("method", ""))


def write(path_out):
    data = {}
    for label, path, values, kwargs in variants():
        try:
            arrays, method = run_one(path, values, kwargs)
        except Exception as e:  # a variant that fails is recorded as failing, to be compared as such
            print(f"{label}: {type(e).__name__}: {e}", flush=True)
            data[f"{label}|error"] = np.array(f"{type(e).__name__}: {e}")
            continue
        for k, v in arrays.items():
            data[f"{label}|{k}"] = np.asarray(v)
        data[f"{label}|method"] = np.array(method)
        print(f"{label}: {method}, {int(arrays['counts'][0])} steps", flush=True)
    np.savez(path_out, **data)


def compare(a_path, b_path):
    a, b = np.load(a_path), np.load(b_path)
    bad = 0
    labels = sorted({k.split("|")[0] for k in list(a.files) + list(b.files)})
    for label in labels:
        ka = sorted(k for k in a.files if k.startswith(label + "|"))
        kb = sorted(k for k in b.files if k.startswith(label + "|"))
        diffs = []
        if ka != kb:
            diffs.append(f"keys {[k.split('|')[1] for k in ka]} vs {[k.split('|')[1] for k in kb]}")
        for k in sorted(set(ka) & set(kb)):
            x, y = a[k], b[k]
            if x.dtype.kind in "US" or y.dtype.kind in "US":
                if str(x) != str(y):
                    diffs.append(f"{k.split('|')[1]}: {x} vs {y}")
                continue
            if x.shape != y.shape:
                diffs.append(f"{k.split('|')[1]}: shape {x.shape} vs {y.shape}")
            elif not np.array_equal(x, y, equal_nan=True):
                with np.errstate(all="ignore"):
                    rel = np.nanmax(np.abs(x - y) / np.maximum(np.abs(x), 1e-300))
                diffs.append(f"{k.split('|')[1]}: max relative difference {rel:.3g}")
        if diffs:
            bad += 1
            print(f"DIFFERS {label}: " + "; ".join(diffs))
        else:
            print(f"same    {label}")
    print(f"{len(labels) - bad} bit-identical, {bad} differ")
    return 1 if bad else 0


if __name__ == "__main__":
    if len(sys.argv) == 3 and sys.argv[1] == "write":
        write(sys.argv[2])
    elif len(sys.argv) == 4 and sys.argv[1] == "compare":
        sys.exit(compare(sys.argv[2], sys.argv[3]))
    else:
        print(__doc__)
        sys.exit(2)
