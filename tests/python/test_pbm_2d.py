"""The 2-D population of paper 002 from Python: the scene runs from the command line, the distribution read back from
a result is the unit's own (its sums are the reported number), the plots are written, a bad collision file is one
line of bad input naming the file, row and column, and `granuflow bench pbm2d` measures what issue 11 asks."""
import json
import os
import shutil

import numpy as np
import pytest
from conftest import ROOT, cli, run_bad_scene, sha256, strict_json

import granuflow as gf
from granuflow.plots import pbm2d

SCENE = os.path.join(ROOT, "flowsheets", "sen_2d_dem_kernel.yaml")
CSV = os.path.join(ROOT, "flowsheets", "data", "sen2014_collisions_example.csv")


@pytest.fixture(scope="module")
def result():
    return gf.load(SCENE).simulate()


def test_scene_runs_from_the_command_line_and_closes_its_balances(tmp_path):
    before = sha256(CSV)
    p = cli("run", SCENE, "--out", tmp_path / "out")
    assert p.returncode == 0, p.stderr
    s = strict_json(tmp_path / "out" / "summary.json")
    assert abs(s["balance"]["water_rel"]) < 1e-6 and abs(s["balance"]["solids_rel"]) < 1e-6, s["balance"]
    assert 2.5e-3 < s["D_avg_2s"] < 4e-3 and 0.3 < s["x_avg_2s"] < 0.8, s
    assert sha256(CSV) == before


def test_distribution_is_the_units_population(result):
    for t in (0.0, 1.0, 2.0):
        tt, s, ll, N = pbm2d.distribution(result, t)
        k = int(np.argmin(np.abs(result.t - t)))
        assert tt == pytest.approx(t)
        assert N.shape == (40, 40) and len(s) == 40 and len(ll) == 40
        assert N.sum() == pytest.approx(result["granulator.number"][k], rel=1e-12)
        # Eq. (16): number-weighted liquid content of the bins
        lc = ll[None, :] / (s[:, None] + ll[None, :])
        assert (N * lc).sum() / N.sum() == pytest.approx(result["granulator.x_avg"][k], rel=1e-12)
    _, s, ll, N0 = pbm2d.distribution(result, 0.0)
    assert N0[0, 0] == pytest.approx(50000)  # 2 mm primaries, dry, on the first solid pivot
    assert ll[1] == pytest.approx(np.pi / 6 * 8e-9 / 2)  # half a droplet per liquid class
    t, d, solid, edges, counts = pbm2d.marginals(result, 2.0)
    assert solid.sum() == pytest.approx(counts.sum()) == pytest.approx(result["granulator.number"][-1])
    assert d[0] == pytest.approx(2e-3)


def test_plots_are_written(result, tmp_path):
    a = pbm2d.plot_heatmaps(result, str(tmp_path / "heat.png"), times_s=[0.5, 2.0], lc_min=0.2,
                            liquid_unit_m3=np.pi / 6 * 8e-9)
    b = pbm2d.plot_marginals(result, str(tmp_path / "marginals.png"))
    for f in (a, b):
        assert os.path.getsize(f) > 10000
    with pytest.raises(ValueError, match="no 2-D population"):
        pbm2d.distribution(gf.load(os.path.join(ROOT, "flowsheets", "demo_tanks.yaml")).simulate(), 0.0)


def test_a_bad_collision_file_is_one_line_naming_file_row_and_column(tmp_path):
    os.mkdir(tmp_path / "data")
    text = open(CSV).read().replace("counts,285636,43875", "counts,285636,-43875")
    (tmp_path / "data" / "sen2014_collisions_example.csv").write_text(text)
    scene = tmp_path / "scene.yaml"
    shutil.copy(SCENE, scene)
    row = 1 + text.splitlines().index(next(x for x in text.splitlines() if "-43875" in x))
    run_bad_scene(tmp_path, scene, "units.granulator.settings.agg_collisions_file",
                  "sen2014_collisions_example.csv", f"row {row}, column 3", "must be >= 0")


def test_bench_pbm2d_measures_what_the_issue_asks():
    p = cli("bench", "pbm2d", "--quick", "--json", "--repeats", "1", timeout=300)
    assert p.returncode == 0, p.stderr
    recs = [json.loads(x) for x in p.stdout.splitlines()]
    speed = [r for r in recs if r["section"] == "speed"]
    assert {(r["code"], r["size"]) for r in speed} >= {("granuflow", 20), ("granuflow", 40), ("scipy", 20)}
    g = next(r for r in speed if r["code"] == "granuflow" and r["size"] == 20 and r["linear_solver"].startswith("g"))
    sp = next(r for r in speed if r["code"] == "scipy" and r["size"] == 20)
    assert g["D_avg"] == pytest.approx(sp["D_avg"], rel=1e-4)  # the same equations in both codes
    assert g["linear_iterations"] > 0 and g["jacobians"] == 0
    psi = [r["D_avg"] for r in recs if r["section"] == "parameters" and r["param"] == "agg_psi0"]
    assert psi == sorted(psi) and psi[-1] > psi[0] * 1.1  # stickier collisions, larger granules
    ver = [r for r in recs if r["section"] == "verification"]
    red = next(r for r in ver if "reduction" in r["check"])
    assert abs(red["err_M0"]) < 1e-8 and abs(red["marginal_vs_1d_engine"]) < 1e-8 and abs(red["err_M2"]) < 0.05
    m2 = [r["err_M2"] for r in ver if "reduction" in r["check"]]  # q = 2, 4, 8: the fixed pivot's 1/q^2
    assert len(m2) == 3 and m2[0] > 3 * m2[1] > 9 * m2[2] > 0
    dense = next(r for r in ver if "dense" in r["check"])
    assert abs(dense["solid_balance"]) < 1e-13 and abs(dense["liquid_balance"]) < 1e-13
    eff = [r for r in recs if r["section"] == "efficiency"]
    assert len(eff) == 6
