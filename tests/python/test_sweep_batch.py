"""granuflow.sweep.batch: sweep points solved and reduced in the C++ core give the rows of the per-point Python path
(Flowsheet.simulate, final_values, Result.warnings) bit for bit: values, nulls, warnings and failures."""
import numpy as np
import pytest
from conftest import SCENE

import granuflow as gf
from granuflow import sweep
from granuflow.sweep import batch

OUTPUTS = ["d50_um", "d90_um", "d10_um", "bed_moisture_wet", "T_gas_out_K", "bed.T", "bed.top_class_fraction"]


def _same_rows(a, b):
    assert list(a.columns) == list(b.columns)
    for c in a.columns:
        if c in ("wall_time_s", "solve_time_s"):
            assert np.isnan(a[c].to_numpy()).tolist() == np.isnan(b[c].to_numpy()).tolist()
        elif a[c].dtype == float:  # float.hex tells -0.0 from 0.0 and NaN from a number
            assert [x.hex() for x in a[c]] == [x.hex() for x in b[c]], c
        else:
            assert a[c].tolist() == b[c].tolist(), c


def test_batch_rows_equal_the_per_point_path_with_nulls_warnings_and_failures():
    fs = gf.load(SCENE)
    # 2 x 2 operating points after 60 min (d90 lies in the top size class: null with a warning), one whose inlet
    # temperature is out of bounds (refused when set) and the scene's base point
    points = [{"inlet.T": t, "nozzle.mdot": m} for t in (313.15, 353.15) for m in (0.001, 0.002)]
    points += [{"inlet.T": 2000.0, "nozzle.mdot": 0.001}, {}]
    ev = batch.batch_evaluator(fs, points, ["inlet.T", "nozzle.mdot"], {"inlet.T": 333.15, "nozzle.mdot": 0.0015},
                               OUTPUTS, {"n_out": 2})
    assert ev is not None  # this scene and these points go through the core
    kw = dict(outputs=OUTPUTS, progress=False, simulate={"n_out": 2})
    fast = sweep.run_sweep(fs, points, workers=2, **kw)
    slow = sweep.run_sweep(fs, points, workers=2, batch=False, **kw)
    _same_rows(fast, slow)
    assert fast["status"].tolist() == ["ok"] * 4 + ["failed", "ok"]
    assert "inlet.T" in fast["message"][4] and np.isnan(fast["d50_um"][4])
    # at the higher spray rate d90 lies in the top size class: null, and said so; every point warns of the grid end
    assert np.isnan(fast["d90_um"]).tolist() == [False, True, False, True, True, True]
    assert ["d90 lies in the top size class" in m for m in fast["message"]] == [False, True, False, True, False, True]
    assert all(m.startswith("warning: bed: ") and "top size class (1000 um)" in m for m in fast["message"][:4])
    assert (fast["d50_um"][:4] > 200).all() and (np.diff(fast["d50_um"][:2]) > 0).all()
    # one thread or the serial executor: the same rows
    _same_rows(sweep.run_sweep(fs, points, executor="serial", **kw), fast)
    # initial distributions outside the grid (in its top, then its bottom class) and a loose tolerance whose water
    # balance closes worse than it explains: the warnings of both ends and of the balance guard
    pts = [{"bed.d50_0": 9e-4}, {"bed.d50_0": 6e-5}]
    kw["simulate"] = {"n_out": 2, "rtol": 0.03, "atol": 0.1}
    fast, slow = (sweep.run_sweep(fs, pts, batch=b, **kw) for b in (True, False))
    _same_rows(fast, slow)
    assert ["initial size distribution lies outside the grid" in m for m in fast["message"]] == [True, True]
    assert "top size class" in fast["message"][0] and "bottom size class (50 um)" in fast["message"][1]
    assert "warning: balance: the water balance closes only to" in fast["message"][1]
    # a solver that gives up (too few steps) fails every point with the core's message, on either path
    kw["simulate"] = {"n_out": 2, "max_steps": 5}
    fast, slow = (sweep.run_sweep(fs, points[:1], batch=b, **kw) for b in (True, False))
    _same_rows(fast, slow)
    assert fast["status"][0] == "failed" and "IDA_TOO_MUCH_WORK" in fast["message"][0]


def test_batch_is_left_to_the_per_point_path_where_it_cannot_match():
    fs = gf.load(SCENE)
    args = (["inlet.T"], {"inlet.T": 333.15}, ["d50_um"])
    assert batch.batch_evaluator(fs, [{"inlet.T": "60 degC"}], *args, {}) is None  # parsed per point
    assert batch.batch_evaluator(fs, [{"inlet.T": True}], *args, {}) is None
    assert batch.batch_evaluator(fs, [{"inlet.T": 330.0}], *args, {"t_end": "10 min"}) is None
    assert batch.batch_evaluator(fs, [{"inlet.T": 330.0}], *args, {"sensitivities": ["inlet.T"]}) is None
    # with a progress callback (the calling thread reports while two others solve): the same rows
    ev, seen = batch.BatchEvaluate(*args, {"t_end": 60.0}), []
    items = [(i, {"inlet.T": 320.0 + 5 * i}) for i in range(4)]

    def untimed(rows):
        return [{k: v for k, v in r.items() if not k.endswith("time_s")} for r in rows]
    plain = untimed(ev.batch([fs.clone(), fs.clone()], items))
    ev.on_progress = seen.append
    assert untimed(ev.batch([fs.clone(), fs.clone()], items)) == plain
    assert seen == sorted(seen) and all(0 <= k <= 4 for k in seen) and [r["_i"] for r in plain] == [0, 1, 2, 3]
    with pytest.raises(gf.ConfigError, match="the same scene: give each thread its own clone"):
        batch.BatchEvaluate(*args, {}).batch([fs, fs], [(0, {"inlet.T": 330.0})])
    assert batch.batch_evaluator(fs.with_settings({"particles.classes": 12}), [{"inlet.T": 330.0}], *args,
                                 {"t_end": 60.0}) is not None
