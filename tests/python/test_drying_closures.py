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
