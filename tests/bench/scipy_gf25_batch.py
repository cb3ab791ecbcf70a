#!/usr/bin/python3
"""The headline scene flowsheets/stoeckl_gf25_batch.yaml written the way a researcher would without granuflow:
batch agglomeration of maltodextrin in the Glatt GF25 fluid bed (paper 001, Stoeckl, Bellinghausen, Heinrich),
one ODE system y' = f(t, y) in NumPy integrated by scipy.integrate.solve_ivp (BDF, SciPy's finite-difference
Jacobian, rtol 1e-6, atol 1e-6 x the state scales granuflow declares). Same equations and defaults as the
granuflow units (units/*.cpp, kernels/*, docs/paper001_decisions.md); everything granuflow holds as an algebraic
state (bed temperature, u0, spray zone, droplet evaporation, gas T and Y, heat and vapour flows) is computed
explicitly inside f. The speed and cross-check reference of `granuflow bench scene`.

    /usr/bin/python3 tests/bench/scipy_gf25_batch.py --classes N [--no-breakage] [--repeats R] [--json]

(Debian's /usr/bin/python3: the `python3` first on PATH may not see numpy/scipy.) States: M_i, W_i (solid and
water mass per class, kg), H_bed (J), gas water W_g (kg) and gas enthalpy H_g (J). SI units throughout.
"""
from __future__ import annotations

import argparse
import json
import math
import statistics
import time

import numpy as np
from scipy.integrate import quad, solve_ivp
from scipy.special import erfc

# ------------------------------------------------------------------ constants (framework/.../properties.hpp)
T0 = 273.15                # K, enthalpy reference
R_GAS = 8.314462618        # J/(mol K)
G = 9.80665                # m/s^2
P_ATM = 101325.0           # Pa
M_W, M_A = 0.01801528, 0.0289647  # kg/mol, water and dry air
CP_AIR, CP_VAP, CP_WAT = 1006.0, 1870.0, 4180.0  # J/(kg K)
DH0 = 2.501e6              # J/kg, latent heat at T0
ANT_A, ANT_B, ANT_C = 16.262, 3800.0, 226.3     # Eq. (69), p in kPa, T in degC (Table 8)
MU_REF, T_REF, S_SUTH = 1.716e-5, 273.15, 110.4  # Sutherland, air

# ------------------------------------------------------------------ scene and paper defaults (paper001_defaults.hpp)
V_DOT = 700.0 / 3600.0     # m^3/s at inlet T and p (flow_basis: inlet)
T_IN, Y_IN = 333.15, 0.005  # K, kg/kg dry air
SPRAY_RATE, T_SPRAY = 90e-3 / 60.0, 283.15  # kg/s, K
T_ON, T_OFF, T_END = 0.0, 3600.0, 3600.0    # s
BED_MASS, X0, D50_0, SIGMA_0 = 15.0, 0.030928, 200e-6, 1.5
D_MIN, D_MAX = 50e-6, 1000e-6  # m, first and last pivot
RHO_S, EPS_INTRA, CP_S, CP_L = 1545.0, 0.3, 1220.0, 4180.0
RHO_ENV = RHO_S * (1.0 - EPS_INTRA)  # kg/m^3, size <-> mass
A_BED = 0.25               # m^2
M_GAS = 1.53               # kg dry air hold-up
K_WALL, A_WALL, T_ENV = 13.8, 7.3, 293.15
K_EVAP, D_DROP, RHO_L, EVAP_MULT = 3e-3, 30e-6, 1000.0, 1.0  # Eq. (66)
TAU_C1, TAU_C2 = -3e-3, 0.23                 # Eq. (29)
WS_C1, WS_C2, WS_C3, WS_FLOOR = -3e-4, 5.5e-3, 0.13, 0.05  # Eq. (47) and its floor
V_C1, V_C2, D_ZONE = 1.0e-2, 6.6e-2, 0.3     # Eqs. (48), (49)
RHO_P, RHO_DROP, H_PEN = 900.0, 1000.0, 168e-6  # Eqs. (33), (42), (57)
LN_BETA0, TAU_SPRAY = -17.24, 0.22          # Eq. (37)
STICKY_OFFSET, STICKY_SLOPE = 20.0, 8.733   # Eq. (53)
GT_K, TG_L, TG_S = 6.4, 138.15, 440.15      # Eq. (54)
K_BREAK, D_MIN_BREAK, F_MAT, E_MIN = 1.3e-3, 50e-6, 1.0, 0.3  # Eq. (92), d in um
Q_FRAG, D_FRAG_MIN = 0.5, 50e-6              # Eq. (93)
X_CR, SH_CORR, BET_MM, BET_N = 0.07, 1.0, 0.037, 11.9  # Eqs. (74), (80), (81)
D_V, LAMBDA_G = 2.0e-5, 2.4e-2               # m^2/s, W/(m K)
ETA_DEN_FLOOR, ETA_MIN = 0.01, -1.0          # Eq. (80) regularization
MASS_FLOOR = 1e-12                           # kg, X = W / (M + floor)
# tolerance scales granuflow declares (fluid_bed.cpp, chamber_gas.cpp)
SCALE_M, SCALE_W, SCALE_H, SCALE_GW, SCALE_GH = 10.0, 0.5, 1e6, 0.01, 1e5


# ================================================================== properties (properties.hpp)
def p_sat(t):  # Eq. (69): Antoine, Pa
    return 1000.0 * np.exp(ANT_A - ANT_B / (ANT_C + (t - T0)))


def humidity_from_pp(pv, p):  # Eq. (68) form: kg/kg dry air
    return (M_W / M_A) * pv / (p - pv)


def sat_humidity(t, p):  # Eq. (68) with p_sat capped at 0.9 p
    return humidity_from_pp(np.minimum(p_sat(t), 0.9 * p), p)


def vapour_pp(y, p):  # Eq. (83): Dalton, y = mole fraction
    return y / (y + M_W / M_A) * p


def h_humid_air(t, y):  # Eq. (63): J/kg dry air, from 0 degC
    return CP_AIR * (t - T0) + y * (CP_VAP * (t - T0) + DH0)


def t_humid_air(h, y):  # Eq. (63) inverted: K
    return T0 + (h - y * DH0) / (CP_AIR + y * CP_VAP)


def h_vapour(t):  # vapour enthalpy, J/kg
    return CP_VAP * (t - T0) + DH0


def h_liquid(t):  # liquid water enthalpy, J/kg
    return CP_WAT * (t - T0)


def rho_dry_air(t, p):  # ideal gas, kg/m^3
    return p * M_A / (R_GAS * t)


def rho_dry_partial(t, p, y):  # dry-air partial density, kg/m^3
    return rho_dry_air(t, p - vapour_pp(y, p))


def mu_air(t):  # Sutherland, Pa s
    return MU_REF * (t / T_REF) ** 1.5 * (T_REF + S_SUTH) / (t + S_SUTH)


def bulk_number(single, re, sc_pr, ratio):  # Eqs. (74), (87): Re X / a ln(1 + single a / (Re X))
    pe = re * sc_pr
    return pe / ratio * np.log1p(single * ratio / pe)


# ================================================================== grid and constant arrays (configure)
class Model:
    """Size grid, pair and breakage matrices (fluid_bed.cpp configure()) and the right-hand side."""

    def __init__(self, classes: int = 10, breakage: bool = True):
        n = self.n = classes
        # log-spaced pivots (size_grid_settings.hpp), volume edges at geometric means (grid.cpp from_pivots)
        d = D_MIN * (D_MAX / D_MIN) ** (np.arange(n) / (n - 1))
        x = math.pi / 6.0 * d ** 3
        e = np.empty(n + 1)
        e[1:n] = np.sqrt(x[:-1] * x[1:])
        e[0], e[n] = x[0] ** 2 / e[1], x[-1] ** 2 / e[n - 1]
        self.d, self.x = np.cbrt(6.0 * x / math.pi), x
        self.de = np.cbrt(6.0 * e / math.pi)
        d = self.d
        self.mp = RHO_ENV * x                               # particle mass, kg
        self.surf = math.pi * d ** 2                        # Eq. (51), m^2
        self.surf_per_mass = self.surf / self.mp
        self._pairs()
        self._breakage(breakage)
        # spray zone: Eq. (42) coating number per unit X_LS, and Eq. (57) h A / V
        self.kappa = d ** 3 * RHO_P * (0.25 * math.pi * D_DROP ** 2) / (D_DROP ** 3 * RHO_DROP * self.surf)
        self.hav = H_PEN * self.surf / (math.pi / 6.0 * d ** 3)
        # initial log-normal mass distribution over the cells, tails folded into the end classes
        cdf = 0.5 * erfc(-np.log(self.de / D50_0) / (math.log(SIGMA_0) * math.sqrt(2.0)))
        cdf[0], cdf[n] = 0.0, 1.0
        self.init_frac = np.diff(cdf)
        self.atol_scale = np.concatenate([np.full(n, SCALE_M), np.full(n, SCALE_W), [SCALE_H, SCALE_GW, SCALE_GH]])
        self.calls = 0  # every evaluation of f, the finite-difference Jacobian columns included

    def _pairs(self):
        """Mass-based fixed pivot (Eqs. (21)-(24)): pair (j <= k) lands on pivots a, a + 1 keeping number and mass;
        at or beyond the top pivot it stays in the top class with its mass. The pair sums become constant
        matrices so that dM = Bm @ events and dW = Cj @ (events X_j) + Ck @ (events X_k)."""
        n, x, d = self.n, self.x, self.d
        j, k = np.triu_indices(n)
        v = x[j] + x[k]
        a = np.clip(np.searchsorted(x, v, side="right") - 1, 0, n - 1)   # x_a <= v < x_{a+1}
        top = v >= x[-1]
        a[top] = n - 1
        a1 = np.minimum(a + 1, n - 1)
        span = np.where(top, 1.0, x[a1] - x[a])
        up = np.where(top, 0.0, (v - x[a]) / span * x[a1] / v)           # mass fraction onto pivot a + 1
        P = len(j)
        q = np.arange(P)
        mpj, mpk = self.mp[j], self.mp[k]
        Cj, Ck = np.zeros((n, P)), np.zeros((n, P))
        for C, cls, m in ((Cj, j, mpj), (Ck, k, mpk)):
            np.add.at(C, (cls, q), -m)
            np.add.at(C, (a, q), (1.0 - up) * m)
            np.add.at(C, (a1, q), up * m)
        self.Cj, self.Ck, self.Bm = Cj, Ck, Cj + Ck
        self.pj, self.pk = j, k
        # Eq. (37): EKE collision frequency per pair, x 1/2 for like pairs (Eq. (21))
        s = d[j] + d[k]
        cf = math.exp(LN_BETA0) * s * s * np.sqrt(1.0 / d[j] ** 3 + 1.0 / d[k] ** 3) * TAU_SPRAY
        self.cf = np.where(j == k, 0.5, 1.0) * cf

    def _breakage(self, on: bool):
        """Eq. (92) selection rate per class (d in um) and Eq. (93) fragments split between neighbouring pivots
        keeping their number and volume (fixed pivot, granuflow's default breakage_scheme); what falls below the
        grid stays in class 0 with its mass. Fragments keep the parent's moisture."""
        n, d, x = self.n, self.d, self.x
        self.Kb = None
        if not on:
            return
        d_fit = d * 1e6
        e_kin = d_fit * E_MIN / (D_MIN_BREAK * 1e6)                    # Eq. (91)
        xx = F_MAT * d_fit * (e_kin - E_MIN)
        shape = np.where(xx > 0, -np.expm1(-np.maximum(xx, 0.0)), 0.0)  # Eq. (90), per unit k_break

        def cut(z):  # tanh cut-off of Eq. (93)
            return 0.5 * (1.0 + np.tanh((z - D_FRAG_MIN) / D_FRAG_MIN))

        x_lo = x[0] ** 2 / x[1]                                         # virtual pivot below the grid
        xe = np.concatenate(([x_lo], x))                                 # pivots, x_lo first
        frag = np.zeros((n, n))
        for kk in range(n):
            u = x[kk]

            def B(v, dk=d[kk]):  # Eq. (93): cumulative volume fraction of fragments below volume v
                dv = np.cbrt(6.0 * v / math.pi)
                return (dv / dk) ** Q_FRAG * cut(dv) / cut(dk)

            mass = np.zeros(n)
            mass[0] += u * B(x_lo)                                        # below the grid: kept in class 0
            for a in range(kk + 1):                                       # interval [xe[a], xe[a + 1]]
                lo, hi = xe[a], xe[a + 1]
                vol = u * (B(hi) - B(lo))
                # number of fragments in [lo, hi]: u int (1/v) dB = u [B/v] + u int B / v^2 dv (by parts)
                num = u * (B(hi) / hi - B(lo) / lo + quad(lambda v: B(v) / v ** 2, lo, hi, limit=200)[0])
                nu = (vol - lo * num) / (hi - lo)                         # to the upper pivot, number and volume kept
                mass[a] += hi * nu                                        # pivot a + 1 of xe is class a
                if a > 0:
                    mass[a - 1] += lo * (num - nu)
                else:
                    mass[0] += lo * (num - nu)                            # at x_lo: kept in class 0 with its mass
            frag[:, kk] = mass / u
            frag[kk, kk] -= 1.0                                           # the parent leaves class k
        self.Kb = K_BREAK * frag * shape[None, :]

    # -------------------------------------------------------------- units
    @staticmethod
    def gas_inlet():  # paper 001 Table 1: dry-air mass flow from V_dot at inlet T, p; returns (mdot, T, Y, p)
        return V_DOT * rho_dry_partial(T_IN, P_ATM, Y_IN), T_IN, Y_IN, P_ATM

    @staticmethod
    def spray_nozzle(on: bool):  # spray source, kg/s and K, switched at segment starts
        return (SPRAY_RATE if on else 0.0), T_SPRAY

    @staticmethod
    def droplet_evaporation(m_l, t_g, y_g, p):  # Eq. (66): A = 6 m_L / (rho_L d_d), Y_eq at T_gas, clipped
        a = 6.0 * m_l / (RHO_L * D_DROP)
        m = EVAP_MULT * K_EVAP * a * (sat_humidity(t_g, p) - y_g)
        m = min(max(m, 0.0), m_l)
        return m, m_l - m                       # evaporated, deposited (both at the spray temperature)

    def spray_zone(self, M, W, t_bed, u0, m_liq):
        """Eqs. (29)-(33), (41)-(57): liquid split (class_surface), wetted fraction and wet-spot moisture."""
        d = self.d
        rho = rho_dry_air(t_bed, P_ATM)                                  # dry air at the bed temperature
        mu = mu_air(t_bed)
        nu = mu / rho
        ar = rho * d ** 3 * (RHO_P - rho) * G / mu ** 2                  # Eq. (33)
        re_mf = 2.0 * ar / (1650.0 + np.sqrt(1650.0 ** 2 + 98.0 * ar))  # Eq. (32), Wen-Yu
        umf = re_mf * nu / d                                             # Eq. (31)
        re = (u0 - umf) * d / nu                                         # Eq. (30)
        tau = TAU_C1 * re + TAU_C2                                       # Eq. (29)
        ws = np.maximum((WS_C1 * re + WS_C2) * re + WS_C3, WS_FLOOR)     # Eq. (47), floored
        t_cross = D_ZONE / (V_C1 * re + V_C2)                            # Eqs. (48), (49)
        w_part = tau * d * d
        total = np.sum(w_part * M / self.mp)                             # Eq. (44): N_i tau_i d_i^2
        m_dep = w_part * M / self.mp * m_liq / total
        x_ls = m_liq * w_part / total * t_cross / (ws * self.mp)         # Eqs. (43), (45), (46)
        phi = self.kappa * x_ls                                          # Eq. (42)
        fwet = -np.expm1(-phi)                                           # Eq. (41)
        frac = self.hav * fwet                                           # Eq. (57), V_wet / V_p
        with np.errstate(divide="ignore", invalid="ignore"):
            g = np.where(phi < 1e-8, 1.0 + 0.5 * phi, phi / fwet)
        dx = np.where(frac > 1.0, x_ls, g / (self.kappa * self.hav))     # Eqs. (55)-(56), cap at 1
        xwet = dx + W / (M + MASS_FLOOR)                                 # Eq. (55)
        return m_dep, fwet, xwet

    def aggregation(self, M, X, fwet, xwet, t_s):
        """Eqs. (21)-(24), (36)-(40), (52)-(54): glass-transition kernel on the mass-based fixed pivot."""
        xl = xwet / (1.0 + xwet)
        tg = (GT_K * xl * TG_L + (1.0 - xl) * TG_S) / (GT_K * xl + (1.0 - xl))  # Eq. (54)
        sticky = 0.5 * (np.tanh((t_s - (STICKY_OFFSET + tg)) / STICKY_SLOPE) + 1.0)  # Eq. (53)
        number = M / self.mp
        j, k = self.pj, self.pk
        psi_geom = 1.0 - (1.0 - fwet[j]) * (1.0 - fwet[k])              # Eq. (40)
        psi_phys = 1.0 - (1.0 - sticky[j]) * (1.0 - sticky[k])          # Eq. (52)
        events = self.cf * psi_geom * psi_phys * number[j] * number[k]   # Eq. (39) x N_j N_k, 1/s
        dM = self.Bm @ events
        dW = self.Cj @ (events * X[j]) + self.Ck @ (events * X[k])
        return dM, dW

    def bed_transfer(self, M, W, t_s, t_g, y_g, p, u0):
        """Eqs. (70)-(83) drying and (85)-(89) gas-solid heat flow per class; returns (kg/s per class, W)."""
        d = self.d
        rho_da = rho_dry_partial(t_g, p, y_g)                            # Y is per kg dry air, Eq. (72)
        rho = (1.0 + y_g) * rho_da                                       # humid air
        mu = mu_air(t_g)
        nu = mu / rho
        sc = mu / (rho * D_V)                                            # Eq. (78)
        pr = (CP_AIR + y_g * CP_VAP) * mu / LAMBDA_G                     # Eq. (89)
        a = min(vapour_pp(y_g, p) / p_sat(t_s), 0.99)                    # Eqs. (82), (83), capped
        x_eq = BET_MM * BET_N * a / ((1.0 - a) * (1.0 + (BET_N - 1.0) * a))  # Eq. (81)
        y_sat = sat_humidity(t_s, p)                                     # Eq. (68) at T_S
        ratio = np.dot(M, self.surf_per_mass) / A_BED                    # A_p / A_inlet, Eqs. (74), (87)
        area = M / self.mp * self.surf                                   # Eq. (70): N_i pi d_i^2
        re0 = u0 * d / nu                                                # Eq. (76)
        sq = 0.6 * np.sqrt(re0)
        shb = SH_CORR * bulk_number(2.0 + sq * np.cbrt(sc), re0, sc, ratio)  # Eqs. (74), (75)
        flux = rho_da * (shb * D_V / d) * (y_sat - y_g)                  # Eqs. (72), (73)
        den = max(X_CR - x_eq, ETA_DEN_FLOOR)
        eta = np.maximum((W / (M + MASS_FLOOR) - x_eq) / den, ETA_MIN)   # Eq. (80), regularized
        dry = np.minimum(eta, 1.0) * area * flux                         # Eqs. (70), (79)
        nub = bulk_number(2.0 + sq * np.cbrt(pr), re0, pr, ratio)        # Eqs. (87), (88)
        q = np.sum(nub * LAMBDA_G / d * area) * (t_g - t_s)              # Eqs. (85), (86)
        return dry, q

    @staticmethod
    def wall_heat_loss(t_g):  # Eq. (84): W
        return K_WALL * A_WALL * (t_g - T_ENV)

    @staticmethod
    def chamber_gas(wg, hg):  # Eq. (63): Y and T of the chamber gas from its water and enthalpy
        y = wg / M_GAS
        return y, t_humid_air(hg / M_GAS, y)

    @staticmethod
    def gas_outlet(m_in, y, t):  # exhaust: the chamber gas leaves at its state (accumulators only in granuflow)
        return m_in, y, t

    # -------------------------------------------------------------- right-hand side
    def rhs(self, t, y, spray_on):
        self.calls += 1
        n = self.n
        M, W, h_bed, wg, hg = y[:n], y[n:2 * n], y[2 * n], y[2 * n + 1], y[2 * n + 2]
        m_in, t_in, y_in, p = self.gas_inlet()
        y_g, t_g = self.chamber_gas(wg, hg)
        # bed temperature from its enthalpy, Eq. (60); u0 from the inlet flow, Eq. (77)
        t_s = T0 + h_bed / (CP_S * M.sum() + CP_L * W.sum())
        u0 = m_in / rho_dry_partial(t_in, p, y_in) / A_BED
        m_l, t_l = self.spray_nozzle(spray_on)
        m_ev, m_liq = self.droplet_evaporation(m_l, t_g, y_g, p)
        X = W / (M + MASS_FLOOR)
        if m_liq > 0.0:
            m_dep, fwet, xwet = self.spray_zone(M, W, t_s, u0, m_liq)
            dM, dW = self.aggregation(M, X, fwet, xwet, t_s)
        else:  # no deposited liquid: nothing wetted, psi_geom = 0
            m_dep, dM, dW = np.zeros(n), np.zeros(n), np.zeros(n)
        if self.Kb is not None:  # Eqs. (90)-(93): linear in M and W
            dM = dM + self.Kb @ M
            dW = dW + self.Kb @ W
        dry, q_s = self.bed_transfer(M, W, t_s, t_g, y_g, p, u0)
        m_vap = dry.sum()
        dW = dW + m_dep - dry                                                        # Eq. (58)
        dh_bed = m_dep.sum() * CP_L * (t_l - T0) - m_vap * h_vapour(t_s) + q_s      # Eq. (59)
        m_out, y_out, t_out = self.gas_outlet(m_in, y_g, t_g)
        dwg = m_in * y_in - m_out * y_out + m_ev + m_vap                             # Eq. (61)
        dhg = (m_in * h_humid_air(t_in, y_in) - m_out * h_humid_air(t_out, y_out) + m_ev * h_liquid(t_l)
               + m_vap * h_vapour(t_s) - self.wall_heat_loss(t_g) - q_s)            # Eq. (62)
        return np.concatenate([dM, dW, [dh_bed, dwg, dhg]])

    def initial_state(self):  # bed and gas at the inlet state (scene links)
        dry = BED_MASS / (1.0 + X0)
        M = dry * self.init_frac
        W = M * X0
        h_bed = (CP_S * M.sum() + CP_L * W.sum()) * (T_IN - T0)
        return np.concatenate([M, W, [h_bed, M_GAS * Y_IN, M_GAS * h_humid_air(T_IN, Y_IN)]])

    # -------------------------------------------------------------- outputs
    def quantile(self, mass, q):  # FluidBed::quantile: Q3 at the edges, linear in ln d inside a cell
        c = np.cumsum(mass) / mass.sum()
        below = np.concatenate(([0.0], c[:-1]))
        for i in range(self.n):
            if c[i] >= q and mass[i] > 0:
                f = (q - below[i]) / (c[i] - below[i])
                return math.exp(math.log(self.de[i]) + f * (math.log(self.de[i + 1]) - math.log(self.de[i])))
        return self.de[-1]

    def summary(self, yend):
        n = self.n
        M, W = yend[:n], yend[n:2 * n]
        _, t_g = self.chamber_gas(yend[2 * n + 1], yend[2 * n + 2])
        return {"d10_um": self.quantile(M, 0.1) * 1e6, "d50_um": self.quantile(M, 0.5) * 1e6,
                "d90_um": self.quantile(M, 0.9) * 1e6, "bed_moisture": W.sum() / M.sum(), "T_gas_out_K": t_g,
                "T_bed_K": T0 + yend[2 * n] / (CP_S * M.sum() + CP_L * W.sum())}


# ================================================================== integration
def segments():
    """Integration segments between the nozzle's switching times; the spray state is fixed per segment
    (decided at its start, as granuflow's breakpoints)."""
    cuts = sorted({0.0, T_END} | {t for t in (T_ON, T_OFF) if 0.0 < t < T_END})
    return [(a, b, T_ON <= a < T_OFF) for a, b in zip(cuts[:-1], cuts[1:])]


def solve(model: Model, t_eval=None):
    """solve_ivp(BDF) over the segments; returns (t, y, stats, status)."""
    y0 = model.initial_state()
    atol = 1e-6 * model.atol_scale
    ts, ys, stats, status = [], [], {"nfev": 0, "njev": 0, "nlu": 0, "steps": 0}, 0
    model.calls = 0
    for a, b, on in segments():
        last = b == T_END
        te = None if t_eval is None else np.append(t_eval[(t_eval >= a) & (t_eval < b)], b)
        sol = solve_ivp(model.rhs, (a, b), y0, method="BDF", rtol=1e-6, atol=atol, t_eval=te, args=(on,))
        for key in ("nfev", "njev", "nlu"):
            stats[key] += getattr(sol, key)
        stats["steps"] += len(sol.t) - 1 if t_eval is None else 0
        keep = slice(None) if last else slice(0, -1)  # the segment end is the next segment's start
        ts.append(sol.t[keep])
        ys.append(sol.y[:, keep])
        if sol.status < 0:
            status = sol.status
            break
        y0 = sol.y[:, -1]
    stats["rhs_calls"] = model.calls
    return np.concatenate(ts), np.concatenate(ys, axis=1), stats, status


def simulate(classes: int = 10, breakage: bool = True):
    """One run on the 121 output times: (model, t, y, stats, status), for cross-checks of trajectories."""
    model = Model(classes, breakage)
    return (model, *solve(model, np.linspace(0.0, T_END, 121)))


class Timed:
    """One variant ready to time: the model built and warmed up (one solve, which also counts the steps), so that
    a caller can interleave its solves with other work (`granuflow bench scene` alternates them with granuflow's
    runs, so that both see the same state of a shared machine)."""

    def __init__(self, classes: int = 10, breakage: bool = True):
        self.classes, self.breakage = classes, breakage
        self.model = Model(classes, breakage)
        self.t_eval = np.linspace(0.0, T_END, 121)
        self.steps = solve(self.model, None)[2]["steps"]  # t_eval does not change the stepping
        self.walls: list[float] = []
        self.last = None

    def solve(self) -> float:
        """One timed solve on the output times (model set-up excluded, as granuflow's configure); its wall time."""
        w0 = time.perf_counter()
        _, y, stats, status = solve(self.model, self.t_eval)
        wall = time.perf_counter() - w0
        self.walls.append(wall)
        self.last = (y, stats, status)
        return wall

    def record(self) -> dict:
        """The --json record: median wall time of the solves so far, solver statistics and the 60-min summary."""
        y, stats, status = self.last
        rec = {"code": "scipy", "classes": self.classes, "breakage": self.breakage,
               "wall_s_median": statistics.median(self.walls), "wall_s_min": min(self.walls),
               "repeats": len(self.walls), "nfev": stats["nfev"], "njev": stats["njev"], "nlu": stats["nlu"],
               "steps": self.steps, "rhs_calls": stats["rhs_calls"]}
        rec.update(self.model.summary(y[:, -1]))
        rec["status"] = status
        return rec


def run(classes: int = 10, breakage: bool = True, repeats: int = 1) -> dict:
    """The --json record of ``repeats`` solves in a row (see Timed)."""
    timed = Timed(classes, breakage)
    for _ in range(max(1, repeats)):
        timed.solve()
    return timed.record()


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--classes", type=int, default=10)
    ap.add_argument("--no-breakage", action="store_true")
    ap.add_argument("--repeats", type=int, default=1)
    ap.add_argument("--json", action="store_true")
    a = ap.parse_args()
    r = run(a.classes, not a.no_breakage, a.repeats)
    if a.json:
        print(json.dumps(r))
    else:
        print(f"scipy BDF, {r['classes']} classes, breakage {'on' if r['breakage'] else 'off'}: "
              f"{r['wall_s_median'] * 1e3:.1f} ms (median of {r['repeats']}), {r['steps']} steps, nfev {r['nfev']} "
              f"({r['rhs_calls']} f calls with the Jacobian columns), njev {r['njev']}, nlu {r['nlu']}; "
              f"d10/d50/d90 {r['d10_um']:.1f}/{r['d50_um']:.1f}/{r['d90_um']:.1f} um, "
              f"moisture {r['bed_moisture']:.5f} kg/kg, T_gas {r['T_gas_out_K']:.3f} K, status {r['status']}")


if __name__ == "__main__":
    main()
