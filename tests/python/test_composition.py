"""Particles of two solids (issue 27, section 2): paper 003's Table 7.7 batch written as published, cores of
1040 kg/m3 growing a sodium-benzoate layer of 1440 kg/m3 in the two-compartment bed."""
import math
import os

import numpy as np
import pytest
from conftest import ROOT
from scipy.integrate import solve_ivp

import granuflow as gf

SCENE = os.path.join(ROOT, "flowsheets", "paper003_table77_layering.yaml")
N, RHO_CORE, RHO_LAYER = 100, 1040.0, 1440.0
M_SUS = 0.112 / 60 * 0.3  # kg/s of sodium benzoate: 100 ml/min at 1.12 kg/L, 30 wt%
TAU_S, TAU_D = 4.0, 196.0


@pytest.fixture(scope="module")
def run():
    return gf.load(SCENE).simulate()


def per_class(r, unit, what):
    return np.array([r[f"{unit}.{what}_{i}"] for i in range(N)])


def moments(r, unit, d):
    """Number moments k = 0..2 of a zone, its class numbers from the composition: N_i = sum_c m_c,i / rho_c / x_i."""
    x = math.pi / 6 * d ** 3
    n = (per_class(r, unit, "alumina_mass") / RHO_CORE + per_class(r, unit, "benzoate_mass") / RHO_LAYER) / x[:, None]
    return np.array([(n * d[:, None] ** k).sum(0) for k in range(3)])


def test_the_bed_gains_the_sprayed_mass_and_each_solid_balance_closes(run):
    total = run["spray.mass"] + run["drying.mass"]
    assert total[0] == pytest.approx(4.000, rel=1e-9)
    assert total[-1] == pytest.approx(7.024, rel=1e-7)  # 4 kg + 90 min x 33.6 g/min
    cores = run["spray.mass_alumina"] + run["drying.mass_alumina"]
    layer = run["spray.mass_benzoate"] + run["drying.mass_benzoate"]
    assert np.max(np.abs(cores - 4.0)) < 1e-8  # the cores pass between the zones, none made or lost
    assert layer[-1] == pytest.approx(M_SUS * 90 * 60, rel=1e-7)
    bal = run.balance_closure()
    assert bal["solids_rel"] < 1e-8
    assert bal["solids:alumina_rel"] < 1e-8 and bal["solids:benzoate_rel"] < 1e-8


def test_two_densities_follow_the_exact_moment_equations(run):
    """Eqs. (7.37)-(7.39) in number moments with the layer's density in the growth rate,
    G = 2 M_sus / (rho_layer pi mu_2) (paper 003, Eq. (7.33)): the whole bed's mean and standard deviation."""
    d = np.array([run[f"spray.psd_d_{i}"][0] for i in range(N)])
    ma, md = moments(run, "spray", d), moments(run, "drying", d)

    def rhs(t, y):
        a, b = y[:3], y[3:]
        g = 2 * M_SUS / (RHO_LAYER * math.pi * a[2])
        return np.concatenate([np.array([0.0, g * a[0], 2 * g * a[1]]) - a / TAU_S + b / TAU_D, a / TAU_S - b / TAU_D])

    sol = solve_ivp(rhs, (0, run.t[-1]), np.concatenate([ma[:, 0], md[:, 0]]), t_eval=run.t, rtol=1e-11, atol=1e-30,
                    method="LSODA")

    def mean_sigma(m):
        mean = m[1] / m[0]
        return mean, np.sqrt(m[2] / m[0] - mean ** 2)

    (mean_x, sig_x), (mean_p, sig_p) = mean_sigma(sol.y[:3] + sol.y[3:]), mean_sigma(ma + md)
    growth = sig_x[-1] - sig_x[0]
    assert growth > 15e-6
    assert np.max(np.abs(sig_p - sig_x)) < 0.01 * growth
    assert np.max(np.abs(mean_p - mean_x)) < 1e-5 * mean_x[-1]
    # layering makes no particles: counted from the composition, the bed keeps its number (at one density for both
    # solids the layer's volume would be wrong and so would the counts)
    n0 = (ma + md)[0]
    assert np.max(np.abs(n0 / n0[0] - 1)) < 1e-6


def test_the_layer_mass_fraction_per_class_shows_the_coating_uniformity(run):
    """The layer's share of each class: two zones spread it (particles that visited the spray zone more often carry
    more), and the larger classes, grown by more visits, carry the larger share."""
    i = -1
    core = per_class(run, "spray", "alumina_mass")[:, i] + per_class(run, "drying", "alumina_mass")[:, i]
    layer = per_class(run, "spray", "benzoate_mass")[:, i] + per_class(run, "drying", "benzoate_mass")[:, i]
    held = (core + layer) > 1e-4 * (core + layer).sum()
    frac = layer[held] / (core + layer)[held]
    assert np.all((frac > 0) & (frac < 1))
    assert frac[-1] > frac[0] + 0.1
    assert (layer.sum() / (core + layer).sum()) == pytest.approx(3.024 / 7.024, rel=1e-7)


def test_a_spray_component_the_particles_do_not_have_is_refused():
    text = open(SCENE).read().replace("spray_component: benzoate", "spray_component: sugar")
    with pytest.raises(ValueError, match=r"spray_component = 'sugar'.*alumina, benzoate"):
        gf.load_text(text, "bad")


def test_a_unit_that_carries_one_solid_refuses_a_particle_system_of_several():
    text = open(os.path.join(ROOT, "flowsheets", "pbm_constant_kernel.yaml")).read().replace(
        "classes: 27}", "classes: 27, components: 'core, layer'}")
    with pytest.raises(ValueError, match=r"several solids \(components: core, layer\).*carries one solid only"):
        gf.load_text(text, "bad")
