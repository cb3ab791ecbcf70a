#!/usr/bin/python3
"""The baseline a Python user would write: the fixed pivot technique (Kumar & Ramkrishna 1996) in NumPy,
integrated with scipy.integrate.solve_ivp (BDF and LSODA, finite-difference Jacobians as solve_ivp does by
default), on the same cases, grids, initial binning and tolerances as granuflow_bench_pbm.

    /usr/bin/python3 tests/bench/scipy_fixed_pivot.py [--json] [--repeats R] [--quick] [--case NAME]

(Debian's /usr/bin/python3: the `python3` first on PATH may not see numpy/scipy.) One record per run with the
keys of granuflow_bench_pbm: case, method (scipy_fp_BDF, scipy_fp_LSODA; growth: scipy_upwind_*), q, classes,
rtol, tau, err_M0, err_M2, err_L1, mass_drift, solve_ms (median of R repeats of solve_ivp in one process).
Growth has no pivot scheme: the baseline there is first-order upwind finite volumes in diameter.
"""
from __future__ import annotations

import argparse
import json
import math
import os
import platform
import statistics
import subprocess
import sys
import time

import numpy as np
from scipy.integrate import solve_ivp
from scipy.special import i1e

CASES = {"constant": 100.0, "sum": 3.0, "product": 0.4, "growth": 1.0, "breakage": 10.0}


# ------------------------------------------------------------------ grid (same as kernels/discretization/grid.cpp)
def grid(q: int, doublings: int):
    n = doublings * q
    e = 2.0 ** -12 * np.exp2(np.arange(n + 1) / q)
    x = 0.5 * (e[:-1] + e[1:])
    x_lo, x_hi = x[0] ** 2 / x[1], x[-1] ** 2 / x[-2]
    return e, x, x_lo, x_hi


def initial(e, x, x_lo, x_hi):
    """Exponential n = exp(-v): exact cell number and volume, split on the pivots keeping both (as granuflow's
    'moments' binning), virtual-pivot shares folded back by volume."""
    a, h = e[:-1], np.diff(e)
    num = -np.exp(-a) * np.expm1(-h)
    vol = np.exp(-a) * (-(1 + a) * np.expm1(-h) - h * np.exp(-h))
    n = len(x)
    xe = np.concatenate(([x_lo], x, [x_hi]))  # extended pivots, index i + 1
    N = np.zeros(n + 2)
    for i in range(n):
        lo = i if vol[i] >= x[i] * num[i] else i - 1
        xa, xb = xe[lo + 1], xe[lo + 2]
        nu = (vol[i] - xa * num[i]) / (xb - xa)
        N[lo + 1] += num[i] - nu
        N[lo + 2] += nu
    N[1] += N[0] * x_lo / x[0]
    N[n] += N[n + 1] * x_hi / x[-1]
    return N[1:n + 1]


# ------------------------------------------------------------------ fixed pivot aggregation
def aggregation_rhs(x, x_hi, kernel):
    n = len(x)
    J, K = np.triu_indices(n)
    v = x[J] + x[K]
    beta = {"constant": np.ones_like(v), "sum": v, "product": x[J] * x[K]}[kernel]
    beta = beta * np.where(J == K, 0.5, 1.0)
    a = np.searchsorted(x, v, side="right") - 1          # lower pivot
    inside = v < x[-1]
    top = (v >= x[-1]) & (v < x_hi)                       # split with the virtual pivot above
    xa = x[np.clip(a, 0, n - 1)]
    xb = np.where(inside, x[np.clip(a + 1, 0, n - 1)], x_hi)
    wb = np.where(inside | top, (v - xa) / (xb - xa), 0.0)
    wa = np.where(inside | top, 1.0 - wb, 0.0)
    A = np.where(inside | top, a, n)                      # row n: outside (number above)
    B = np.where(inside, a + 1, n)
    out_vol = np.where(top, wb * x_hi, np.where(inside, 0.0, v))
    out_num = np.where(inside | top, 0.0, 1.0)

    def rhs(t, y):
        N = y[:n]
        r = beta * N[J] * N[K]
        d = -np.bincount(J, r, n) - np.bincount(K, r, n)
        birth = np.bincount(A, r * wa, n + 1) + np.bincount(B, r * (wb + out_num), n + 1)
        d += birth[:n]
        return np.concatenate((d, [birth[n], np.dot(r, out_vol)]))

    return rhs, 2


# ------------------------------------------------------------------ fixed pivot breakage (b = 2/u, S = v)
def breakage_rhs(x, x_lo):
    n = len(x)
    xe = np.concatenate(([x_lo], x))
    A = np.zeros((n + 1, n))                              # row n: volume below
    for k in range(n):
        u = x[k]
        A[n, k] += u * (x_lo / u) ** 2                     # fragments below x_lo
        for a in range(-1, k):
            lo, hi = xe[a + 1], xe[a + 2]
            num = 2.0 * (hi - lo) / u
            vol = (hi * hi - lo * lo) / u
            nu = (vol - lo * num) / (hi - lo)
            if a >= 0:
                A[a, k] += num - nu
            else:
                A[n, k] += lo * (num - nu)
            A[a + 1, k] += nu
        A[k, k] -= 1.0
    S = x.copy()

    def rhs(t, y):
        return A @ (S * y[:n])

    return rhs, 1


# ------------------------------------------------------------------ first-order upwind growth in diameter
def growth_rhs(e, x, x_hi, G=1.0):
    n = len(x)
    d = np.cbrt(6.0 * e / math.pi)
    w = np.diff(d)

    def rhs(t, y):
        F = G * y[:n] / w                                   # flux through the upper face of each cell
        dN = -F
        dN[1:] += F[:-1]
        return np.concatenate((dN, [F[-1], F[-1] * x_hi, np.dot(F[:-1], np.diff(x)) + F[-1] * (x_hi - x[-1])]))

    return rhs, 3


# ------------------------------------------------------------------ analytic references (docs/verification.md)
def gl_cells(f, lo, hi, panels=16):
    xg, wg = np.polynomial.legendre.leggauss(8)
    out = np.zeros(len(lo))
    for p in range(panels):
        a = lo + (hi - lo) * p / panels
        b = lo + (hi - lo) * (p + 1) / panels
        m, h = 0.5 * (a + b), 0.5 * (b - a)
        for xi, wi in zip(xg, wg):
            out += wi * h * f(m + h * xi)
    return out


def golovin(v, t):
    g = 1.0 - math.exp(-t)
    sg = math.sqrt(g)
    z = 2.0 * v * sg
    return (1.0 - g) * np.exp(-(1.0 + g) * v + z) * i1e(z) / (v * sg)


def reference(case, tau, e, x):
    lo, hi = e[:-1], e[1:]
    if case == "constant":
        s = 1.0 + tau / 2
        return 1 / s, 2 + tau, gl_cells(lambda v: v * np.exp(-v / s) / s ** 2, lo, hi)
    if case == "sum":
        return math.exp(-tau), 2 * math.exp(2 * tau), gl_cells(lambda v: v * golovin(v, tau), lo, hi)
    if case == "product":
        return 1 - tau / 2, 2 / (1 - 2 * tau), None
    if case == "breakage":
        return 1 + tau, 2 / (1 + tau), gl_cells(lambda v: v * (1 + tau) ** 2 * np.exp(-v * (1 + tau)), lo, hi)

    # growth: shifted distribution in diameter
    def vol(L):
        return math.pi / 6 * L ** 3

    def dens(L):
        s = np.maximum(L - tau, 0)
        return np.where(L > tau, np.exp(-vol(s)) * 0.5 * math.pi * s ** 2, 0.0)
    Lg = np.linspace(0, 6, 6001)[:-1] + 0.0005
    m0 = np.sum(dens(Lg + tau)) * 0.001
    m2 = np.sum(vol(Lg + tau) ** 2 * dens(Lg + tau)) * 0.001
    d = np.cbrt(6 * e / math.pi)
    return m0, m2, gl_cells(lambda L: vol(L) * dens(L), d[:-1], d[1:])


# ------------------------------------------------------------------ one run
def run(case, method, q, rtol, repeats):
    tau = CASES[case]
    doublings = 19 if case == "growth" else 27
    e, x, x_lo, x_hi = grid(q, doublings)
    n = len(x)
    if case == "growth":
        rhs, extra = growth_rhs(e, x, x_hi)
    elif case == "breakage":
        rhs, extra = breakage_rhs(x, x_lo)
    else:
        rhs, extra = aggregation_rhs(x, x_hi, case)
    y0 = np.concatenate((initial(e, x, x_lo, x_hi), np.zeros(extra)))
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        sol = solve_ivp(rhs, (0.0, tau), y0, method=method, rtol=rtol, atol=1e-3 * rtol, t_eval=[tau])
        times.append((time.perf_counter() - t0) * 1e3)
    y = sol.y[:, -1]
    N = y[:n]
    m0, m2, cells = reference(case, tau, e, x)
    v0 = np.dot(y0[:n], x)
    if case == "growth":
        v1 = np.dot(N, x) + y[n + 1] - y[n + 2]
    elif case == "breakage":
        v1 = np.dot(N, x) + y[n]
    else:
        v1 = np.dot(N, x) + y[n + 1]
    rec = {"case": case, "method": ("scipy_upwind_" if case == "growth" else "scipy_fp_") + method, "q": q,
           "classes": n, "rtol": rtol, "tau": tau, "err_M0": float(np.sum(N) / m0 - 1),
           "err_M2": float(np.dot(N, x * x) / m2 - 1),
           "err_L1": None if cells is None else float(np.sum(np.abs(N * x - cells)) / np.sum(cells)),
           "mass_drift": float(v1 / v0 - 1), "solve_ms": statistics.median(times), "repeats": repeats,
           "steps": None, "rhs_evaluations": int(sol.nfev), "jacobians": int(sol.njev), "lu": int(sol.nlu),
           "success": bool(sol.success)}
    return rec


def meta():
    root = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
    try:
        commit = subprocess.run(["git", "-C", root, "rev-parse", "--short", "HEAD"], capture_output=True, text=True,
                                timeout=10).stdout.strip()
    except Exception:  # noqa: BLE001 - metadata only
        commit = ""
    cpu = ""
    try:
        with open("/proc/cpuinfo") as f:
            cpu = next((l.split(":", 1)[1].strip() for l in f if l.startswith("model name")), "")
    except OSError:
        pass
    import scipy
    return {"code": "scipy", "machine": platform.node(), "cpu": cpu, "cores": os.cpu_count(), "commit": commit,
            "python": sys.version.split()[0], "numpy": np.__version__, "scipy": scipy.__version__,
            "date": time.strftime("%Y-%m-%d %H:%M:%S")}


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--json", action="store_true")
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--case", choices=sorted(CASES))
    args = ap.parse_args()
    qs = [1, 2, 4] if args.quick else [1, 2, 3, 4, 6, 8, 12]
    rtols = [1e-2, 1e-4, 1e-6] if args.quick else [1e-2, 1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8]
    m = meta()
    for case in CASES:
        if args.case and case != args.case:
            continue
        for method in ("BDF", "LSODA"):
            for q in qs:
                for rtol in rtols:
                    rec = run(case, method, q, rtol, args.repeats)
                    rec.update(m)
                    if args.json:
                        print(json.dumps(rec), flush=True)
                    else:
                        print(f"{case:9s} {rec['method']:18s} q={q} n={rec['classes']:3d} rtol={rtol:.0e}  "
                              f"M0 {rec['err_M0']:+.2e}  M2 {rec['err_M2']:+.3e}  "
                              f"L1 {rec['err_L1'] if rec['err_L1'] is not None else float('nan'):.2e}  "
                              f"drift {rec['mass_drift']:+.1e}  {rec['solve_ms']:9.2f} ms  "
                              f"(nfev {rec['rhs_evaluations']}, njev {rec['jacobians']})", flush=True)


if __name__ == "__main__":
    main()
