#!/usr/bin/python3
"""The baseline a researcher would write for the 2-D population balance of paper 002: NumPy over every pair of bins
(solid class x liquid class), integrated with scipy.integrate.solve_ivp (BDF) with an analytic dense Jacobian
(finite differences would need one right-hand side per state per Jacobian: --jacobian fd), on the equations, grid
and tolerances of flowsheets/sen_2d_dem_kernel.yaml at size x size bins (granuflow's pbm_2d: fixed pivot in solid
volume, liquid volume additive on a uniform grid, DEM collision frequencies x the step efficiency of Eq. (13), droplets
of one volume absorbed whole, every particle alike).

    /usr/bin/python3 tests/bench/scipy_pbm2d.py --size 40 [--json] [--jacobian analytic|fd] [--repeats R]

One JSON record per run: size, states, method, jacobian, wall_s (median of R repeats in one process), D_avg, x_avg,
number at t_end, solver counts. The two integration segments (before and after the spray starts) are solved apart,
as granuflow restarts at the breakpoint.
"""
from __future__ import annotations

import argparse
import json
import math
import os
import statistics
import sys
import time

import numpy as np
from scipy.integrate import solve_ivp

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.abspath(os.path.join(HERE, "..", ".."))
CSV = os.path.join(ROOT, "flowsheets", "data", "sen2014_collisions_example.csv")

# The scene's numbers (flowsheets/sen_2d_dem_kernel.yaml).
D0 = 2e-3
S0 = math.pi / 6 * D0 ** 3
N0, Q, T_ON, T_END = 50000.0, 50000 * S0, 0.2, 2.0
PSI0, LC_MIN = 0.01, 0.2
RTOL, ATOL = 1e-5, 1e-4


def read_counts(path):
    rows = {}
    counts = []
    like = None
    for line in open(path):
        line = line.split("#")[0].strip()
        if not line:
            continue
        key, *vals = line.split(",")
        if key == "counts":
            counts.append([float(v) for v in vals])
        elif key == "like_collisions":
            like = vals[0].strip()
        else:
            rows[key] = [float(v) for v in vals]
    F = np.array(rows["particles"])
    N = np.array(counts)
    if like == "once":  # a like collision counted once: twice per pair as Eq. (12) reads it
        N = N + np.diag(np.diag(N))
    C = N / np.outer(F, F) / rows["dt_s"][0]
    return np.array(rows["edges_m"]), C


def model(size):
    q = size // 5
    v_min = 2 * S0 / (1 + 2 ** (1 / q))
    e = v_min * np.exp2(np.arange(size + 1) / q)
    s = 0.5 * (e[:-1] + e[1:])
    x_hi = s[-1] ** 2 / s[-2]
    nl = size
    dl = 20 * S0 / nl
    l = dl * np.arange(nl)
    ns = size
    n = ns * nl
    # bins a = i * nl + j
    si = np.repeat(s, nl)
    lj = np.tile(l, ns)
    lc = lj / (si + lj)
    wet = lc >= LC_MIN - 1e-9  # as granuflow: pivots exactly on the threshold (4 primaries, 1 droplet) are wet
    edges, C = read_counts(CSV)
    cls = np.searchsorted(edges, np.cbrt(6 * s / math.pi), side="right") - 1
    K = PSI0 * C[np.ix_(cls, cls)]
    A, B = np.triu_indices(n)
    I, J = A // nl, A % nl
    Kk, M = B // nl, B % nl
    c = K[I, Kk] * (wet[A] | wet[B]) * np.where(A == B, 0.5, 1.0)   # Eq. (13), either partner wet
    keep = c > 0
    A, B, I, J, Kk, M, c = A[keep], B[keep], I[keep], J[keep], Kk[keep], M[keep], c[keep]
    v = s[I] + s[Kk]
    L = J + M
    a = np.searchsorted(s, v, side="right") - 1
    lo = np.clip(a, 0, ns - 1)
    inside = v < s[-1]
    top = (v >= s[-1]) & (v < x_hi)
    xb = np.where(inside, s[np.clip(a + 1, 0, ns - 1)], x_hi)
    nu = np.where(inside | top, (v - s[lo]) / (xb - s[lo]), 0.0)
    on_grid = L < nl
    OUT = n  # index of "left the grid"
    TL = np.where((inside | top) & on_grid, lo * nl + L, OUT)
    TH = np.where(inside & on_grid, (lo + 1) * nl + L, OUT)
    WL = np.where(inside | top, 1 - nu, 0.0)
    WH = np.where(inside | top, nu, 1.0)
    # droplets: every particle alike, one droplet moves a particle by v_d / dl liquid classes (split if not whole)
    kappa = S0 / dl
    k0 = int(math.floor(kappa))
    f = kappa - k0
    jj = np.arange(n) % nl
    D_lo = np.where(jj + k0 < nl, np.arange(n) + k0, OUT)
    D_hi = np.where(jj + k0 + 1 < nl, np.arange(n) + k0 + 1, OUT)
    R = Q / S0
    nn = n + 1

    def rhs(t, N, spray):
        r = c * N[A] * N[B]
        d = -np.bincount(A, r, nn) - np.bincount(B, r, nn)
        d += np.bincount(TL, r * WL, nn) + np.bincount(TH, r * WH, nn)
        if spray:
            rho = R / N.sum() * N
            d[:n] -= rho
            d += np.bincount(D_lo, rho * (1 - f), nn) + np.bincount(D_hi, rho * f, nn)
        return d[:n]

    def jac(t, N, spray):
        # rate c N_A N_B: d/dN_A = c N_B, d/dN_B = c N_A, on rows A, B (-), TL (+WL), TH (+WH)
        dA, dB = c * N[B], c * N[A]
        idx, val = [], []
        for rows, w in ((A, -1.0), (B, -1.0), (TL, WL), (TH, WH)):
            for cols, dv in ((A, dA), (B, dB)):
                idx.append(rows * nn + cols)
                val.append(w * dv)
        Jm = np.bincount(np.concatenate(idx), np.concatenate(val), nn * nn).reshape(nn, nn)[:n, :n]
        if spray:
            W = N.sum()
            Dm = np.zeros((nn, n))
            ar = np.arange(n)
            Dm[ar, ar] -= 1
            np.add.at(Dm, (D_lo, ar), 1 - f)
            np.add.at(Dm, (D_hi, ar), f)
            Dm = Dm[:n]
            Jm = Jm + Dm * (R / W) - np.outer(Dm @ (R * N / W ** 2), np.ones(n))
        return Jm

    y0 = np.zeros(n)
    a0 = 0  # the primary particle is pivot 0
    y0[a0 * nl] = N0
    return dict(rhs=rhs, jac=jac, y0=y0, si=si, lj=lj, n=n, pairs=len(c))


def solve(m, jacobian):
    y = m["y0"]
    stats = {"nfev": 0, "njev": 0, "nlu": 0, "steps": 0}
    for (t0, t1), spray in (((0.0, T_ON), False), ((T_ON, T_END), True)):
        kw = {"jac": (lambda t, N, s=spray: m["jac"](t, N, s))} if jacobian == "analytic" else {}
        sol = solve_ivp(lambda t, N, s=spray: m["rhs"](t, N, s), (t0, t1), y, method="BDF", rtol=RTOL, atol=ATOL,
                        t_eval=[t1], **kw)
        if not sol.success:
            raise RuntimeError(sol.message)
        y = sol.y[:, -1]
        stats["nfev"] += sol.nfev
        stats["njev"] += sol.njev
        stats["nlu"] += sol.nlu
    return y, stats


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--size", type=int, default=20)
    ap.add_argument("--jacobian", choices=["analytic", "fd"], default="analytic")
    ap.add_argument("--repeats", type=int, default=1)
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args()
    t0 = time.perf_counter()
    m = model(args.size)
    setup_s = time.perf_counter() - t0
    walls = []
    for _ in range(args.repeats):
        t0 = time.perf_counter()
        y, st = solve(m, args.jacobian)
        walls.append(time.perf_counter() - t0)
    num = y.sum()
    D = np.cbrt(6 * (m["si"] + m["lj"]) / math.pi)
    rec = {"code": "scipy", "size": args.size, "states": m["n"], "pairs": m["pairs"], "method": "BDF",
           "jacobian": args.jacobian, "wall_s": statistics.median(walls), "setup_s": setup_s, "repeats": args.repeats,
           "D_avg": float(np.dot(y, D) / num), "x_avg": float(np.dot(y, m["lj"] / (m["si"] + m["lj"])) / num),
           "number": float(num), "rhs_evaluations": st["nfev"], "jacobians": st["njev"], "lu": st["nlu"]}
    print(json.dumps(rec) if args.json else rec)
    return 0


if __name__ == "__main__":
    sys.exit(main())
