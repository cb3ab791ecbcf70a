"""Issue 10, design space on a paper-003 scene: the map of steady product d50 over spray rate and upper cut size of
flowsheets/continuous_layering_free_holdup.yaml (free bed hold-up, a fixed seed feed) is made of direct steady-state
solves, and the spray rate moves the product the way the physics says."""
import os

import numpy as np
import pytest
from conftest import ROOT

import granuflow as gf
from granuflow import design_space as ds

FREE = os.path.join(ROOT, "flowsheets", "continuous_layering_free_holdup.yaml")


def free_loop(classes=40, **params):
    fs = gf.load_text(open(FREE).read().replace("classes: 100", f"classes: {classes}"), "free_holdup")
    fs.update(params)
    return fs


@pytest.fixture(scope="module")
def steady_map():
    base = free_loop()
    grid = ds.contour_map(base, ("gran.m_spray", "kg/h", [150, 200, 250]), ("sieve.upper_d_cut", "mm", [1.4, 1.6]),
                          outputs=["d50_um", "bed_mass_kg"], workers=1, progress=False, steady=True)
    return base, grid


def test_map_points_are_the_direct_steady_solves(steady_map):
    base, grid = steady_map
    assert grid.n_simulations == 6
    # labelled as steady states, not as the state at the scene's end time
    assert grid.steady and grid.when == "at the steady state" and grid.to_dataframe().attrs["steady_state"]
    d50 = np.asarray(grid.values["d50_um"])
    assert np.all(np.isfinite(d50))
    for i, j in ((0, 0), (1, 2), (0, 1)):  # (cut index, spray index): corners and a middle point
        f = base.clone()
        f.update({"gran.m_spray": grid.x.values[j] / 3600.0, "sieve.upper_d_cut": grid.y.values[i] * 1e-3})
        st = f.steady_state()
        assert d50[i, j] == pytest.approx(st["outputs"]["product.d50"] * 1e6, rel=1e-9)
        assert grid.values["bed_mass_kg"][i, j] == pytest.approx(st["outputs"]["gran.mass"], rel=1e-9)
    # and a steady state is where the dynamics end: one point run for 400 h (its slowest mode decays in < 10 h)
    f = base.clone()
    f.update({"gran.m_spray": 250.0 / 3600.0, "sieve.upper_d_cut": 1.6e-3})
    r = f.simulate(t_end=400 * 3600.0, n_out=2, rtol=1e-8)
    assert r["product.d50"][-1] * 1e6 == pytest.approx(d50[1, 2], rel=1e-6)


def test_product_grows_with_spray_rate_and_upper_cut(steady_map):
    """Nuclei come from the seed feed (fixed, 1 kg/h) and the mill. More spray puts more solids on about the same
    number of nuclei: in steady state product mass flow = seeds + spray solids while the number of product granules
    per hour is bounded by the nuclei supplied, so each granule must carry more mass and the product d50 rises with
    the spray rate. A larger upper cut lets larger granules pass as product (fewer are milled), so d50 rises with it
    too. Both effects are a few percent over the map; a reversed sign would mean the seeds, the growth law or the
    sieve were wrong."""
    _, grid = steady_map
    d50 = np.asarray(grid.values["d50_um"])
    assert np.all(np.diff(d50, axis=1) > 3.0)  # µm per 50 kg/h of spray, at both cut sizes
    assert np.all(np.diff(d50, axis=0) > 20.0)  # µm per 0.2 mm of upper cut
    # the free hold-up settles where the discharge k M balances seeds + recycle + spray solids: more spray, more bed
    assert np.all(np.diff(np.asarray(grid.values["bed_mass_kg"]), axis=1) > 0)


def test_without_seeds_the_spray_rate_only_scales_the_loop():
    """Without the seed feed every nucleus comes from the mill and the loop's equations are homogeneous of degree one
    in masses and flows (discharge k M, growth G proportional to spray solids over bed surface, linear sieve and
    mill): 25 % more spray gives a 25 % larger bed and throughput and exactly the same product. This is why the
    scene needs a nucleus source that does not scale with the spray."""
    out = []
    for spray in (200.0, 250.0):
        st = free_loop(**{"seeds.mdot": 0.0, "gran.m_spray": spray / 3600.0}).steady_state()["outputs"]
        out.append(st)
    assert out[1]["product.d50"] == pytest.approx(out[0]["product.d50"], rel=1e-8)
    assert out[1]["gran.mass"] == pytest.approx(1.25 * out[0]["gran.mass"], rel=1e-8)
    assert out[1]["product.mdot"] == pytest.approx(1.25 * out[0]["product.mdot"], rel=1e-8)


def test_a_run_into_the_steady_state_lengthens_its_steps():
    """At a steady state the solution stops changing and the integrator's step should grow. With the Newton matrix of
    a large block kept long and IDAS's default Newton test, the error Newton left behind looked like local error, the
    step stayed at 174 s and, the step being constant, nothing refreshed the matrix: this point crept through 600 h
    in 13323 steps (solver_setup.cpp, kLargeBlockNewtonTest). The run must also end at the direct steady solve."""
    fs = free_loop(100, **{"gran.m_spray": 250.0 / 3600.0, "sieve.upper_d_cut": 1.7e-3})
    r = fs.simulate(t_end=600 * 3600.0, n_out=2)
    assert r.stats["states"] == 103 and r.stats["steps"] < 2500
    st = fs.steady_state()
    assert r["product.d50"][-1] == pytest.approx(st["outputs"]["product.d50"], rel=1e-6)
