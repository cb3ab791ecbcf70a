"""The review's drying closures (paper 000, sections 5.2 and 5.4.1; docs/drying_closures.md) on the wet batch of
flowsheets/paper000_drying_closures.yaml: every drying curve and drying surface runs, the balances close, moisture
stays non-negative, faster curves dry sooner, a smaller drying surface dries later, the defaults are the scene's
linear curve over the film, and a cubic that breaks A + B + C = 1 is refused with one line."""
import os

import numpy as np
import pytest
from conftest import ROOT

import granuflow as gf

SCENE = os.path.join(ROOT, "flowsheets", "paper000_drying_closures.yaml")
# (curve, surface, parameters): the defaults, each curve over the film, each surface under the linear curve
CHOICES = {
    "linear/film": ("linear", "film", {}),
    "gamma 3": ("gamma", "film", {"bed.drying_gamma": 3.0}),
    "gamma 0.3": ("gamma", "film", {"bed.drying_gamma": 0.3}),
    "cubic": ("cubic", "film", {"bed.drying_A": 0.5, "bed.drying_B": 0.3, "bed.drying_C": 0.2}),
    "correction 0.5": ("linear", "correction", {"bed.drying_f_surface": 0.5}),
    "coverage": ("linear", "coverage", {}),
    "droplet height": ("linear", "droplet_height", {}),
}


def run(curve, surface, params):
    fs = gf.load(SCENE).with_settings({"bed.drying_curve": curve, "bed.drying_surface": surface})
    fs.update(params)
    return fs.simulate(warn=False)


@pytest.fixture(scope="module")
def runs():
    return {k: run(*v) for k, v in CHOICES.items()}


def time_to(r, moisture):
    """Time at which the bed moisture (dry basis) falls through ``moisture`` after the spray (linear between outputs),
    or inf."""
    x, t = np.asarray(r["bed.moisture"]), np.asarray(r.t)
    hit = np.nonzero((t >= 600.0) & (x <= moisture))[0]
    if not hit.size:
        return float("inf")
    k = hit[0]
    return float(t[k - 1] + (x[k - 1] - moisture) / (x[k - 1] - x[k]) * (t[k] - t[k - 1]))


def test_every_choice_closes_its_balances_and_keeps_moisture_non_negative(runs):
    for name, r in runs.items():
        b = r.summary["balance"]
        for q in ("water_rel", "solids_rel", "energy_rel"):
            assert b[q] is not None and b[q] < 1e-5, (name, q, b)
        assert np.min(r["bed.moisture"]) >= 0.0, name
        assert np.all(np.isfinite(r["bed.d50"])), name


def test_the_batch_dries(runs):
    for name, r in runs.items():
        x = np.asarray(r["bed.moisture"])
        assert x[-1] < 0.5 * x[0], (name, x[0], x[-1])


def test_faster_curves_dry_sooner(runs):
    # below the critical moisture (0.07) gamma > 1 dries faster than linear, gamma < 1 and this cubic slower
    x_end = {k: runs[k]["bed.moisture"][-1] for k in runs}
    assert x_end["gamma 3"] < x_end["linear/film"] < x_end["cubic"] < x_end["gamma 0.3"], x_end
    level = 0.03
    t = {k: time_to(runs[k], level) for k in ("gamma 3", "linear/film", "gamma 0.3")}
    assert t["gamma 3"] < t["linear/film"] < t["gamma 0.3"], t


def test_less_drying_surface_dries_later(runs):
    x = {k: np.asarray(runs[k]["bed.moisture"]) for k in runs}
    # half the film dries slower at every time after the start; the bed is colder-wetter, so never drier
    assert np.all(x["correction 0.5"][1:] >= x["linear/film"][1:] - 1e-12)
    assert x["correction 0.5"][-1] > x["linear/film"][-1]
    # the droplets' footprints cover less than the whole surface once the bed has dried below a covering layer
    assert x["coverage"][-1] > x["linear/film"][-1]


def test_defaults_are_the_linear_curve_over_the_film(runs):
    fs = gf.load(SCENE)
    settings = fs.unit_settings()["bed"][1]
    assert settings.get("drying_curve") == "linear" and settings.get("drying_surface") == "film"
    r = gf.load(SCENE).simulate(warn=False)
    assert np.array_equal(np.asarray(r["bed.moisture"]), np.asarray(runs["linear/film"]["bed.moisture"]))


def test_a_cubic_breaking_its_rule_is_refused_in_one_line():
    fs = gf.load(SCENE).with_settings({"bed.drying_curve": "cubic"})
    fs.update({"bed.drying_A": 0.6, "bed.drying_B": 0.6, "bed.drying_C": 0.6})
    with pytest.raises(gf.ConfigError) as e:
        fs.simulate(warn=False)
    msg = str(e.value)
    assert "A + B + C = 1.8" in msg and "\n" not in msg, msg


# Paper 003's two-zone bed (spray and drying compartments) holding a wet batch, the spray off: the compartments' drying
# curve (setting drying_curve) against their first-order drying.
TWO_ZONE = """
scene: wet_two_zone_batch
t_end: 10 min
output: {n: 21}
solver: {rtol: 1e-8, atol: 1e-10}
particles: {settings: {classes: 12, d_min: 5.0e-4, d_max: 4.0e-3}, params: {rho_s: 1040, eps_intra: 0}}
units:
  spray: {type: spray_compartment, settings: {drying: first_order, CURVE},
          params: {bed_mass: 0.08, m_spray: 0, tau: 4 s, X0: 0.2, X_eq: 0.01, tau_dry: 60 s, PARAMS}}
  dry: {type: drying_compartment, settings: {drying: first_order, CURVE},
        params: {bed_mass: 3.92, tau: 196 s, X0: 0.2, X_eq: 0.01, tau_dry: 60 s, PARAMS}}
connections: [spray.out -> dry.in, dry.out -> spray.in]
"""


def two_zone(curve=None, params=""):
    text = TWO_ZONE.replace("CURVE", f"drying_curve: {curve}" if curve else "drying_curve: none")
    text = text.replace(", PARAMS", f", {params}" if params else "")
    return gf.load_text(text).simulate(warn=False)


def test_chamber_linear_curve_below_the_critical_moisture_is_first_order_drying():
    first, linear = two_zone(), two_zone("linear", "X_cr: 1.0")
    for u in ("spray", "dry"):
        assert np.allclose(linear[f"{u}.moisture"], first[f"{u}.moisture"], rtol=1e-6, atol=0), u


def test_chamber_curves_order_and_the_constant_rate_period():
    x = {g: two_zone("gamma", f"X_cr: 0.1, drying_gamma: {g}")["dry.moisture"][-1] for g in (0.3, 1.0, 3.0)}
    assert x[3.0] < x[1.0] < x[0.3], x
    # above X_cr the bed dries at the constant rate (X_cr - X_eq) M / tau_dry of both compartments together
    r = two_zone("gamma", "X_cr: 0.1, drying_gamma: 3")
    rate = r["spray.vapour_mdot"][0] + r["dry.vapour_mdot"][0]
    assert rate == pytest.approx((0.1 - 0.01) * 4.0 / 60.0, rel=1e-9)


# Spray filtration (paper 000, sections 5.1.4 and 5.5) and the Stokes deformation regime (section 5.6) on the same
# wet batch. A path of 1 mm filters about half of the droplets; a path of 10 m all of them (F = 1 exactly).
def filtration_run(length):
    fs = gf.load(SCENE).with_settings({"bed.spray_deposition": "filtration", "bed.stokes_deformation": "report"})
    fs.update({"bed.filtration_length": length})
    return fs.simulate(warn=False)


@pytest.fixture(scope="module")
def filtered():
    return filtration_run(1e-3)


def hand_filtered_fraction(r, k, length, phi_p=0.1, d_d=30e-6, rho_d=1000.0, p=101325.0):
    """Paper 000, section 5.1.4, written out: Kolakaluri's clean-bed filter over the bed's classes at output k."""
    t_g, y, u0 = r["gas.T"][k], r["gas.Y"][k], r["bed.u0"][k]
    mu = 1.716e-5 * (t_g / 273.15) ** 1.5 * (273.15 + 110.4) / (t_g + 110.4)  # Sutherland, as properties.hpp
    p_v = p * y / (y + 0.01801528 / 0.0289647)
    rho = (1.0 + y) * (p - p_v) * 0.0289647 / (8.314462618 * t_g)
    n = sum(1 for i in range(100) if f"bed.psd_d_{i}" in r)
    d = np.asarray([r[f"bed.psd_d_{i}"][k] for i in range(n)])
    m = np.asarray([r[f"bed.psd_m_{i}"][k] for i in range(n)])
    phi_f = 1.0 - phi_p
    slip = u0 / phi_f
    st = slip * d_d**2 * rho_d / (18.0 * d * mu * phi_f)
    re = slip * (1.0 - phi_p) * rho * d / (mu * phi_f)
    c = phi_p ** (1.0 / 3.0)
    a = (6.0 - 6.0 * c**5) / (6.0 - 9.0 * c + 9.0 * c**5 - 6.0 * phi_p**2)
    st_eff = (a + 1.14 * re**0.2 * (1.0 - phi_p) ** -1.5) * st / 2.0
    eta = st_eff**3.2 / (4.3 + st_eff**3.2)
    lam = np.sum(1.5 * eta * phi_p * (m / m.sum()) / d)
    return 1.0 - np.exp(-lam * length)


def test_filtration_shares_the_spray_and_closes_the_balances(runs, filtered):
    r, ref = filtered, runs["linear/film"]
    b = r.summary["balance"]
    for q in ("water_rel", "solids_rel", "energy_rel"):
        assert b[q] is not None and b[q] < 1e-5, (q, b)
    f0 = r["bed.filtered_fraction"][0]
    assert f0 == pytest.approx(hand_filtered_fraction(r, 0, 1e-3), rel=1e-9)
    assert 0.2 < f0 < 0.8, f0
    # at the start both beds hold the same water and see the same gas: the unfiltered water (a water spray) is the
    # extra vapour, evaporated in the gas (section 5.5)
    extra = r["bed.m_vap"][0] - ref["bed.m_vap"][0]
    assert extra == pytest.approx((1.0 - f0) * r["droplets.m_dep"][0], rel=1e-9)
    # less water reaches the particles: the bed is drier while sprayed (by little: the evaporated droplets wet the
    # gas the bed dries into, section 5.5)
    k = int(np.searchsorted(np.asarray(r.t), 600.0))
    assert r["bed.moisture"][k] < ref["bed.moisture"][k]


def test_filtration_of_every_droplet_is_the_spray_zone_wetting(runs):
    r, ref = filtration_run(10.0), runs["linear/film"]
    assert np.all(np.asarray(r["bed.filtered_fraction"]) == 1.0)
    for key in ("bed.moisture", "bed.T", "bed.d50", "gas.Y"):
        assert np.array_equal(r[key], ref[key]), key


def test_stokes_deformation_regime_of_the_d50_granules(filtered):
    r = filtered
    d50 = np.asarray(r["bed.d50"])
    rho = 1545.0 * (1.0 - 0.3)  # maltodextrin's envelope density, rho_s (1 - eps_intra), paper 001, Tables 6-7
    # St = 2 M u / (3 pi mu d^2) with M = rho pi d^3 / 6: St = rho d50 u / (9 mu) at u = 0.5 m/s, mu = 1 mPa s
    assert np.allclose(np.asarray(r["bed.stokes_viscous"]), rho * d50 * 0.5 / (9.0 * 1e-3), rtol=1e-12)
    crit = 2.0 * (1.0 + 1.0 / 0.5) * np.log(10e-6 / 1e-6)  # St*_def = 2 St*_coal, paper 000, section 5.6
    assert np.allclose(r["bed.stokes_def_critical"], crit, rtol=1e-14)
    assert np.allclose(r["bed.stokes_coal_critical"], crit / 2.0, rtol=1e-14)
    st = np.asarray(r["bed.stokes_viscous"])
    expect = np.where(st < crit / 2.0, 0.0, np.where(st < crit, 1.0, 2.0))
    assert np.array_equal(np.asarray(r["bed.deformation_regime"]), expect)


def two_zone_surface(surface, params=""):
    text = TWO_ZONE.replace("CURVE", f"drying_curve: none, drying_surface: {surface}")
    text = text.replace(", PARAMS", f", {params}" if params else "")
    return gf.load_text(text).simulate(warn=False)


def test_chamber_drying_surfaces_scale_the_rate_by_their_wetted_share():
    first = two_zone()
    film = two_zone_surface("film")
    for u in ("spray", "dry"):
        assert np.array_equal(film[f"{u}.moisture"], first[f"{u}.moisture"]), u
    half = two_zone_surface("correction", "drying_f_surface: 0.5")
    rate = {k: r["spray.vapour_mdot"][0] + r["dry.vapour_mdot"][0] for k, r in (("first", first), ("half", half))}
    assert rate["half"] == pytest.approx(0.5 * rate["first"], rel=1e-12)
    # coverage: the class's water as 30 um droplets covers 1 - exp(-phi_i) of it, phi_i = 3 V_l / (2 d_d A_i) =
    # X0 rho_p d_i / (4 rho_l d_d) for spheres; at the start every class holds X0 = 0.2, X_eq = 0.01, tau_dry = 60 s
    cov = two_zone_surface("coverage")
    hand = 0.0
    for u in ("spray", "dry"):
        n = sum(1 for i in range(100) if f"{u}.psd_d_{i}" in cov)
        for i in range(n):
            d, m = cov[f"{u}.psd_d_{i}"][0], cov[f"{u}.psd_m_{i}"][0]
            phi = 0.2 * 1040.0 * d / (4.0 * 1000.0 * 30e-6)
            hand += (0.2 - 0.01) * m / 60.0 * -np.expm1(-phi)
    assert cov["spray.vapour_mdot"][0] + cov["dry.vapour_mdot"][0] == pytest.approx(hand, rel=1e-9)
    b = cov.summary["balance"]
    assert b["water_rel"] is not None and b["water_rel"] < 1e-6, b
