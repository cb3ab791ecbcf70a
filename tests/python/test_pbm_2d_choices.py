"""Paper 002's open choices in the 2-D population (issue 30, section 3), each on the shipped scene: what it must change
physically, and that the defaults are today's model. Also the bound on N0 (issue 29): a population far beyond the
DEM run's is refused at once instead of grinding."""
import os
import time

import numpy as np
import pytest
from conftest import ROOT, assert_bad_input, cli, run_bad_scene, sha256

import granuflow as gf
from granuflow.plots import pbm2d

SCENE = os.path.join(ROOT, "flowsheets", "sen_2d_dem_kernel.yaml")
CSV = os.path.join(ROOT, "flowsheets", "data", "sen2014_collisions_example.csv")


def scene(folder, settings=None, like="like_collisions,twice\n"):
    """A copy of the shipped scene (and its collision file, its like_collisions row replaced by `like`) in `folder`,
    with unit settings added; continuous liquid has no droplet size."""
    os.makedirs(folder / "data", exist_ok=True)
    csv = open(CSV).read()
    assert "like_collisions,twice\n" in csv
    (folder / "data" / os.path.basename(CSV)).write_text(csv.replace("like_collisions,twice\n", like))
    text = open(SCENE).read()
    for key, value in (settings or {}).items():
        if key != "spray":
            text = text.replace("      psd_classes: 16\n", f"      psd_classes: 16\n      {key}: {value}\n")
    if (settings or {}).get("spray") == "continuous":
        text = text.replace("spray: droplets", "spray: continuous").replace("      d_drop: 2 mm\n", "")
    path = folder / "scene.yaml"
    path.write_text(text)
    return path


def run(folder, settings=None, like="like_collisions,twice\n"):
    return gf.load(scene(folder, settings, like)).simulate()


def liquid_spread(result, t=2.0):
    """(number fraction on odd liquid classes, standard deviation of the liquid volume per particle) at t."""
    _, _, ll, N = pbm2d.distribution(result, t)
    n, marginal = N.sum(), N.sum(axis=0)
    mean = (marginal * ll).sum() / n
    return marginal[1::2].sum() / n, np.sqrt((marginal * (ll - mean) ** 2).sum() / n)


def liquid_held(result):
    """Liquid on the grid and off it at the end, m3."""
    return result["granulator.liquid_volume"][-1] + result["granulator.liquid_left_grid"][-1] / 1000.0


@pytest.fixture(scope="module")
def shipped():
    return gf.load(SCENE).simulate()


def test_defaults_spelled_out_are_the_shipped_model(shipped, tmp_path):
    r = run(tmp_path, {"spray_weight": "number", "psd_diameter": "total"})
    for out in ("D_avg", "x_avg", "d50", "number"):
        assert np.array_equal(r[f"granulator.{out}"], shipped[f"granulator.{out}"]), out


def test_continuous_liquid_fills_every_liquid_class_and_narrows_the_liquid_distribution(shipped, tmp_path):
    r = run(tmp_path, {"spray": "continuous"})
    odd_d, sd_d = liquid_spread(shipped)
    odd_c, sd_c = liquid_spread(r)
    # droplets of two liquid steps land on even classes only; a continuous flow passes through every class
    assert odd_d < 1e-12 and odd_c > 0.3, (odd_d, odd_c)
    # the same liquid, spread more evenly over the particles: a narrower distribution, a higher mean content
    assert liquid_held(r) == pytest.approx(liquid_held(shipped), rel=1e-9)
    assert abs(r["granulator.liquid_balance"][-1]) < 1e-12
    assert sd_c < 0.9 * sd_d, (sd_c, sd_d)
    assert r["granulator.x_avg"][-1] > shipped["granulator.x_avg"][-1]


def test_without_aggregation_liquid_arrives_in_quanta_of_a_droplet_or_of_a_liquid_class(tmp_path):
    # every particle alike: the liquid per particle is a Poisson count of quanta, variance = quantum x mean; droplets
    # of two liquid classes, the continuous flow's upwind steps of one (docs/pbm_2d.md)
    for spray, quanta in (("droplets", 2.0), ("continuous", 1.0)):
        path = scene(tmp_path / spray, {"spray": spray})
        path.write_text(path.read_text().replace("agg_psi0: 0.01", "agg_psi0: 0"))
        _, _, ll, N = pbm2d.distribution(gf.load(path).simulate(), 1.0)
        m = N.sum(axis=0)
        mean = (m * ll).sum() / m.sum()
        var = (m * (ll - mean) ** 2).sum() / m.sum()
        assert var / (ll[1] * mean) == pytest.approx(quanta, rel=1e-6), spray


def test_sharing_by_surface_gives_the_larger_particles_more_liquid(shipped, tmp_path):
    for spray in ("droplets", "continuous"):
        by_number = shipped if spray == "droplets" else run(tmp_path / "n", {"spray": spray})
        by_surface = run(tmp_path / spray, {"spray": spray, "spray_weight": "surface"})
        assert liquid_held(by_surface) == pytest.approx(liquid_held(by_number), rel=1e-9)
        # the wetter (larger) particles draw more of the liquid: the liquid per particle spreads wider
        assert liquid_spread(by_surface)[1] > 1.05 * liquid_spread(by_number)[1], spray
    with pytest.raises(gf.ConfigError, match=r"spray_weight = 'cross_section': needs spray: droplets"):
        gf.load(scene(tmp_path / "x", {"spray": "continuous", "spray_weight": "cross_section"}))


def test_size_classes_by_solid_diameter_move_only_the_size_distribution(shipped, tmp_path):
    r = run(tmp_path, {"psd_diameter": "solid"})
    for out in ("D_avg", "x_avg", "number"):  # Eqs. (15)-(16) keep solid plus liquid
        assert np.array_equal(r[f"granulator.{out}"], shipped[f"granulator.{out}"]), out
    assert r["granulator.d50"][0] == shipped["granulator.d50"][0]  # dry at the start: one diameter
    assert r["granulator.d50"][-1] < 0.8 * shipped["granulator.d50"][-1]  # wet at the end: the liquid left out


def test_like_collisions_counted_once_double_their_rate(shipped, tmp_path):
    r = run(tmp_path, like="like_collisions,once\n")
    assert r["granulator.number"][-1] < shipped["granulator.number"][-1] * 0.95
    assert r["granulator.D_avg"][-1] > shipped["granulator.D_avg"][-1] * 1.02


def test_a_collision_file_that_does_not_say_how_it_counts_is_refused(tmp_path):
    path = scene(tmp_path, like="")
    data = tmp_path / "data" / os.path.basename(CSV)
    before = sha256(data)
    run_bad_scene(tmp_path, path, "agg_collisions_file", "no 'like_collisions' row", "like_collisions,twice")
    assert sha256(data) == before


def test_n0_beyond_the_dem_population_is_refused_at_once(tmp_path):
    start = time.monotonic()
    p = cli("run", SCENE, "--set", "granulator.N0=1e30", "--out", tmp_path / "out", "--no-plots", timeout=60)
    assert_bad_input(p, "N0 = 1e+30", "N0 <= 51600", "sen2014_collisions_example.csv")
    assert time.monotonic() - start < 30
