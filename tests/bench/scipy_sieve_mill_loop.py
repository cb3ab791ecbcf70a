#!/usr/bin/python3
"""The sieve-mill loop of flowsheets/continuous_layering_sieve_mill.yaml written the way a researcher would without
granuflow: one ODE system M' = f(t, M) in NumPy (the dry solids mass per size class of the well-mixed granulator),
integrated by scipy.integrate.solve_ivp (BDF, SciPy's finite-difference Jacobian). Same equations and numbers as the
granuflow units: layering growth on van Albada finite volumes normalized to the sprayed solids (units/
particle_chamber.cpp, kernels/discretization/fv_growth.cpp), a discharge that holds the bed mass (ideal level
controller with a smooth valve and a capacity), a two-deck screen with Plitt curves averaged over each class
(kernels/classification), a mill with a log-normal product cut off at the parent (kernels/comminution), the
undersize and the milled oversize mixed back into the bed. Where granuflow solves the loop's algebraic equations with
the rest (the discharge depends on the recycle it creates), f solves them itself: the recycle is a fixed fraction of
the discharge for a given hold-up, so the discharge is the root of one scalar equation (Newton, to round-off).

    /usr/bin/python3 tests/bench/scipy_sieve_mill_loop.py --classes N [--t-end H] [--mill-d50 UM] [--repeats R] [--json]

(Debian's /usr/bin/python3.) Prints the wall time, the solver statistics and the product's d10/d50/d90 and the bed
mass at the end; `granuflow bench loop` runs it beside granuflow on the same variant. SI units throughout.
"""
from __future__ import annotations

import argparse
import json
import math
import statistics
import time

import numpy as np
from scipy.integrate import solve_ivp
from scipy.special import erfc

# --------------------------------------------------------------------------- the scene's numbers (SI)
D_MIN, D_MAX = 1.0e-4, 4.0e-3           # m, first and last pivot diameter
RHO = 1500.0                            # kg/m^3, envelope density (rho_s (1 - eps_intra))
M_SPRAY, W_SPRAY = 200.0 / 3600.0, 0.3  # kg/s spray liquid, kg/kg solids in it
M0, D50_0, SIGMA_0 = 100.0, 600e-6, 1.4  # initial bed: kg, m, -
M_SET, TAU_C, MDOT_MAX = 100.0, 60.0, 1000.0 / 3600.0  # kg, s, kg/s
EPS = 1e-3 * M_SET / TAU_C              # kg/s, smoothing of the valve
UP_CUT, UP_M, LO_CUT, LO_M = 1.4e-3, 10.0, 1.0e-3, 10.0  # Plitt decks
MILL_D50, MILL_SIGMA = 450e-6, 1.5
MASS_FLOOR = 1e-12                      # kg


class Loop:
    def __init__(self, n: int, mill_d50: float = MILL_D50, m_spray: float = M_SPRAY):
        self.n = n
        d = D_MIN * (D_MAX / D_MIN) ** (np.arange(n) / (n - 1))
        x = math.pi / 6.0 * d ** 3
        e = np.empty(n + 1)
        e[1:n] = np.sqrt(x[:-1] * x[1:])
        e[0], e[n] = x[0] ** 2 / e[1], x[-1] ** 2 / e[n - 1]
        self.x, self.d = x, d
        self.de = (6.0 * e / math.pi) ** (1.0 / 3.0)
        x_lo, x_hi = x[0] ** 2 / x[1], x[-1] ** 2 / x[-2]
        self.x_hi = x_hi
        self.pm = RHO * x                                   # particle mass per class
        width = np.diff(self.de)
        centre = 0.5 * (self.de[:-1] + self.de[1:])
        self.width = width
        self.cplus = np.zeros(n)
        self.cminus = np.zeros(n)
        self.cplus[:-1] = width[:-1] / np.diff(centre)
        self.cminus[1:] = width[1:] / np.diff(centre)
        xe = np.concatenate(([x_lo], x, [x_hi]))
        self.dx_face = np.diff(xe)                          # n + 1: pivot above minus pivot below each face
        self.amount = m_spray * W_SPRAY / RHO               # m^3/s of layer
        self.t_up = self.plitt_cells(UP_CUT, UP_M)
        self.t_lo = self.plitt_cells(LO_CUT, LO_M)
        self.P = self.mill_matrix(mill_d50, MILL_SIGMA)
        # per unit of discharge: the part that returns (undersize + milled oversize; the mill keeps mass)
        self.product_share = self.t_lo * (1.0 - self.t_up)
        cdf = 0.5 * erfc(-np.log(self.de / D50_0) / (math.log(SIGMA_0) * math.sqrt(2.0)))
        cdf[0], cdf[-1] = 0.0, 1.0
        self.M0 = M0 * np.diff(cdf)
        self.nfev = 0

    def plitt_cells(self, cut, m):
        """Plitt curve averaged over ln d in each class: 2 x 2 Gauss points on panels of at most 0.02 in ln d."""
        xg = (0.3399810435848563, 0.8611363115940526)
        wg = (0.6521451548625461, 0.3478548451374538)
        out = np.empty(self.n)
        for i in range(self.n):
            la, lb = math.log(self.de[i]), math.log(self.de[i + 1])
            panels = max(1, math.ceil((lb - la) / 0.02))
            h = (lb - la) / panels
            s = 0.0
            for k in range(panels):
                mid = la + (k + 0.5) * h
                for g in range(2):
                    for sg in (-1.0, 1.0):
                        dd = math.exp(mid + sg * xg[g] * 0.5 * h)
                        s += 0.5 * wg[g] / panels * (1.0 - math.exp(-math.log(2.0) * (dd / cut) ** m))
            out[i] = s
        return out

    def mill_matrix(self, d50, sigma):
        """P[i, k]: mass fraction of feed class k leaving in class i (log-normal product cut off at the parent)."""
        n = self.n
        finer = 0.5 * erfc(-np.log(self.de[1:] / d50) / (math.log(sigma) * math.sqrt(2.0)))
        P = np.zeros((n, n))
        for k in range(n):
            below = 0.0
            for i in range(k):
                P[i, k] = finer[i] - below
                below = finer[i]
            P[k, k] = 1.0 - P[:k, k].sum()
        return P

    def growth(self, M):
        """dM/dt of layering (paper 003, Eqs. (7.32)-(7.34)) on van Albada finite volumes in diameter."""
        N = M / self.pm
        n = self.n
        nd = N / self.width
        phi = np.zeros(n + 1)
        phi[1:] = nd                                        # donor of face f is cell f - 1; nothing enters at 0
        a = (nd[2:] - nd[1:-1]) * self.cplus[1:-1]          # donors 1 .. n - 2 have both neighbours
        b = (nd[1:-1] - nd[:-2]) * self.cminus[1:-1]
        q = a * a + b * b
        slope = np.divide(a * b * (a + b), q, out=np.zeros_like(q), where=q > 0.0)
        phi[2:n] += 0.5 * slope
        integral = phi @ self.dx_face
        F = phi * (self.amount / integral) if integral > 0.0 else np.zeros(n + 1)
        dM = self.pm * (F[:-1] - F[1:])
        dM[-1] += RHO * self.x_hi * F[-1]                   # grown past the top: kept in the top class
        return dM

    @staticmethod
    def softplus(u):
        return 0.5 * (u + math.sqrt(u * u + EPS * EPS))

    def discharge(self, M):
        """Total discharge R: R = min(softplus(u), mdot_max), u = R c + M_sus + (M - M_set)/tau_c, with c the part
        of the discharge that comes back (undersize and milled oversize)."""
        mass = M.sum()
        frac = M / (mass + MASS_FLOOR)
        c = frac @ (1.0 - self.product_share)
        a = self.amount * RHO + (mass - M_SET) / TAU_C

        def g(R):
            u = c * R + a
            open_ = self.softplus(u)
            du = 0.5 * (1.0 + u / math.sqrt(u * u + EPS * EPS))
            v = open_ - MDOT_MAX
            dv = 0.5 * (1.0 + v / math.sqrt(v * v + EPS * EPS))
            return open_ - self.softplus(v), c * du * (1.0 - dv)
        R = max(a / max(1.0 - c, 1e-3), 0.0)
        for _ in range(50):
            gr, dg = g(R)
            step = (R - gr) / (1.0 - dg)
            R -= step
            if abs(step) <= 1e-15 * max(R, 1e-12):
                break
        return R, frac

    def rhs(self, t, M):
        self.nfev += 1
        R, frac = self.discharge(M)
        D = R * frac
        over = self.t_up * D
        prod = self.t_lo * (D - over)
        under = D - over - prod
        return self.growth(M) + under + self.P @ over - D

    def product(self, M):
        R, frac = self.discharge(M)
        D = R * frac
        over = self.t_up * D
        return self.t_lo * (D - over)


def characteristic(de, m, x):
    """Mass-based d_x, linear in ln d inside a class (kernels/discretization/psd.hpp)."""
    q = np.concatenate(([0.0], np.cumsum(np.maximum(m, 0.0))))
    q /= q[-1]
    for i in range(len(m)):
        if q[i + 1] >= x and q[i + 1] > q[i]:
            return de[i] * (de[i + 1] / de[i]) ** ((x - q[i]) / (q[i + 1] - q[i]))
    return de[-1]


def run(n, t_end, rtol, atol, mill_d50):
    loop = Loop(n, mill_d50)
    t0 = time.perf_counter()
    sol = solve_ivp(loop.rhs, (0.0, t_end), loop.M0, method="BDF", rtol=rtol, atol=atol, t_eval=[t_end])
    wall = time.perf_counter() - t0
    if not sol.success:
        raise RuntimeError(sol.message)
    M = sol.y[:, -1]
    prod = loop.product(M)
    return {"wall_s": wall, "nfev": sol.nfev, "njev": sol.njev, "nlu": sol.nlu, "steps": None,
            "d10_um": characteristic(loop.de, prod, 0.1) * 1e6, "d50_um": characteristic(loop.de, prod, 0.5) * 1e6,
            "d90_um": characteristic(loop.de, prod, 0.9) * 1e6, "bed_mass_kg": float(M.sum()),
            "product_kg_s": float(prod.sum())}


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--classes", type=int, default=100)
    p.add_argument("--t-end", type=float, default=300.0, help="end time, h (default 300: to steady state)")
    p.add_argument("--rtol", type=float, default=1e-6)
    p.add_argument("--atol", type=float, default=1e-8, help="kg (granuflow: atol 1e-8 x the 1 kg scale of M)")
    p.add_argument("--mill-d50", type=float, default=MILL_D50 * 1e6, help="um")
    p.add_argument("--repeats", type=int, default=1)
    p.add_argument("--json", action="store_true")
    a = p.parse_args()
    runs = [run(a.classes, a.t_end * 3600.0, a.rtol, a.atol, a.mill_d50 * 1e-6) for _ in range(a.repeats)]
    rec = dict(runs[-1])
    rec.update({"code": "scipy", "method": "solve_ivp BDF, finite-difference Jacobian", "classes": a.classes,
                "t_end_h": a.t_end, "rtol": a.rtol, "atol": a.atol, "mill_d50_um": a.mill_d50,
                "wall_s_median": statistics.median(r["wall_s"] for r in runs), "repeats": a.repeats})
    if a.json:
        print(json.dumps(rec))
    else:
        print(f"{a.classes} classes, {a.t_end:g} h: {rec['wall_s_median']:.3f} s (nfev {rec['nfev']}, njev "
              f"{rec['njev']}, nlu {rec['nlu']}); product d10/d50/d90 {rec['d10_um']:.3f}/{rec['d50_um']:.3f}/"
              f"{rec['d90_um']:.3f} um, bed {rec['bed_mass_kg']:.6f} kg")


if __name__ == "__main__":
    main()
