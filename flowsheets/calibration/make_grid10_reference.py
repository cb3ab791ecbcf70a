"""Regenerates grid10_gf25_table1.yaml and its CSV files: the "measurements" against which the converged-grid
variant of the headline scene (stoeckl_gf25_batch_converged.yaml, 80 size classes) is refitted (issue 28, §5).

The paper's real Table-1 measurements are not published; what its parameters (Tables 8-10) reproduce is the
10-class model. So the data are the headline scene on its 10-class grid with the paper's parameters, at the 15
runs of paper 001, Table 1, every 5 min to 60 min, WITHOUT noise: a refit on 80 classes then shows only what the
grid changes. The experiment file names the converged scene, so that `granuflow calibrate` fits the 80-class
model to the 10-class trajectories (stages_grid_converged.yaml):

    PYTHONPATH=build/python python3 flowsheets/calibration/make_grid10_reference.py
    build/granuflow calibrate flowsheets/calibration/grid10_gf25_table1.yaml \\
        --stages flowsheets/calibration/stages_grid_converged.yaml --out out/grid_converged

`--runs K --out FILE` writes a smaller problem (the first K runs) elsewhere, for tests. `--summarize REPORT.json`
writes grid_converged_fit.json from the calibration's report (each parameter's paper value, refit and standard
error; the d50 residual of the converged scene against the data over all 15 runs), which notebook 11 and
tests/python/test_grid_converged.py read.
"""
import argparse
import json
import os

import numpy as np

from granuflow import calibration as cal, load

HERE = os.path.dirname(os.path.abspath(__file__))
SCENE_10 = os.path.join(HERE, "..", "stoeckl_gf25_batch.yaml")
SCENE_CONVERGED = os.path.join(HERE, "..", "stoeckl_gf25_batch_converged.yaml")


def experiments(runs: int | None = None, workers: int = 2) -> "cal.ExperimentSet":
    """The 10-class model's trajectories at the Table-1 points (all 15, or the first `runs`), noise free, as an
    experiment set on the converged scene."""
    fs = load(SCENE_10)
    points = cal.table1_points()
    if runs is not None:
        points = points[:runs]
    es = cal.synthetic_experiments(fs, points, noise=False, name="grid10_gf25_table1", workers=workers)
    es.scene = os.path.normpath(SCENE_CONVERGED)
    es.description = ("the headline scene on the paper's 10-class grid with the paper's parameters (Tables 8-10) at "
                      "the Table-1 runs, noise free: data for refitting the kinetics on a converged grid "
                      "(make_grid10_reference.py)")
    return es


def summarize(report_path: str, out: str) -> dict:
    """The refit in brief: per parameter the paper's value (the start), the refit and its standard error; the
    relative d50 residual of the converged scene (with the values it holds) against the data of every run."""
    rep = json.load(open(report_path))
    stage = rep["result"]["stages"][-1]
    params = {e["name"]: {"paper": e["start"], "refit": e["value"], "std_error": e["se"]} for e in stage["estimates"]}
    es = cal.load_experiments(os.path.join(HERE, "grid10_gf25_table1.yaml"))
    fs = es.flowsheet()
    for name, p in params.items():  # the scene must hold the refit (its comment cites this file)
        if not np.isclose(fs.get(name), p["refit"], rtol=1e-3):
            raise SystemExit(f"{name}: the converged scene holds {fs.get(name)!r}, the fit gave {p['refit']!r}")
    rel = []
    for q in cal.predict(fs, es.experiments):
        if q["observable"] == "bed.d50":
            rel += list(np.asarray(q["model"]) / np.asarray(q["data"]) - 1)
    rel = np.asarray(rel)
    doc = {"command": "build/granuflow calibrate flowsheets/calibration/grid10_gf25_table1.yaml --stages "
                      "flowsheets/calibration/stages_grid_converged.yaml --out DIR",
           "classes": int(fs.grid()["classes"]), "stage": stage["name"], "cost": stage["cost"],
           "iterations": stage["iterations"], "chi2_reduced": stage["chi2_reduced"], "parameters": params,
           "d50_rel_residual": {"rms": float(np.sqrt(np.mean(rel ** 2))), "max": float(np.max(np.abs(rel))),
                                "runs": len(es.experiments)}}
    with open(out, "w") as f:
        json.dump(doc, f, indent=2)
        f.write("\n")
    return doc


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--runs", type=int, default=None, help="only the first RUNS Table-1 runs (default: all 15)")
    ap.add_argument("--out", default=os.path.join(HERE, "grid10_gf25_table1.yaml"), help="experiment file to write")
    ap.add_argument("--summarize", metavar="REPORT_JSON",
                    help="write grid_converged_fit.json from a calibration report")
    args = ap.parse_args()
    if args.summarize:
        print(json.dumps(summarize(args.summarize, os.path.join(HERE, "grid_converged_fit.json")), indent=2))
        raise SystemExit(0)
    cal.save_experiments(experiments(args.runs), args.out, csv_dir=os.path.splitext(os.path.basename(args.out))[0])
    print(f"wrote {args.out}")
