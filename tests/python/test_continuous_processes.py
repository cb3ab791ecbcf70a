"""Paper 003's continuous and zoned processes (issue 10): the sieve-mill loop's steady state, conservation in sieve and
mill, surface-proportional layering against its analytic solution, the two-zone model against its exact moment
equations, tanks in series against Eq. (7.31), grid convergence, and the oscillating loop."""
import json
import math
import os
import re

import numpy as np
import pytest
from conftest import ROOT, cli, strict_json
from scipy.integrate import solve_ivp
from scipy.special import gammainc

import granuflow as gf
from granuflow.steady import steady_report

LOOP = os.path.join(ROOT, "flowsheets", "continuous_layering_sieve_mill.yaml")
TWO_ZONE = os.path.join(ROOT, "flowsheets", "two_zone_layering.yaml")
RTD = os.path.join(ROOT, "flowsheets", "tanks_in_series_rtd.yaml")


def loop(classes=None, **params):
    fs = gf.load(LOOP)
    fs.set_input("gran.m_spray", [0.0], [200.0 / 3600.0])  # no spray step: the operating point of the first 60 h
    if classes:
        text = open(LOOP).read().replace("classes: 100", f"classes: {classes}")
        fs2 = gf.load_text(text, "loop")
        fs2.set_input("gran.m_spray", [0.0], [200.0 / 3600.0])
        fs = fs2
    fs.update(params)
    return fs


# -- the sieve-mill loop -------------------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def loop_60():
    return loop(60)


def test_steady_state_equals_the_end_of_a_long_run_and_closes_the_balance(loop_60):
    rep = steady_report(loop_60)
    assert rep["solver"]["method"] == "newton"
    bal = rep["balance"]["solids"]
    assert bal["in"] == pytest.approx(60.0 / 3600.0, rel=1e-12)  # the spray's solids
    assert bal["rel"] < 1e-9  # feed in = product out
    assert rep["product_kg_s"] == pytest.approx(bal["in"], rel=1e-9)
    assert rep["stability"]["stable"] and rep["stability"]["oscillation_period_s"] > 3600
    res = loop_60.simulate(t_end=400 * 3600.0, n_out=2, rtol=1e-8)
    assert res["product.d50"][-1] * 1e6 == pytest.approx(rep["d50_um"], rel=1e-6)
    assert res["gran.mass"][-1] == pytest.approx(rep["bed_mass_kg"], rel=1e-6)
    # the controller holds the bed within eps^2 tau_c / (4 R) of its set point
    assert rep["bed_mass_kg"] == pytest.approx(100.0, rel=1e-5)


def test_steady_state_from_a_poor_start_needs_no_tuning(loop_60):
    ref = steady_report(loop_60)["d50_um"]
    for start in ({"gran.d50_0": 300e-6}, {"gran.bed_mass": 10.0}):
        fs = loop_60.clone()
        fs.update(start)
        rep = steady_report(fs, stability=False)
        assert rep["solver"]["method"] == "pseudo-transient continuation, then newton", start
        assert rep["solver"]["pseudo_steps"] < 100
        assert rep["d50_um"] == pytest.approx(ref, rel=1e-9), start


def test_spray_rate_sets_the_throughput_not_the_product(loop_60):
    """Bed mass held, every nucleus from the mill: every rate of the loop scales with the spray, so the steady product
    is the same at +20 % spray and only the flows grow by 20 %."""
    a = steady_report(loop_60, stability=False)
    fs = loop_60.clone()
    fs.set_input("gran.m_spray", [0.0], [240.0 / 3600.0])
    b = steady_report(fs, stability=False)
    assert b["d50_um"] == pytest.approx(a["d50_um"], rel=1e-9)
    assert b["product_kg_s"] == pytest.approx(1.2 * a["product_kg_s"], rel=1e-9)
    assert b["discharge_kg_s"] == pytest.approx(1.2 * a["discharge_kg_s"], rel=1e-6)


def test_grid_convergence_of_the_steady_product():
    d = {n: steady_report(loop(n), stability=False) for n in (25, 50, 100)}
    for key in ("d10_um", "d50_um", "d90_um"):
        e1 = abs(d[50][key] - d[25][key])
        e2 = abs(d[100][key] - d[50][key])
        assert e2 < 0.6 * e1, (key, e1, e2)
        assert e2 < 0.015 * d[100][key]


def test_the_oscillation_is_physical():
    """A coarser mill product (600 um) makes the steady state unstable (a Hopf bifurcation): the eigenvalue with the
    largest real part is positive on 60 and 120 classes alike, and the dynamics keep oscillating with that
    eigenvalue's period at two tolerances; first-order upwind's numerical diffusion damps the same physics."""
    eig = {}
    for n in (60, 120):
        st = loop(n, **{"mill.d50": 600e-6}).steady_state(stability=True)["stability"]
        eig[n] = (st["max_real_eigenvalue"], 2 * math.pi / st["imag_of_max"])
    assert eig[60][0] > 0 and eig[120][0] > 0
    assert eig[60][1] == pytest.approx(eig[120][1], rel=0.02)  # period about 7 h on both grids
    periods = []
    for rtol in (1e-6, 1e-8):
        fs = loop(60, **{"mill.d50": 600e-6})
        r = fs.simulate(t_end=250 * 3600.0, n_out=2501, rtol=rtol)
        d = r["product.d50"][1000:]
        assert d.max() - d.min() > 100e-6  # a limit cycle of more than 100 um in d50, not decaying
        up = np.where((d[:-1] < d.mean()) & (d[1:] >= d.mean()))[0]
        periods.append(np.mean(np.diff(r.t[1000:][up])))
    assert periods[0] == pytest.approx(periods[1], rel=0.01)
    st = loop(60, **{"mill.d50": 450e-6}).steady_state(stability=True)["stability"]
    assert st["max_real_eigenvalue"] < 0  # the damped set
    text = open(LOOP).read().replace("classes: 100", "classes: 60").replace(
        "bed_mass: controlled}", "bed_mass: controlled, growth_scheme: fv_upwind}")
    up_st = gf.load_text(text).steady_state(stability=True)  # default mill 450 um; now 600 um on upwind:
    fs = gf.load_text(text)
    fs.set("mill.d50", 600e-6)
    assert fs.steady_state(stability=True)["stability"]["max_real_eigenvalue"] < eig[60][0] / 3
    assert up_st["stability"]["max_real_eigenvalue"] < 0


def test_steady_cli_writes_the_report_and_names_a_missing_steady_state(tmp_path):
    p = cli("steady", LOOP, "--out", tmp_path / "s", "--set", "mill.d50=600 um")
    assert p.returncode == 0, p.stderr
    rep = strict_json(tmp_path / "s" / "steady.json")
    for key in ("d10_um", "d50_um", "d90_um", "bed_mass_kg", "product_kg_s", "balance", "stability", "solver"):
        assert key in rep
    assert rep["stability"]["stable"] is False and "UNSTABLE" in p.stdout
    assert rep["solver"]["iterations"] > 0 and rep["solver"]["wall_time_s"] > 0
    psd = open(tmp_path / "s" / "steady_psd.csv").read().splitlines()
    assert psd[0].startswith("unit,class,d_um") and len(psd) == 101
    p = cli("steady", TWO_ZONE, "--out", tmp_path / "b")
    assert p.returncode == 3 and "Traceback" not in p.stderr
    assert "has no steady state" in p.stderr and len(p.stderr.strip().splitlines()) == 1


def test_contour_map_from_steady_states(tmp_path):
    p = cli("contour", LOOP, "--steady", "--x", "mill.d50:um:400:500:2", "--y", "sieve.upper_d_cut:mm:1.4:1.6:2",
            "--output", "d50_um", "--out", tmp_path / "c", "--workers", "1", "--set", "particles.rho_s=1500")
    assert p.returncode == 0, p.stderr
    meta = json.load(open(tmp_path / "c" / "contour.json"))
    assert meta["steady_state"] is True and meta["n_failed"] == 0
    rows = open(tmp_path / "c" / "contour.csv").read().splitlines()
    assert len(rows) == 5


# -- sieve and mill ------------------------------------------------------------------------------------------------
SPLIT = """
scene: sieve_and_mill
t_end: 1 s
output: {n: 2}
particles: {settings: {classes: 30, d_min: 1.0e-4, d_max: 4.0e-3}}
units:
  feed: {type: solids_feed, params: {mdot: 0.1, d50: 1 mm, sigma: 1.8, X: 0.05}}
  split: {type: solids_splitter, params: {fraction: 0.5}}
  sieve: {type: sieve, settings: {upper_curve: sharp, lower_curve: sharp},
          params: {upper_d_cut: UPPER, lower_d_cut: LOWER}}
  mill: {type: mill, settings: {law: LAW}}
  over: {type: solids_product}
  prod: {type: solids_product}
  under: {type: solids_product}
  milled: {type: solids_product}
connections: [feed.out -> split.in, split.out1 -> sieve.in, split.out2 -> mill.in, sieve.oversize -> over.in,
              sieve.product -> prod.in, sieve.undersize -> under.in, mill.out -> milled.in]
"""


def split_scene(upper, lower, law="lognormal"):
    return gf.load_text(SPLIT.replace("UPPER", repr(upper)).replace("LOWER", repr(lower)).replace("LAW", law))


def test_sieve_and_mill_conserve_mass_class_by_class():
    for law in ("lognormal", "vogel_peukert"):
        fs = split_scene(1.7e-3, 0.6e-3, law)
        r = fs.simulate()
        y = {k: r[k][-1] for k in fs.state_names}
        for i in range(30):
            feed = y[f"split.out1_mdot_{i}"]
            parts = sum(y[f"sieve.{o}_mdot_{i}"] for o in ("oversize", "product", "undersize"))
            assert parts == pytest.approx(feed, rel=1e-15, abs=1e-300)
            w = sum(y[f"sieve.{o}_water_{i}"] for o in ("oversize", "product", "undersize"))
            assert w == pytest.approx(y[f"split.out1_water_{i}"], rel=1e-15, abs=1e-300)
        milled = sum(y[f"mill.mdot_{i}"] for i in range(30))
        assert milled == pytest.approx(0.05, rel=1e-14)  # the mill's columns sum to one exactly
        assert sum(y[f"mill.water_{i}"] for i in range(30)) == pytest.approx(0.05 * 0.05, rel=1e-14)
        assert r["mill.d50_out"][-1] < r["mill.d50_in"][-1]  # it grinds


def test_the_product_fraction_of_an_empty_sieve_is_undefined():
    """The sieve's product_fraction is product/(oversize + product + undersize); with nothing on the decks it is
    undefined (NaN in the time series), never 0, which would read as "all of it is off-spec"."""
    fs = split_scene(1.7e-3, 0.6e-3)
    r = fs.simulate()
    m = {o: r[f"sieve.{o}_mdot"][-1] for o in ("oversize", "product", "undersize")}
    assert r["sieve.product_fraction"][-1] == pytest.approx(m["product"] / sum(m.values()), rel=1e-14)
    assert 0 < r["sieve.product_fraction"][-1] < 1
    r = fs.set("split.fraction", 0.0).simulate()
    assert r["sieve.product_mdot"][-1] == 0 and np.isnan(r["sieve.product_fraction"][-1])


def test_a_dry_particle_system_computes_the_same_flows_without_water():
    """particles: water: false: the sieve, mill, splitter and mixer declare no water states (their outlets pass on the
    feed's one zero), and every flow they compute is bit for bit the one of the same scene carrying zero water."""
    dry_text = SPLIT.replace("classes: 30,", "classes: 30, water: false,").replace(", X: 0.05", "")
    dry_text = dry_text.replace("UPPER", "1.7e-3").replace("LOWER", "0.6e-3").replace("LAW", "vogel_peukert")
    wet_text = dry_text.replace(", water: false", "")
    dry, wet = gf.load_text(dry_text, "dry"), gf.load_text(wet_text, "wet")
    rd, rw = dry.simulate(), wet.simulate()
    water = [k for k in wet.state_names if "water" in k]
    assert len(water) == 30 * (2 + 3 + 1) + 30 and not [k for k in dry.state_names if "water_" in k]
    assert "feed.water" in dry.state_names and rd["feed.water"][-1] == 0.0  # the one zero the outlets pass on
    assert set(dry.state_names) == set(wet.state_names) - set(water) | {"feed.water"}
    for k in set(dry.state_names) - {"feed.water"}:
        assert np.array_equal(rd[k], rw[k]), k
    for k in rd.output_names:
        assert np.array_equal(rd[k], rw[k]), k
    assert rd.stats["explicit_states"] == rw.stats["explicit_states"] - len(water) + 1


def test_a_dry_particle_system_refuses_water():
    dry = SPLIT.replace("classes: 30,", "classes: 30, water: false,")
    dry = dry.replace("UPPER", "1.7e-3").replace("LOWER", "0.6e-3").replace("LAW", "lognormal")
    with pytest.raises(gf.ConfigError, match=r"feed.*X.*0\.05.*the particle system is dry"):
        gf.load_text(dry, "dry").simulate()
    wet_gran = CLASSIFIED.replace("d_max: 4.0e-3}", "d_max: 4.0e-3, water: false}")
    with pytest.raises(gf.ConfigError, match=r"gran.*drying: first_order.*particle system is dry"):
        gf.load_text(wet_gran, "wet_gran")
    # every unit that holds water on its particles says so: the paper-001 bed and spray zone, the 2-D population
    for scene, unit in (("stoeckl_gf25_batch.yaml", "spray_zone|bed"), ("sen_2d_dem_kernel.yaml", "2-D population")):
        text = open(os.path.join(ROOT, "flowsheets", scene)).read()
        dry_text = re.sub(r"(particles:\n(?:  material: .*\n)?  settings: \{)", r"\1water: false, ", text, count=1)
        assert dry_text != text, scene
        with pytest.raises(gf.ConfigError, match=rf"({unit}).*particle system is dry"):
            gf.load_text(dry_text, "dry")


def test_the_lognormal_mill_applies_its_breakage_matrix():
    # The log-normal law's fragments do not depend on the parent, and the mill applies its matrix with a suffix sum
    # over the coarser classes: compare with the matrix product built here from the law, P_ik = F(e_i+1) - F(e_i) for
    # i < k (class 0 also takes what falls below the grid), P_kk = 1 - F(e_k).
    fs = split_scene(1.7e-3, 0.6e-3)
    fs.set("mill.d50", 450e-6)
    fs.set("mill.sigma_g", 1.6)
    r = fs.simulate()
    y = {k: r[k][-1] for k in fs.state_names}
    dp = 1e-4 * (4e-3 / 1e-4) ** (np.arange(30) / 29)
    de = np.sqrt(dp[:-1] * dp[1:])  # the edges between classes
    F = np.array([0.5 * math.erfc(-math.log(d / 450e-6) / (math.log(1.6) * math.sqrt(2.0))) for d in de])
    P = np.zeros((30, 30))
    for k in range(30):
        below = 0.0
        for i in range(k):
            P[i, k] = F[i] - below
            below = F[i]
        P[k, k] = 1.0 - P[:k, k].sum()
    for q in ("mdot", "water"):
        feed = np.array([y[f"split.out2_{q}_{i}"] for i in range(30)])
        out = np.array([y[f"mill.{q}_{i}"] for i in range(30)])
        assert out == pytest.approx(P @ feed, rel=1e-12, abs=1e-15 * feed.sum())
        assert out.sum() == pytest.approx(feed.sum(), rel=1e-14)


def test_an_ideal_sieve_splits_at_its_cut_sizes():
    # the grid: log-spaced pivots; the edges between classes are their geometric means (in volume, so in diameter)
    dp = 1e-4 * (4e-3 / 1e-4) ** (np.arange(30) / 29)
    de = np.sqrt(dp[:-1] * dp[1:])  # de[k]: the edge between classes k and k + 1
    fs = split_scene(float(de[24]), float(de[15]))  # both cuts on cell edges
    r = fs.simulate()
    y = {k: r[k][-1] for k in fs.state_names}
    for i in range(30):
        feed = y[f"split.out1_mdot_{i}"]
        got = [y[f"sieve.{o}_mdot_{i}"] / feed for o in ("oversize", "product", "undersize")]
        want = [1, 0, 0] if i >= 25 else [0, 1, 0] if i >= 16 else [0, 0, 1]
        assert got == pytest.approx(want, abs=1e-12), i
    # a cut inside a cell splits it by the share of ln d above the cut
    fs = split_scene(float(de[24]), math.sqrt(de[15] * de[16]))
    r = fs.simulate()
    assert r["sieve.product_mdot_16"][-1] == pytest.approx(0.5 * r["split.out1_mdot_16"][-1], rel=1e-12)


# -- a chamber's outlets: computed inline by companion units ---------------------------------------------------------
CLASSIFIED = """
scene: classified
t_end: 2 h
output: {n: 5}
particles:
  settings: {classes: 20, d_min: 1.0e-4, d_max: 4.0e-3}
  params: {rho_s: 1500 kg/m3}
units:
  gran:
    type: granulator
    settings: {discharge: classified, bed_mass: controlled, drying: first_order}
    params: {bed_mass: 50 kg, M_set: 50 kg, d50_0: 800 um, sigma_0: 1.5, class_d_cut: 1.0 mm, X0: 0.05}
  product: {type: solids_product}
connections: [gran.discharge -> product.in]
"""


def test_outlet_flows_are_computed_inline_from_the_hold_up_and_one_rate():
    """The discharge's per-class flows are no unknowns of the Newton system: the companion unit gran:discharge
    computes r f_i M_i and r f_i W_i from the granulator's hold-up and its one rate state, and they keep the names
    gran.discharge_mdot_i, gran.discharge_water_i."""
    fs = loop(20)
    r = fs.simulate(t_end=3 * 3600.0, n_out=4)
    names = fs.state_names
    assert {f"gran.discharge_mdot_{i}" for i in range(20)} <= set(names) and "gran.discharge_rate" in names
    assert not any(":" in k for k in names)
    # the Newton system: 20 class masses, T, the dry chamber's zero water, the rate and the product's states;
    # the 20 flows are among the inlined states, with the sieve's, the mill's and the mixer's
    assert r.stats["states"] < 30 and r.stats["states"] + r.stats["explicit_states"] == len(names)
    for k in range(1, 4):
        for i in range(20):
            want = r["gran.discharge_rate"][k] * r[f"gran.M_{i}"][k]
            assert r[f"gran.discharge_mdot_{i}"][k] == pytest.approx(want, rel=1e-13, abs=1e-300)
        total = sum(r[f"gran.discharge_mdot_{i}"][k] for i in range(20))
        assert r["gran.discharge_mdot"][k] == pytest.approx(total, rel=1e-13)
    # a classified discharge of a wet bed: class i leaves at r f_i, water with its solids, fine classes stay
    fs = gf.load_text(CLASSIFIED, "classified")
    r = fs.simulate()
    frac = []
    for i in range(20):
        m, w = r[f"gran.discharge_mdot_{i}"][-1], r[f"gran.discharge_water_{i}"][-1]
        assert w / m == pytest.approx(r[f"gran.W_{i}"][-1] / r[f"gran.M_{i}"][-1], rel=1e-12)
        frac.append(m / (r["gran.discharge_rate"][-1] * r[f"gran.M_{i}"][-1]))
    assert frac[0] < 1e-3 and frac[-1] > 0.999 and np.all(np.diff(frac) > -1e-15)  # a separation curve
    assert r["gran.discharge_mdot"][-1] == pytest.approx(r["product.mdot"][-1], rel=1e-13)
    assert r["gran.mass"][-1] == pytest.approx(50.0, rel=1e-3)  # the controller holds the bed
    # paper 001's fluid bed discharges the same way: k M_i and k W_i, computed by bed:discharge
    fs = gf.load(os.path.join(ROOT, "flowsheets", "continuous_drying_bed.yaml"))
    r = fs.simulate(t_end=1800.0, n_out=3)
    assert r["bed.discharge_rate"][-1] == pytest.approx(1e-3, rel=1e-14)
    for i in range(12):
        for q, hold in (("mdot", "M"), ("water", "W")):
            want = 1e-3 * r[f"bed.{hold}_{i}"][-1]
            assert r[f"bed.discharge_{q}_{i}"][-1] == pytest.approx(want, rel=1e-13, abs=1e-300)


def test_a_chamber_outlet_is_named_by_its_owner_in_errors():
    text = CLASSIFIED.replace("connections: [gran.discharge -> product.in]", "connections: []")
    with pytest.raises(gf.ConfigError, match=r"port gran\.discharge \(solids, out\) is not connected"):
        gf.load_text(text, "open")
    with pytest.raises(gf.ConfigError, match=r"has no port 'dis' \(ports: .*discharge"):
        gf.load_text(CLASSIFIED.replace("gran.discharge ->", "gran.dis ->"), "typo")
    with pytest.raises(gf.ConfigError, match=r"unit name 'gran:x'.*no '\.' or ':'"):
        gf.load_text(CLASSIFIED.replace("  gran:\n", "  gran:x:\n"), "colon")


# -- layering without recycle: analytic surface-proportional growth --------------------------------------------------
def test_batch_layering_follows_the_analytic_surface_proportional_growth():
    """Paper 003, Eqs. (7.33)-(7.34): every particle grows at G = 2 M_sus / (rho pi mu_2), so the number distribution
    shifts by s(t), and mu_3 grows by 6 M_sus t / (pi rho): s solves mu_3^0 + 3 s mu_2^0 + 3 s^2 mu_1^0 + s^3 mu_0^0 =
    mu_3^0 + 6 M_sus t / (pi rho). The mean diameter is mu_1^0 / mu_0^0 + s."""
    r = gf.load(TWO_ZONE).simulate()
    n, rho, m_sus = 100, 1040.0, 0.112 / 60 * 0.3
    d = np.array([r[f"onezone.psd_d_{i}"][0] for i in range(n)])
    N0 = np.array([r[f"onezone.psd_m_{i}"][0] for i in range(n)]) / (rho * math.pi / 6 * d ** 3)
    mu = [np.sum(N0 * d ** k) for k in range(4)]
    for k in range(0, 91, 15):
        t = r.t[k]
        rhs = 6 * m_sus * t / (math.pi * rho)
        s = np.roots([mu[0], 3 * mu[1], 3 * mu[2], -rhs])
        s = float(np.real(s[np.isreal(s)]).max())
        assert r["onezone.d_mean"][k] == pytest.approx(mu[1] / mu[0] + s, rel=2e-4), t
    # the shape is kept: the standard deviation stays (numerical diffusion of the scheme: < 0.5 % in 90 min)
    assert r["onezone.sigma"][-1] == pytest.approx(r["onezone.sigma"][0], rel=5e-3)


def test_two_zones_follow_their_exact_moment_equations():
    """Eqs. (7.37)-(7.39) in moments: mu_k' = k G mu_(k-1) - mu_k / tau_a + mu_k^d / tau_d in the spray zone, with
    G = 2 M_sus / (rho pi mu_2^a), and the exchange alone in the drying zone: a closed system for k = 0..2, so the
    mean and the standard deviation of the whole bed are exact; the population balance must follow them."""
    r = gf.load(TWO_ZONE).simulate()
    n, rho, m_sus, ta, td = 100, 1040.0, 0.112 / 60 * 0.3, 4.0, 196.0
    d = np.array([r[f"spray.psd_d_{i}"][0] for i in range(n)])
    pm = rho * math.pi / 6 * d ** 3

    def moments(unit):
        M = np.array([r[f"{unit}.psd_m_{i}"] for i in range(n)]) / pm[:, None]
        return np.array([(M * d[:, None] ** k).sum(0) for k in range(3)])

    ma, md = moments("spray"), moments("drying")

    def rhs(t, y):
        a, b = y[:3], y[3:]
        g = 2 * m_sus / (rho * math.pi * a[2])
        return np.concatenate([np.array([0.0, g * a[0], 2 * g * a[1]]) - a / ta + b / td, a / ta - b / td])

    sol = solve_ivp(rhs, (0, r.t[-1]), np.concatenate([ma[:, 0], md[:, 0]]), t_eval=r.t, rtol=1e-11, atol=1e-30,
                    method="LSODA")
    tot, pbm = sol.y[:3] + sol.y[3:], ma + md

    def mean_sigma(m):
        mean = m[1] / m[0]
        return mean, np.sqrt(m[2] / m[0] - mean ** 2)

    (mean_x, sig_x), (mean_p, sig_p) = mean_sigma(tot), mean_sigma(pbm)
    growth = sig_x[-1] - sig_x[0]
    assert growth > 20e-6  # dispersive growth: sigma rises by more than 20 um in 90 min
    assert np.max(np.abs(sig_p - sig_x)) < 0.01 * growth
    assert np.max(np.abs(mean_p - mean_x)) < 1e-5 * mean_x[-1]
    # the one-zone bed keeps its width while the two-zone bed's grows (Figs. 7.44, 7.48)
    assert r["onezone.sigma"][-1] - r["onezone.sigma"][0] < 0.02 * growth
    # the spray zone keeps its share of the particles, Eq. (7.39)
    frac = ma[0] / (ma[0] + md[0])
    assert frac[-1] == pytest.approx(ta / (ta + td), rel=1e-3)


@pytest.mark.parametrize("scheme", ["fv_van_albada", "fv_koren"])
def test_a_grid_widened_at_the_same_resolution_gives_the_same_beds(scheme):
    """The narrow initial distribution (sigma_g 1.1 at 1.8 mm) on a grid reaching down to 0.1 mm: its lower tail
    holds densities far below 1e-100. With as many classes per size decade, the beds are those of the scene's own
    grid. Before, the default limiter's Jacobian turned NaN there and the run stopped at t = 0 (IDA_CONV_FAIL)."""
    fs = gf.load(TWO_ZONE)
    schemes = {f"{u}.growth_scheme": scheme for u in ("spray", "onezone")}
    run = {"warn": False, "grid_check": False, "accuracy": False}
    own = fs.with_settings({"particles.classes": 60, **schemes}).simulate(**run)
    classes = round(60 * math.log(3.2 / 0.1) / math.log(3.2 / 1.2))
    wide = fs.with_settings({"particles.classes": classes, "particles.d_min": "0.1 mm", **schemes}).simulate(**run)
    a, b = own.summary, wide.summary
    for k in ("sigma_drying_zone_um", "sigma_one_zone_um"):
        assert b[k] == pytest.approx(a[k], rel=1e-3), k
    for k in ("mean_drying_zone_um", "mean_one_zone_um", "d50_um"):
        assert b[k] == pytest.approx(a[k], rel=1e-4), k
    assert b["drying_zone_mass_kg"] == pytest.approx(a["drying_zone_mass_kg"], rel=1e-12)
    assert b["balance"]["solids_rel"] < 1e-9


# -- residence time ------------------------------------------------------------------------------------------------
def test_tanks_in_series_give_eq_7_31():
    fs = gf.load(RTD)
    r = fs.simulate()
    tau, t0, dt = 4500.0, 360.0, 60.0
    tracer = 20.0 / 3600.0 * dt  # kg per chain
    t = r.t
    for chain, n in (("a", 1), ("b", 2), ("c", 5), ("d", 10)):
        E = r[f"tank_{chain}{n}.discharge_mdot_4"] / tracer
        cdf = [gammainc(n, n * np.clip(t - s, 0, None) / tau) for s in (t0, t0 + dt)]
        exact = (cdf[0] - cdf[1]) / dt
        assert np.max(np.abs(E - exact)) * tau < 1e-7, n  # the exact response to the one-minute pulse
        tr = np.clip(t - t0 - dt / 2, 0, None) / tau
        eq731 = n ** n / math.factorial(n - 1) * tr ** (n - 1) * np.exp(-n * tr)  # Eq. (7.31), a Dirac pulse
        eq731[t < t0 + dt / 2] = 0.0  # nothing leaves before the pulse (for N = 1, tau_r^0 would read 1)
        assert np.max(np.abs(tau * E - eq731)) < 3e-4, n
        left = 1.0 - gammainc(n, n * (t[-1] - t0 - dt) / tau)  # still in the tanks at the end
        assert np.trapz(E, t) == pytest.approx(1.0 - left, abs=2e-3), n  # every tracer particle leaves once
    assert r.summary["balance"]["solids_rel"] < 1e-9


# -- the loop bench ------------------------------------------------------------------------------------------------
def test_bench_loop_runs_the_same_loop_in_granuflow_and_scipy():
    """`granuflow bench loop`: the NumPy/SciPy twin (tests/bench/scipy_sieve_mill_loop.py) solves the same equations,
    so both codes end at the steady state granuflow solves directly; the summary names both ratios."""
    from granuflow.bench_loop import bench_loop, loop_summary

    (rec,) = bench_loop(classes=(30,), repeats=1)
    assert rec["steady_method"] == "newton" and rec["steady_solids_balance_rel"] < 1e-9
    assert rec["dynamic_vs_steady_d50_rel"] < 1e-6 and rec["dynamic_vs_steady_bed_rel"] < 1e-6
    for k in ("d10_um", "d50_um", "d90_um"):
        assert rec[f"scipy_{k}"] == pytest.approx(rec[f"steady_{k}"], rel=1e-4), k
    assert rec["scipy_bed_mass_kg"] == pytest.approx(rec["steady_bed_mass_kg"], rel=1e-4)
    assert rec["steady_recycle_ratio"] > 1  # most of what leaves the bed returns to it
    assert rec["speedup_vs_scipy"] > 0 and rec["steady_speedup_vs_dynamic"] > 0
    text = "\n".join(loop_summary([rec]))
    assert "SciPy/dyn" in text and "dyn/steady" in text
