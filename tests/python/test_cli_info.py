"""The informational commands: --version, describe (every column, never truncated; CSV and JSON), closed pipes,
bench --quick on every subcommand."""
import csv
import io
import json
import os
import subprocess
import sys

import granuflow as gf
from conftest import ROOT

SCENE = os.path.join(ROOT, "flowsheets", "stoeckl_gf25_batch.yaml")
EXE = [sys.executable, "-m", "granuflow"]


def run(*args, env=None):
    return subprocess.run(EXE + list(args), capture_output=True, text=True, env={**os.environ, **(env or {})})


def test_version():
    r = run("--version")
    assert r.returncode == 0 and r.stdout.strip() == f"granuflow {gf.__version__} ({gf.build_info()['isa']})"


def test_describe_csv_and_json_hold_every_parameter_and_column():
    fs = gf.load(SCENE)
    rows = list(csv.DictReader(io.StringIO(run("describe", SCENE, "--format", "csv").stdout)))
    assert [r["param"] for r in rows] == fs.params
    bed = {r["param"]: r for r in rows}["bed.agg_ln_beta0"]
    spec = fs.spec("bed.agg_ln_beta0")
    assert bed["source"] == spec["source"] and bed["description"] == spec["description"]
    assert float(bed["value"]) == spec["value"] and float(bed["lower"]) == spec["lower"]
    data = json.loads(run("describe", SCENE, "--format", "json").stdout)
    assert len(data) == len(fs.params)
    assert {d["param"]: d["unit"] for d in data}["inlet.V_dot"] == "m3/s"


def test_describe_table_is_never_truncated_whatever_the_terminal_width():
    fs = gf.load(SCENE)
    longest = max((fs.spec(p)["description"] for p in fs.params), key=len)
    source = max((fs.spec(p)["source"] for p in fs.params), key=len)
    for cols in ("40", "300"):
        out = run("describe", SCENE, env={"COLUMNS": cols}).stdout
        assert longest in out and source in out and "..." not in out
        assert out.splitlines()[0].split()[:3] == ["param", "value", "unit"]


def test_piping_into_head_prints_no_traceback(tmp_path):
    err = tmp_path / "err.txt"
    cmd = " ".join(EXE) + f" describe {SCENE} 2>{err} | head -n 2"
    r = subprocess.run(["bash", "-c", cmd], capture_output=True, text=True)
    assert len(r.stdout.splitlines()) == 2
    assert err.read_text() == ""


def test_every_bench_subcommand_says_what_quick_does():
    r = run("bench", "--help")
    for what in ("core:", "pbm:", "scene:", "sweep:"):
        assert what in r.stdout.replace("\n", " ")


def test_bench_core_quick_is_reduced_and_quiet_when_piped():
    r = run("bench", "core", "--quick", "--repeats", "1", "--json")
    assert r.returncode == 0, r.stderr
    recs = [json.loads(line) for line in r.stdout.splitlines()]
    sizes = [x["states"] for x in recs if x["bench"] == "residual"]
    assert len(sizes) == 2 and max(sizes) < 2000  # no 10000-state chain with --quick
    assert r.stderr == ""  # no progress lines when stderr is not a terminal
