"""A balance that does not close is an error, not a number in a file (issue 27, section 4): a unit written to lose
part of its flow (tests/cpp/leaky_pipe.cpp, registered only with GRANUFLOW_TEST_UNITS set, so it runs in a
subprocess) makes `run` and `steady` exit 3 naming the balance and its closure, and Python raise BalanceError; a
small leak warns (summary.json `warnings`, stderr, BalanceWarning); without a leak nothing is said."""
import json
import os
import subprocess
import sys
import textwrap

import pytest

import granuflow as gf
from granuflow import outputs

from conftest import PKG_PATH, package_env

LEAKY = textwrap.dedent("""\
    scene: leaky_pipe
    description: a feed, a pipe that loses part of its flow, a tank and a product
    t_end: 1000 s
    solver: {rtol: 1e-8, atol: 1e-10}
    units:
      feed: {type: liquid_feed, params: {mdot: 0.5 kg/s, w: 0.1, T: 320 K}}
      pipe: {type: test_leaky_pipe, params: {leak: LEAK}}
      tank: {type: stirred_tank, params: {mass: 100 kg, Q: 0 W, T0: 300 K, w0: 0.1}}
      product: {type: liquid_product}
    connections: [feed.out -> pipe.in, pipe.out -> tank.in, tank.out -> product.in]
    summary: {T_out_K: tank.T}
    """)


def _env():
    return package_env(GRANUFLOW_TEST_UNITS="1")


def _scene(tmp_path, leak):
    path = tmp_path / f"leak_{leak}.yaml"
    path.write_text(LEAKY.replace("LEAK", repr(leak)))
    return path


@pytest.fixture(scope="module")
def leaky_units():
    p = subprocess.run([sys.executable, "-c", "import granuflow as gf; print('test_leaky_pipe' in gf.unit_types())"],
                       capture_output=True, text=True, env=_env(), timeout=60)
    if p.stdout.strip() != "True":
        pytest.skip("the build has no test units (GRANUFLOW_BUILD_TESTS=OFF)")


def _run(args):
    """``granuflow ARGS`` of the build under test, with the test units registered."""
    launcher = os.path.join(os.path.dirname(PKG_PATH), "granuflow")
    cmd = [launcher] if os.access(launcher, os.X_OK) else [sys.executable, "-m", "granuflow"]
    return subprocess.run(cmd + [str(a) for a in args], capture_output=True, text=True, timeout=120, env=_env())


def test_a_unit_that_loses_mass_fails_the_run_naming_the_balance(tmp_path, leaky_units):
    out = tmp_path / "out"
    p = _run(["run", _scene(tmp_path, 0.05), "--out", out, "--no-plots"])
    assert p.returncode == 3, (p.returncode, p.stderr)
    last = p.stderr.strip().splitlines()[-1]
    assert last.startswith("granuflow: balance failure: ") and "balance does not close" in last, p.stderr
    assert "Traceback" not in p.stderr
    s = json.loads((out / "summary.json").read_text())  # what happened is still written
    # the pipe drops 5 % of every flow: water and solids close to 0.05, not to the tolerance
    assert s["balance"]["water_rel"] == pytest.approx(0.05, rel=1e-3)
    assert s["balance"]["solids_rel"] == pytest.approx(0.05, rel=1e-3)
    assert f"closure {s['balance']['water_rel']:.3g}" in p.stderr
    assert any(w.startswith("balance: the water balance does not close") for w in s["warnings"]), s["warnings"]


def test_python_raises_balance_error_for_runs_and_steady_states(tmp_path, leaky_units):
    code = textwrap.dedent(f"""\
        import granuflow as gf
        from granuflow.steady import steady_report
        fs = gf.load({str(_scene(tmp_path, 0.05))!r})
        try:
            fs.simulate()
        except gf.BalanceError as e:
            assert isinstance(e, gf.SolverError)
            same = e.result.summary["balance"] == e.result.balance_closure()
            print("run", e.balance, repr(e.value), same)
        try:
            steady_report(fs, stability=False)
        except gf.BalanceError as e:
            print("steady", e.balance, repr(e.value), e.report["balance"][e.balance]["rel"] == e.value)
        """)
    p = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=_env(), timeout=120)
    assert p.returncode == 0, p.stderr
    lines = p.stdout.split("\n")
    run, steady = lines[0].split(), lines[1].split()
    assert run[0] == "run" and run[1] in ("water", "solids", "energy") and run[3] == "True", p.stdout
    assert float(run[2]) == pytest.approx(0.05, rel=1e-3)
    assert steady[0] == "steady" and steady[3] == "True", p.stdout
    assert float(steady[2]) == pytest.approx(0.05, rel=1e-6)  # |in - out| / in at the steady state


def test_steady_exits_3_and_still_writes_steady_json(tmp_path, leaky_units):
    out = tmp_path / "st"
    p = _run(["steady", _scene(tmp_path, 0.05), "--out", out, "--no-stability"])
    assert p.returncode == 3, (p.returncode, p.stderr)
    assert "balance failure" in p.stderr and "at the steady state" in p.stderr
    rep = json.loads((out / "steady.json").read_text())
    assert rep["balance"]["water"]["rel"] == pytest.approx(0.05, rel=1e-6)


def test_a_small_leak_warns_everywhere_and_exits_0(tmp_path, leaky_units):
    warn_at, fail_at = outputs.balance_limits(1e-8)
    leak = 10 * warn_at  # between the limits: above what rtol 1e-8 explains, far below a lost stream
    assert leak < fail_at
    out = tmp_path / "out"
    p = _run(["run", _scene(tmp_path, leak), "--out", out, "--no-plots"])
    assert p.returncode == 0, p.stderr
    s = json.loads((out / "summary.json").read_text())
    assert s["balance"]["water_rel"] == pytest.approx(leak, rel=1e-2)
    assert any(w.startswith("balance: the water balance closes only to") for w in s["warnings"]), s["warnings"]
    assert "granuflow: warning: balance: the water balance closes only to" in p.stderr
    code = (f"import warnings, granuflow as gf\nwith warnings.catch_warnings(record=True) as w:\n"
            f"    warnings.simplefilter('always')\n    gf.load({str(_scene(tmp_path, leak))!r}).simulate()\n"
            f"print(sorted({{x.category.__name__ for x in w}}))")
    p = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=_env(), timeout=120)
    assert p.returncode == 0 and p.stdout.strip() == "['BalanceWarning']", (p.stdout, p.stderr)


def test_without_a_leak_nothing_is_said(tmp_path, leaky_units):
    out = tmp_path / "out"
    p = _run(["run", _scene(tmp_path, 0.0), "--out", out, "--no-plots"])
    assert p.returncode == 0 and "warning" not in p.stderr, p.stderr
    s = json.loads((out / "summary.json").read_text())
    assert s["warnings"] == [] and s["balance"]["water_rel"] < outputs.balance_limits(1e-8)[0]


def test_limits_follow_the_tolerance_within_their_bounds():
    assert outputs.balance_limits(1e-6) == (pytest.approx(1e-4), outputs.BALANCE_FAIL)
    assert outputs.balance_limits(1e-10)[0] == outputs.BALANCE_WARN_MIN
    assert outputs.balance_limits(1e-2)[0] == outputs.BALANCE_WARN_MAX < outputs.BALANCE_FAIL
    # per-component closures are checked wherever the balance map nests them
    found = outputs.balance_closures({"solids_rel": 1e-9, "solids": {"NaBz": {"rel": 0.2}}, "energy_rel": None})
    assert found == {"solids": 1e-9, "solids.NaBz": 0.2}
    warns, fails = outputs.balance_findings({"solids": {"NaBz": {"rel": 0.2}}}, 1e-6)
    assert len(fails) == 1 and "solids.NaBz balance does not close" in fails[0]
    assert gf.BalanceError.__mro__[1] is gf.SolverError
