"""Relative data paths in a scene resolve against the scene file, also in the copies granuflow makes of it."""
import os

import granuflow as gf

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def test_a_refined_copy_reads_the_scenes_data_from_any_working_folder(tmp_path, monkeypatch):
    # The 2-D scene names its collision table relative to itself (data/...); the refined copies of the error
    # estimate read it from the working folder before, so outside flowsheets/ they failed and the grid went unchecked.
    monkeypatch.chdir(tmp_path)
    fs = gf.load(os.path.join(ROOT, "flowsheets", "sen_2d_dem_kernel.yaml"))
    fine = fs.refined(2)
    assert fine.grid()["classes"] != fs.grid()["classes"]
    r = fine.simulate(t_end=0.5, n_out=2, warn=False)
    assert r.t[-1] == 0.5
