"""`granuflow bench pbm`: valid work-precision records and a readable summary (correctness only; benchmarks never
assert on time)."""
import json
import math
import os
import re
import subprocess
import sys

import pytest
from conftest import ROOT, SCENE, cli, package_env

import granuflow as gf
from granuflow import bench

CASES = {"constant", "sum", "product", "growth", "breakage"}


@pytest.fixture(scope="module")
def records():
    # tests/bench is built with the tests: a missing executable is a broken build, not a reason to skip
    bench.pbm_executable()
    p = cli("bench", "pbm", "--json", "--quick", "--repeats", "1", timeout=300)
    assert p.returncode == 0, p.stderr
    lines = p.stdout.splitlines()
    assert lines and all(line.startswith("{") for line in lines), p.stdout[:500]
    return [json.loads(line) for line in lines]


def test_records_have_the_required_keys(records):
    for r in records:
        missing = [k for k in bench.PBM_KEYS if k not in r and not (k == "integrator" and r["code"] == "scipy")]
        assert not missing, (missing, r)
        assert r["code"] in ("granuflow", "scipy")
        assert r["case"] in CASES and r["q"] in (1, 2, 4) and r["rtol"] in (1e-2, 1e-4, 1e-6)
        assert r["classes"] == r["q"] * (19 if r["case"] == "growth" else 27)
        assert r["solve_ms"] > 0 and r["repeats"] == 1
        for k in ("err_M0", "err_M2", "mass_drift"):
            assert isinstance(r[k], (int, float)) and math.isfinite(r[k]), (k, r)  # %g prints 0 as 0
        assert (r["err_L1"] is None) == (r["case"] == "product"), r
    methods = {(r["case"], r["method"]) for r in records if r["code"] == "granuflow"}
    assert methods == {(c, m) for c in CASES - {"growth"} for m in ("cell_average", "fixed_pivot")} | {
        ("growth", "fv_koren"), ("growth", "fv_upwind")}
    # 4 integrators x 3 grids x 3 tolerances each
    assert len(methods) * 36 == sum(r["code"] == "granuflow" for r in records)
    assert {r["integrator"] for r in records if r["code"] == "granuflow"} == {"auto", "ida", "adams", "erk"}
    # auto: an explicit or Adams method for aggregation (non-stiff), BDF for the breakage case
    ran = {(r["case"], r["integrator_ran"]) for r in records if r.get("integrator") == "auto"}
    assert {m for c, m in ran if c in ("constant", "sum", "product")} <= {"erk", "adams"}
    assert {m for c, m in ran if c == "breakage"} == {"bdf"}  # selection rates up to 3e4 /s: stiff
    assert {r["method"] for r in records if r["code"] == "scipy"} == {
        "scipy_fp_BDF", "scipy_fp_LSODA", "scipy_upwind_BDF", "scipy_upwind_LSODA"}


def test_granuflow_conserves_mass_to_round_off(records):
    for r in records:
        if r["code"] == "granuflow":
            assert abs(r["mass_drift"]) < 1e-12, r


def test_granuflow_fixed_pivot_matches_the_scipy_baseline(records):
    """The same discretization in both codes: the errors agree to the integration tolerance."""
    mine = {(r["case"], r["q"], r["rtol"]): r for r in records
            if r["method"] in ("fixed_pivot", "fv_upwind") and r.get("integrator") == "ida"}
    compared = 0
    for s in records:
        if s["method"].endswith("LSODA") and s["rtol"] == 1e-6:
            g = mine[(s["case"], s["q"], s["rtol"])]
            assert g["err_M2"] == pytest.approx(s["err_M2"], abs=1e-3 * (1 + abs(s["err_M2"]))), (g, s)
            compared += 1
    # every case on every grid of --quick (q = 1, 2, 4) has a SciPy LSODA twin at rtol 1e-6
    assert compared == len(CASES) * 3, compared


def test_summary_and_speed_ratio_script(records, tmp_path):
    path = tmp_path / "pbm.jsonl"
    path.write_text("".join(json.dumps(r) + "\n" for r in records))
    p = subprocess.run([sys.executable, os.path.join(ROOT, "tests", "bench", "pbm_speed_ratio.py"), str(path)],
                       capture_output=True, text=True, env=package_env(), timeout=60)
    assert p.returncode == 0, p.stderr
    assert len(p.stdout.splitlines()) == len(CASES) * len(bench.PBM_LEVELS)
    # the cheapest run that meets the target: one of the two schemes, whichever timed faster here
    assert re.search(r"constant  \|err_M2\| <= 0\.05:  granuflow: (cell_average|fixed_pivot)/", p.stdout), p.stdout
    text = "\n".join(bench.pbm_summary(records))
    for heading in ("Work-precision envelope", "Speed at equal error vs SciPy LSODA", "Same discretization",
                    "What solver.method auto ran", "Targets"):
        assert heading in text
    assert "constant  scipy_fp_LSODA" in text


def test_speed_ratio_at_equal_error():
    def rec(code, method, err, ms, case="constant"):
        return {"code": code, "case": case, "method": method, "q": 1, "rtol": 1e-6, "err_M2": err, "solve_ms": ms}

    recs = [rec("granuflow", "cell_average", 0.02, 2.0), rec("granuflow", "cell_average", 0.004, 5.0),
            rec("granuflow", "fixed_pivot", 0.2, 1.0), rec("scipy", "scipy_fp_LSODA", 0.03, 9.0),
            rec("scipy", "scipy_fp_LSODA", 0.2, 4.0), rec("scipy", "scipy_fp_BDF", 0.3, 8.0)]
    rows = {(r["level"], r["baseline"]): r for r in bench.speed_ratios(recs, levels=(0.05, 0.01))}
    assert rows[(0.05, "scipy_fp_LSODA")]["ratio"] == pytest.approx(4.5)
    assert rows[(0.05, "scipy_fp_LSODA")]["granuflow_ms"] == 2.0
    assert rows[(0.01, "scipy_fp_LSODA")]["ratio"] is None  # SciPy never reaches 1 %
    assert rows[(0.01, "scipy_fp_LSODA")]["granuflow_ms"] == 5.0
    assert rows[(0.05, "scipy_fp_BDF")]["baseline_ms"] is None
    assert [r["solve_ms"] for r in bench.envelope(recs) if r["method"] == "cell_average"] == [2.0, 5.0]
    same = bench.same_scheme_ratios(recs)
    assert {(r["baseline"], r["ratio"]) for r in same} == {("scipy_fp_LSODA", 9.0), ("scipy_fp_LSODA", 4.0),
                                                           ("scipy_fp_BDF", 8.0)}


def test_missing_executable_is_a_clear_error(monkeypatch, tmp_path):
    monkeypatch.setattr(bench, "HERE", str(tmp_path / "python" / "granuflow"))
    with pytest.raises(FileNotFoundError, match=r"granuflow_bench_pbm does not exist .*ninja -C"):
        bench.bench_pbm(quick=True)


def test_a_failing_baseline_is_one_line_not_a_traceback(monkeypatch, tmp_path, capsys):
    """The SciPy scene script runs in this process (alternating with granuflow's runs): its failure is named in one
    line, exit 1, as a baseline run as its own process is."""
    from granuflow.cli import main

    broken = tmp_path / "scipy_gf25_batch.py"
    broken.write_text("class Timed:\n    def __init__(self, n, b):\n        raise ValueError('no model')\n")
    monkeypatch.setattr(bench, "scipy_scene_script", lambda: str(broken))
    assert main(["bench", "scene", "--quick", "--repeats", "1"]) == 1
    err = capsys.readouterr().err
    assert err.strip() == "granuflow: benchmark failed: scipy_gf25_batch.py failed: ValueError: no model", err
    broken.write_text("def broken(:\n")  # not even importable
    assert main(["bench", "scene", "--quick", "--repeats", "1"]) == 1
    err = capsys.readouterr().err
    assert err.startswith("granuflow: benchmark failed: scipy_gf25_batch.py failed: SyntaxError"), err
    assert "Traceback" not in err and len(err.strip().splitlines()) == 1, err


def test_bench_scene_reports_each_variant_with_the_scene_physics():
    """`granuflow bench scene`: one record per class count and breakage switch, from the headline scene itself,
    and an independent SciPy implementation of the same equations agrees with each."""
    p = cli("bench", "scene", "--json", "--repeats", "1", timeout=300)
    assert p.returncode == 0, p.stderr
    recs = [json.loads(line) for line in p.stdout.splitlines()]
    assert [(r["classes"], r["breakage"]) for r in recs] == [(n, b) for n in (10, 20, 40) for b in (True, False)]
    for r in recs:
        n = r["classes"]
        # unknowns: M_i, W_i, the bed's 5 and the gas's 4 lumped states; inlined: the spray zone (3 N + 1, and tau at
        # the N + 1 faces), droplets (2 flows, 2 solids fractions), inlet (4), nozzle (3), wall (1)
        assert (r["unknowns"], r["inlined_states"]) == (2 * n + 9, 4 * n + 14), r
        assert r["wall_ms_median"] > 0 and r["steps"] > 0 and r["jacobians"] > 0
        assert 0.02 < r["bed_moisture"] < 0.2, r
        assert (r["speedup_vs_issue_reference"] is not None) == (r["breakage"] and n in (10, 40))
        # the SciPy implementation of the same equations (tests/bench/scipy_gf25_batch.py), run on the same variant
        assert r["scipy_ms_median"] > 0 and r["speedup_vs_scipy"] > 0
        # measured in alternating rounds: one SciPy solve after each round of granuflow's runs
        assert r["scipy_repeats"] == len(r["speedup_rounds"]) == 1 and r["speedup_rounds"][0] > 0
        for k in ("d10_um", "d50_um", "d90_um", "bed_moisture", "T_gas_out_K"):
            assert r[k] == pytest.approx(r["scipy_" + k], rel=5e-3), (k, r)
    by = {(r["classes"], r["breakage"]): r for r in recs}
    for n in (10, 20, 40):  # breakage is what holds d50 near 450-500 um; without it the bed grows to the top class
        assert by[(n, True)]["d50_um"] < 0.6 * by[(n, False)]["d50_um"]
    # the 10-class variant is the scene file unchanged
    scene = gf.load(SCENE).simulate()
    assert by[(10, True)]["d50_um"] == pytest.approx(scene.summary["d50_um"], rel=1e-12)
