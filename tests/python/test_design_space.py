"""granuflow.design_space: contour maps, feasible windows, NLopt optimization, probabilistic design space, the Dask
executor, `granuflow contour` and `granuflow bench sweep` (correctness only; nothing asserts on time)."""
import json
import os

import numpy as np
import pytest
from conftest import SCENE

import granuflow as gf
from granuflow import design_space as ds
from granuflow import sweep

X = ("inlet.T", "degC", 40, 80, 5)
Y = ("nozzle.mdot", "g/min", 60, 120, 4)
CONSTRAINTS = {"d50_um": (">=", 400), "bed_moisture_wet": ("<", 0.04)}


@pytest.fixture(scope="module")
def fs():
    return gf.load(SCENE)


@pytest.fixture(scope="module")
def grid(fs):
    return ds.contour_map(fs, X, Y, ["d50_um", "bed_moisture_wet", "bed.T"], workers=2, progress=False)


def test_contour_grid_equals_direct_simulations(fs, grid):
    assert grid.shape == (4, 5) and grid["d50_um"].shape == (4, 5) and grid.ok.all()
    np.testing.assert_allclose(grid.x.values, np.linspace(40, 80, 5))
    np.testing.assert_allclose(grid.x.si, np.linspace(40, 80, 5) + 273.15)
    np.testing.assert_allclose(grid.y.si, np.linspace(60, 120, 4) / 6e4)
    for i, j in [(0, 0), (1, 3), (3, 4), (2, 2)]:
        ref = gf.load(SCENE).set("inlet.T", grid.x.si[j]).set("nozzle.mdot", grid.y.si[i]).simulate()
        assert grid["d50_um"][i, j] == ref.summary["d50_um"]
        assert grid["bed_moisture_wet"][i, j] == ref.summary["bed_moisture_wet"]
        assert grid["bed.T"][i, j] == ref["bed.T"][-1]
    assert fs.get("inlet.T") == 333.15 and fs.get("nozzle.mdot") == 0.0015  # the caller's flowsheet untouched
    df = grid.to_dataframe()
    assert len(df) == 20 and list(df.columns[:4]) == ["inlet.T [degC]", "nozzle.mdot [g/min]", "inlet.T [K]",
                                                      "nozzle.mdot [kg/s]"]
    assert df.attrs["units"]["d50_um"] == "um" and df.attrs["units"]["bed.T"] == "K"
    assert df["d50_um"].tolist() == grid["d50_um"].ravel().tolist()
    # paper 001 Fig. 17: d50 grows with the spray rate
    assert (np.diff(grid["d50_um"], axis=0) > 0).all()


def test_fixed_values_and_bad_axes(fs):
    g = ds.contour_map(fs, ("inlet.V_dot", "m3/h", [600, 800]), ("nozzle.mdot", "g/min", [90]), ["d50_um"],
                       fixed={"inlet.T": "80 degC"}, t_end="10 min", progress=False)
    ref = gf.load(SCENE).set("inlet.T", "80 degC").set("inlet.V_dot", "800 m3/h").simulate(t_end=600.0)
    assert g["d50_um"][0, 1] == ref.summary["d50_um"] and g.t_end_s == 600.0 and not g.steady
    with pytest.raises(gf.ConfigError, match="unknown parameter 'inlet.TT'"):
        ds.contour_map(fs, ("inlet.TT", "degC", 40, 80, 3), Y, progress=False)
    with pytest.raises(gf.ConfigError, match="outside the bounds"):
        ds.contour_map(fs, ("inlet.T", "degC", 40, 900, 3), Y, progress=False)
    with pytest.raises(gf.ConfigError, match="unit 'g/min' does not fit inlet.T"):
        ds.contour_map(fs, ("inlet.T", "g/min", 40, 80, 3), Y, progress=False)
    with pytest.raises(gf.ConfigError, match="expected unit.param:unit:lo:hi:n"):
        ds.contour_map(fs, "inlet.T:degC:40:80", Y, progress=False)
    with pytest.raises(gf.ConfigError, match="both vary"):
        ds.contour_map(fs, X, X, progress=False)


def test_feasible_window_agrees_with_the_constraints(grid):
    win = ds.feasible_window(grid, CONSTRAINTS)
    direct = (grid["d50_um"] >= 400) & (grid["bed_moisture_wet"] < 0.04)
    np.testing.assert_array_equal(win.mask, direct)
    assert 0 < win.fraction < 1 and win.outline
    assert win.mask.sum() == int(direct.sum())
    # every feasible grid point lies inside (or on) the outline, every polygon inside the grid
    from matplotlib.path import Path

    X_, Y_ = np.meshgrid(grid.x.values, grid.y.values)
    paths = [Path(r) for r in win.outline]
    for xv, yv in zip(X_[win.mask], Y_[win.mask]):
        assert any(p.contains_point((xv, yv), radius=1e-6) or p.contains_point((xv, yv), radius=-1e-6)
                   for p in paths)
    for r in win.outline:
        assert r[:, 0].min() >= 40 - 1e-9 and r[:, 0].max() <= 80 + 1e-9
    same = ds.feasible_window(grid, ["d50_um>=400", "bed_moisture_wet<0.04"])
    np.testing.assert_array_equal(same.mask, win.mask)
    assert set(win.to_dataframe().columns) >= {"inlet.T [degC]", "feasible", "margin[d50_um >= 400]"}
    with pytest.raises(gf.ConfigError, match="not an output of the grid"):
        ds.feasible_window(grid, {"d90_um": ("<", 900)})
    with pytest.raises(gf.ConfigError, match="expected OUTPUT OP NUMBER"):
        ds.parse_constraints(["d50_um => 400"])


def test_plots_write_png(grid, tmp_path):
    win = ds.feasible_window(grid, CONSTRAINTS)
    for p in (ds.plot_contour(grid, "d50_um", str(tmp_path / "c.png"), window=win),
              ds.plot_feasible_window(win, str(tmp_path / "w.png"), grid=grid, background="d50_um")):
        assert open(p, "rb").read(8) == b"\x89PNG\r\n\x1a\n"


def test_optimizer_finds_a_feasible_point_better_than_the_centre(fs):
    pytest.importorskip("nlopt", reason="Debian python3-nlopt")
    variables = [("nozzle.mdot", "g/min", 60, 120), ("inlet.T", "degC", 40, 80)]
    res = ds.optimize(fs, "nozzle.mdot", variables, CONSTRAINTS, maximize=True, algorithm="LN_COBYLA",
                      x0={"nozzle.mdot": 90, "inlet.T": 60}, maxeval=80)
    assert res.feasible and res.nlopt_result in ("XTOL_REACHED", "FTOL_REACHED", "SUCCESS", "MAXEVAL_REACHED")
    assert res.x["nozzle.mdot"] > 90  # the centre point's spray rate
    assert 60 <= res.x["nozzle.mdot"] <= 120 and 40 <= res.x["inlet.T"] <= 80
    assert 0 < res.n_simulations <= 80 and len(res.history) == res.n_simulations
    ref = gf.load(SCENE).set("nozzle.mdot", res.x_si["nozzle.mdot"]).set("inlet.T", res.x_si["inlet.T"]).simulate()
    assert res.constraints["d50_um >= 400"]["value"] == pytest.approx(ref.summary["d50_um"], rel=1e-12)
    assert ref.summary["d50_um"] >= 400 and ref.summary["bed_moisture_wet"] < 0.04
    # a global algorithm (few evaluations) also returns a feasible point within the bounds
    glob = ds.optimize(fs, "nozzle.mdot", variables, CONSTRAINTS, maximize=True, algorithm="GN_ISRES", maxeval=60)
    assert glob.feasible and glob.nlopt_result == "MAXEVAL_REACHED"
    assert 60 <= glob.x["nozzle.mdot"] <= 120 and 40 <= glob.x["inlet.T"] <= 80


def test_invalid_algorithms_are_clear_errors(fs):
    pytest.importorskip("nlopt", reason="Debian python3-nlopt")
    v = [("nozzle.mdot", "g/min", 60, 120)]
    with pytest.raises(gf.ConfigError, match=r"algorithm = 'LN_FOO': unknown NLopt algorithm \(local: .*LN_COBYLA"):
        ds.optimize(fs, "nozzle.mdot", v, CONSTRAINTS, algorithm="LN_FOO")
    with pytest.raises(gf.ConfigError, match="GN_ISRES"):
        ds.optimize(fs, "nozzle.mdot", v, CONSTRAINTS, algorithm="nonsense")
    with pytest.raises(gf.ConfigError, match="LN_BOBYQA does not take constraints.*AUGLAG"):
        ds.optimize(fs, "nozzle.mdot", v, CONSTRAINTS, algorithm="LN_BOBYQA")
    with pytest.raises(gf.ConfigError, match="local_algorithm = 'LN_FOO'"):
        ds.optimize(fs, "nozzle.mdot", v, CONSTRAINTS, algorithm="AUGLAG", local_algorithm="LN_FOO")
    with pytest.raises(gf.ConfigError, match="is a parameter that is not a variable|that is not a variable"):
        ds.optimize(fs, "inlet.T", v, CONSTRAINTS)


def test_probabilistic_map_is_a_probability_and_saturates_far_from_the_bounds(fs):
    params = ["bed.agg_ln_beta0", "bed.X_cr"]
    cov = [[0.05 ** 2, 0.0], [0.0, 0.003 ** 2]]
    x, y = ("inlet.T", "degC", [45, 75]), ("nozzle.mdot", "g/min", [62, 80, 118])
    pm = ds.probabilistic_design_space(fs, x, y, CONSTRAINTS, params=params, covariance=cov, progress=False)
    P = pm.probability
    assert P.shape == (3, 2) and ((P >= 0) & (P <= 1)).all() and pm.n_failed == 0
    nominal = ds.feasible_window(pm, CONSTRAINTS)
    z = np.min(np.stack([(pm.values["d50_um"] - 400) / pm.sigma["d50_um"],
                         (0.04 - pm.values["bed_moisture_wet"]) / pm.sigma["bed_moisture_wet"]]), axis=0)
    far = np.abs(z) > 6
    assert far.any()
    np.testing.assert_array_equal(P[far], nominal.mask[far].astype(float))  # exactly 0 or 1
    # the nominal values are those of the grid at the mean parameters
    g = ds.contour_map(fs, x, y, ["d50_um"], progress=False)
    np.testing.assert_array_equal(pm.values["d50_um"], g["d50_um"])
    # finite differences agree with the sensitivities; Monte Carlo is a probability and agrees far out
    fd = ds.probabilistic_design_space(fs, x, y, CONSTRAINTS, params=params, covariance=cov, progress=False,
                                       sensitivities="fd")
    np.testing.assert_allclose(fd.sigma["d50_um"], pm.sigma["d50_um"], rtol=0.15)
    mc = ds.probabilistic_design_space(fs, x, y, CONSTRAINTS, params=params, covariance=cov, progress=False,
                                       method="monte_carlo", n_samples=8, workers=2)
    assert mc.n_simulations == 48 and ((mc.probability >= 0) & (mc.probability <= 1)).all()
    np.testing.assert_array_equal(mc.probability[far], P[far])
    with pytest.raises(gf.ConfigError, match="symmetric 2x2"):
        ds.probabilistic_design_space(fs, x, y, CONSTRAINTS, params=params, covariance=[[1, 0]], progress=False)


def test_dask_local_cluster_reproduces_threads_exactly(fs, grid):
    distributed = pytest.importorskip("distributed", reason="Debian python3-distributed")
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None,
                                  silence_logs=40) as cluster, distributed.Client(cluster) as client:
        g = ds.contour_map(fs, X, Y, ["d50_um", "bed_moisture_wet", "bed.T"], executor=client, progress=False)
        for o in grid.outputs:
            np.testing.assert_array_equal(g[o], grid[o])
        assert g.message.tolist() == grid.message.tolist() and g.status.tolist() == grid.status.tolist()
        assert len(client.nthreads()) == 2
        # the generic runner takes the client as it is, also for a flowsheet with changed parameters
        mod = gf.load(SCENE).set("inlet.V_dot", "650 m3/h")
        pts = [{"nozzle.mdot": "70 g/min"}, {"nozzle.mdot": "110 g/min"}]
        a = sweep.run_sweep(mod, pts, ["d50_um"], executor=client, progress=False)
        b = sweep.run_sweep(mod, pts, ["d50_um"], executor="serial", progress=False)
        np.testing.assert_array_equal(a["d50_um"].to_numpy(), b["d50_um"].to_numpy())
        # each Dask task solves its chunk in the core (granuflow.sweep.batch): the rows of the per-point path
        c = sweep.run_sweep(mod, pts, ["d50_um", "d90_um"], executor=client, progress=False, batch=False)
        d = sweep.run_sweep(mod, pts, ["d50_um", "d90_um"], executor=client, progress=False)
        for col in ("d50_um", "d90_um", "nozzle.mdot", "status", "message"):
            assert c[col].astype(str).tolist() == d[col].astype(str).tolist()


def test_contour_cli(tmp_path, capsys):
    from granuflow import cli

    out = tmp_path / "c"
    rc = cli.main(["contour", SCENE, "--x", "inlet.T:degC:50:80:3", "--y", "nozzle.mdot:g/min:60:100:3",
                   "--constraint", "d50_um>=400", "--constraint", "bed_moisture_wet<0.04", "--out", str(out),
                   "--workers", "2", "--quiet"])
    assert rc == 0
    files = set(os.listdir(out))
    assert {"contour.csv", "contour.json", "feasible_window.csv", "feasible_window.png",
            "contour_d50_um.png", "contour_bed_moisture_wet.png"} <= files
    meta = json.load(open(out / "contour.json"))
    assert meta["n_points"] == 9 and meta["n_failed"] == 0 and meta["outputs"] == ["d50_um", "bed_moisture_wet"]
    import pandas as pd

    df = pd.read_csv(out / "contour.csv")
    assert {"inlet.T [degC]", "inlet.T [K]", "nozzle.mdot [g/min]", "nozzle.mdot [kg/s]"} <= set(df.columns)
    assert df["inlet.T [K]"].to_numpy() == pytest.approx(df["inlet.T [degC]"].to_numpy() + 273.15)
    assert meta["units"] == {"d50_um": "um", "bed_moisture_wet": "kg/kg"}
    direct = (df["d50_um"] >= 400) & (df["bed_moisture_wet [kg/kg]"] < 0.04)
    assert len(df) == 9 and df["feasible"].tolist() == direct.tolist()
    for bad in (["--x", "inlet.T:degC:50:80"], ["--x", "inlet.T:degC:50:80:3", "--constraint", "d50_um=>4"],
                ["--x", "inlet.T:degC:50:900:3"]):
        argv = ["contour", SCENE, "--y", "nozzle.mdot:g/min:60:100:2", "--out", str(out), *bad]
        assert cli.main(argv) == 2
    err = capsys.readouterr().err
    assert err.count("granuflow: bad input:") == 3


def test_bench_sweep_records_without_timing_assertions():
    from granuflow import bench

    recs = bench.bench_sweep(n=3, repeats=1, dask=False)
    assert [r["mode"] for r in recs] == ["threads", "threads_2"]
    for r in recs:
        assert r["simulations"] == 9 and r["same_values_as_1_worker"] and r["sims_per_s"] > 0
        assert len(r["loadavg_before"]) == 3 and r["commit"] is not None
    assert recs[0]["parallel_efficiency"] == 1.0
    assert "simulations/s" in "\n".join(bench.sweep_summary(recs))
