"""Checkpoints (docs/events_and_checkpoints.md): a run restarted from a checkpoint file gives the results of the
uninterrupted run with the same checkpoint times bit for bit (states, outputs, sensitivities, events); a checkpoint
of another scene is refused with one line."""
import os

import numpy as np
import pytest
from conftest import DEMO, ROOT, SCENE, assert_bad_input, cli

import granuflow as gf

RECIPE = os.path.join(ROOT, "flowsheets", "stoeckl_gf25_recipe.yaml")
FAST = dict(warn=False, grid_check=False, accuracy=False)


def _same(a, b):
    for k in ("t", "y", "yp", "outputs", "sens", "output_sens"):
        x, y = getattr(a, k), getattr(b, k)
        assert x.shape == y.shape, k
        assert np.array_equal(x, y, equal_nan=True), (k, np.nanmax(np.abs(x - y)))


@pytest.mark.parametrize("scene, at, sens", [(SCENE, [1200.0, 2400.0], ["inlet.V_dot"]),
                                             (RECIPE, [600.0, 1500.0], [])])
def test_restart_is_bit_identical(tmp_path, scene, at, sens):
    fs = gf.load(scene)
    full = fs.simulate(checkpoints=at, checkpoint_dir=str(tmp_path), sensitivities=sens, **FAST)
    assert [os.path.basename(f) for f in full.checkpoint_files] == [f"checkpoint_{t:g}s.gfckpt" for t in at]
    for f in full.checkpoint_files:
        again = gf.load(scene).simulate(checkpoints=at, restart=f, sensitivities=sens, **FAST)
        _same(full, again)
        assert again.events == full.events
    # the checkpoints are breakpoints: the run with them restarts its integrator there
    assert full.stats["reinits"] >= len(at)


def test_restart_across_events_reapplies_their_actions(tmp_path):
    """A checkpoint after stop_spray: the restarted run keeps the spray off (the event's action) and fires the
    remaining events at the same times."""
    full = gf.load(RECIPE).simulate(checkpoints=[1500.0], checkpoint_dir=str(tmp_path), **FAST)
    assert full.events[0]["t"] < 1500.0 < full.events[1]["t"]
    again = gf.load(RECIPE).simulate(checkpoints=[1500.0], restart=full.checkpoint_files[0], **FAST)
    assert [e["t"] for e in again.events] == [e["t"] for e in full.events]
    assert np.all(again["nozzle.mdot"][again.t > 1500.0] == 0.0)


def test_checkpoint_of_another_scene_is_refused(tmp_path):
    full = gf.load(SCENE).simulate(checkpoints=[600.0], checkpoint_dir=str(tmp_path), **FAST)
    with pytest.raises(gf.ConfigError, match="written by scene 'stoeckl_gf25_batch'.*restarts only the scene"):
        gf.load(DEMO).simulate(restart=full.checkpoint_files[0], **FAST)
    # the same scene with other sensitivities has another structure
    with pytest.raises(gf.ConfigError, match="restarts only the scene"):
        gf.load(SCENE).simulate(restart=full.checkpoint_files[0], sensitivities=["inlet.T"], **FAST)


def test_cli_checkpoint_and_restart(tmp_path):
    a, b = tmp_path / "a", tmp_path / "b"
    p = cli("run", SCENE, "--out", a, "--no-plots", "--no-grid-check", "--checkpoint-at", "20 min")
    assert p.returncode == 0, p.stderr
    ckpt = a / "checkpoint_1200s.gfckpt"
    assert ckpt.exists()
    p = cli("run", SCENE, "--out", b, "--no-plots", "--no-grid-check", "--checkpoint-at", "20 min", "--restart", ckpt)
    assert p.returncode == 0, p.stderr
    assert (a / "timeseries.csv").read_text() == (b / "timeseries.csv").read_text()
    bad = tmp_path / "bad.gfckpt"
    bad.write_text("not a checkpoint")
    p = cli("run", SCENE, "--out", tmp_path / "c", "--no-plots", "--restart", bad)
    assert_bad_input(p, "restart", "not a granuflow checkpoint file")
