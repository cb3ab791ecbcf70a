"""A NumPy/SciPy model of the two-zone batch layering of paper 003 (section 7.5.3, Table 7.7; Eqs. (7.32)-(7.39)),
written independently of granuflow as a researcher would, for `granuflow bench targets` (issue 32): the baseline of
the two-zone target at equal accuracy in sigma.

Number densities over diameter in the spray zone (s) and the drying zone (d):
    dn_s/dt + d(G n_s)/dx = -n_s / tau_s + n_d / tau_d,    dn_d/dt = n_s / tau_s - n_d / tau_d,
with the layering growth rate of the spray zone G = 2 mdot_solids / (rho A_s) (the sprayed solids spread over the
particles' surface A_s = pi sum x^2 n_s; Eq. (7.33)), tau_s = 4 s, tau_d = tau_s (1 - 0.02) / 0.02 = 196 s
(Eq. (7.39)). Finite volumes on cells uniform in diameter over the scene's grid range (1.2 to 3.2 mm), Koren's limiter
on the upwind-biased face values, what grows past the top face leaves the domain (the distribution stays far below
it: a few parts in 1e5 of the number at 90 min). Integrated with solve_ivp BDF (finite-difference Jacobian). The
initial distribution is log-normal in mass (d50 1.8 mm, sigma_g 1.1) in both zones (0.08 kg and 3.92 kg). Prints one
JSON record: classes, wall_s, sigma_um (number-based standard deviation of the drying zone's diameter at 90 min).

Usage: python3 scipy_two_zone.py --classes N [--rtol 1e-7]
"""
import argparse
import json
import math
import time

import numpy as np
from scipy.integrate import solve_ivp
from scipy.special import erf

RHO = 1040.0                      # kg/m3, envelope density of particles and layers (the scene's assumption)
MDOT_SOLIDS = 0.112 / 60 * 0.3    # kg/s: 112 g/min of a 30 wt% solution (Table 7.7, at the scene's 1.12 kg/L)
TAU_S = 4.0                       # s, mean residence time in the spray zone (Table 7.7)
TAU_D = TAU_S * (1 - 0.02) / 0.02  # s, Eq. (7.39)
M_S, M_D = 0.08, 3.92             # kg, initial hold-ups
D50, SIGMA_G = 1.8e-3, 1.1        # log-normal in mass
X_LO, X_HI = 1.2e-3, 3.2e-3       # m, the grid's range
T_END = 90 * 60.0


def initial(edges: np.ndarray, mass: float) -> np.ndarray:
    """Particle numbers per cell: the mass in each cell of the log-normal (in mass) divided by the particle mass at
    the cell's centre."""
    cdf = 0.5 * (1 + erf(np.log(edges / D50) / (math.sqrt(2) * math.log(SIGMA_G))))
    x = 0.5 * (edges[1:] + edges[:-1])
    return mass * np.diff(cdf) / (cdf[-1] - cdf[0]) / (RHO * math.pi / 6 * x ** 3)


def koren(r: np.ndarray) -> np.ndarray:
    return np.maximum(0.0, np.minimum(np.minimum(2 * r, (1 + 2 * r) / 3), 2.0))


def rhs_factory(x: np.ndarray, dx: float, n: int):
    def rhs(_t, y):
        ns, nd = y[:n], y[n:]
        area = math.pi * np.dot(x * x, ns)
        g = 2 * MDOT_SOLIDS / (RHO * area)              # m/s, Eq. (7.33)
        c = ns / dx                                     # number density per m of diameter
        face = np.zeros(n + 1)                          # face values, upwind for G > 0; nothing enters at the bottom
        face[1] = c[0]                                  # first interior face: first-order upwind
        diff = np.diff(c)                               # c[i+1] - c[i]
        num, den = diff[1:], diff[:-1]                  # r_i = (c[i+1] - c[i]) / (c[i] - c[i-1]) at face i+1/2
        r = np.divide(num, den, out=np.zeros_like(num), where=np.abs(den) > 1e-300)
        face[2:n] = c[1:n - 1] + 0.5 * koren(r) * den
        face[n] = c[n - 1]                              # top face: upwind, out of the domain
        flux = g * face                                 # number per s through each face
        ds = -(flux[1:] - flux[:-1]) - ns / TAU_S + nd / TAU_D
        dd = ns / TAU_S - nd / TAU_D
        return np.concatenate([ds, dd])
    return rhs


def run(classes: int, rtol: float) -> dict:
    edges = np.linspace(X_LO, X_HI, classes + 1)
    x = 0.5 * (edges[1:] + edges[:-1])
    dx = edges[1] - edges[0]
    y0 = np.concatenate([initial(edges, M_S), initial(edges, M_D)])
    scale = y0.max()
    t0 = time.perf_counter()
    sol = solve_ivp(rhs_factory(x, dx, classes), (0.0, T_END), y0, method="BDF", rtol=rtol, atol=rtol * 1e-3 * scale)
    wall = time.perf_counter() - t0
    if not sol.success:
        raise SystemExit(f"scipy_two_zone: solve_ivp failed at {classes} classes: {sol.message}")
    nd = sol.y[classes:, -1]
    mean = np.dot(nd, x) / nd.sum()
    sigma = math.sqrt(max(np.dot(nd, x * x) / nd.sum() - mean * mean, 0.0))
    return {"code": "scipy", "method": "BDF, Koren", "classes": classes, "rtol": rtol, "wall_s": wall,
            "sigma_um": sigma * 1e6, "steps": int(sol.t.size), "rhs_evaluations": int(sol.nfev)}


if __name__ == "__main__":
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--classes", type=int, required=True)
    p.add_argument("--rtol", type=float, default=1e-7)
    a = p.parse_args()
    print(json.dumps(run(a.classes, a.rtol)))
