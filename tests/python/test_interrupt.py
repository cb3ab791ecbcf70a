"""Ctrl-C (SIGINT) stops work in the core within about 0.1 s (granuflow/interrupt.hpp): a run, the grid check's solve
beside it, sweeps (in the core and on Python threads), Monte Carlo replicas and a calibration. In Python it raises
KeyboardInterrupt; the command line exits 130 with one line and writes nothing. The next run is the same as before.
Every job here would run for several times the wait each test allows if the interrupt did not stop it."""
import os
import signal
import subprocess
import threading
import time

import pytest
from conftest import PKG_PATH, ROOT, SCENE, package_env

import granuflow as gf
from granuflow.accuracy import grid_check

with open(SCENE) as _f:
    HEADLINE = _f.read()
EXPERIMENTS = os.path.join(ROOT, "flowsheets", "calibration", "synthetic_gf25_table1.yaml")
STAGES = os.path.join(ROOT, "flowsheets", "calibration", "stages_paper001.yaml")


def headline_text(classes: int, tol: str) -> str:
    """The headline scene on `classes` classes at tolerance `tol`, with dense LU: the durations below are its (the
    class-local Newton matrix that `auto` takes from 40 classes on solves these grids several times faster)."""
    old_grid, old_tol = "settings: {classes: 10, ", "solver: {rtol: 1e-6, atol: 1e-6}"
    assert old_grid in HEADLINE and old_tol in HEADLINE
    return HEADLINE.replace(old_grid, f"settings: {{classes: {classes}, ").replace(
        old_tol, f"solver: {{rtol: {tol}, atol: {tol}, linear_solver: dense}}")


# 300 classes at rtol 1e-13: 2300 steps, about 4.6 s on the 2-core machine CI runs on (0.4 s of it before the first)
LONG = headline_text(300, "1e-13")


@pytest.fixture(autouse=True)
def sigint_raises():
    """SIGINT raises KeyboardInterrupt in this process, as in a terminal: a process started in the background by a
    shell without job control (a CI script's `cmd &`) inherits SIGINT ignored, and Python then keeps it ignored."""
    before = signal.signal(signal.SIGINT, signal.default_int_handler)
    yield
    signal.signal(signal.SIGINT, before)


def sigint_after(delay: float) -> threading.Timer:
    timer = threading.Timer(delay, lambda: os.kill(os.getpid(), signal.SIGINT))
    timer.start()
    return timer


def test_a_run_stops_at_ctrl_c_and_the_next_run_is_unchanged():
    fs = gf.load(SCENE)
    before = fs.simulate(grid_check=False, warn=False)
    long = gf.load_text(LONG)
    timer = sigint_after(0.8)
    t0 = time.perf_counter()
    with pytest.raises(KeyboardInterrupt):
        long.simulate(grid_check=False, warn=False)
    waited = time.perf_counter() - t0
    timer.join()
    assert waited < 2.0, f"the run went on for {waited:.2f} s after starting (interrupt at 0.8 s)"
    after = fs.simulate(grid_check=False, warn=False)
    assert (after.y == before.y).all() and (after.outputs == before.outputs).all()
    assert after.summary["d50_um"] == before.summary["d50_um"]


def test_the_grid_check_beside_the_run_stops_with_it(monkeypatch, capfd):
    fs = gf.load_text(headline_text(70, "1e-13"))  # within the limit for the check's solve beside the run
    started, timers = [], []

    class Recorded(grid_check.Ahead):
        def __init__(self, *a, **kw):
            super().__init__(*a, **kw)
            started.append(self)
            # 0.1 s after the check's solve started: in the run's own (0.2 s; the finer one takes 0.4 s more),
            # which the caller starts at once
            timers.append(sigint_after(0.1))

    monkeypatch.setattr(grid_check, "Ahead", Recorded)
    with pytest.raises(KeyboardInterrupt):
        fs.simulate()
    timers[0].join()
    assert len(started) == 1
    assert not started[0]._thread.is_alive()
    assert started[0].fine is None  # its solve was stopped, not finished
    err = capfd.readouterr().err
    assert "Exception in thread" not in err and "Traceback" not in err, err


def test_a_sweep_solved_in_the_core_stops_at_ctrl_c():
    from granuflow import design_space as ds

    fs = gf.load_text(headline_text(40, "1e-6"))  # 625 points of about 20 ms on 2 threads: about 6 s
    timer = sigint_after(0.4)
    t0 = time.perf_counter()
    with pytest.raises(KeyboardInterrupt):
        ds.contour_map(fs, x=("inlet.T", "degC", 40, 80, 25), y=("nozzle.mdot", "g/min", 60, 120, 25),
                       outputs=["d50_um"], workers=2, progress=False)
    waited = time.perf_counter() - t0
    timer.join()
    assert waited < 2.0, f"the sweep went on for {waited:.2f} s (interrupt at 0.4 s)"


def test_a_sweep_on_python_threads_stops_at_ctrl_c():
    # the per-point path: Python raises the interrupt in the waiting thread and stops the points being solved
    from granuflow.sweep import run_sweep

    fs = gf.load_text(headline_text(300, "1e-13"))  # about 4.6 s a point
    points = [{"inlet.T": 330.0 + k} for k in range(4)]
    timer = sigint_after(0.8)
    t0 = time.perf_counter()
    with pytest.raises(KeyboardInterrupt):
        run_sweep(fs, points, ["d50_um"], workers=2, progress=False, batch=False)
    waited = time.perf_counter() - t0
    timer.join()
    assert waited < 2.0, f"the sweep went on for {waited:.2f} s (interrupt at 0.8 s)"
    assert not [t for t in threading.enumerate() if t.name.startswith("granuflow-sweep")]


def test_a_monte_carlo_run_stops_at_ctrl_c():
    from granuflow import montecarlo as mc

    timer = sigint_after(0.5)  # 4 replicas of 240 s of the process: about 9 s
    t0 = time.perf_counter()
    with pytest.raises(KeyboardInterrupt):
        mc.run(t_end=240, settings={"replicas": 4})
    waited = time.perf_counter() - t0
    timer.join()
    assert waited < 2.0, f"the replicas went on for {waited:.2f} s (interrupt at 0.5 s)"


def interrupted_cli(args, delay):
    """``granuflow ARGS`` sent SIGINT after `delay` s: (exit code, stdout, stderr, seconds from the signal to the
    exit)."""
    launcher = os.path.join(os.path.dirname(PKG_PATH), "granuflow")
    cmd = [launcher] if os.access(launcher, os.X_OK) else ["/usr/bin/python3", "-m", "granuflow"]
    # the child starts with SIGINT's default action, whatever this process inherited (sigint_raises)
    p = subprocess.Popen(cmd + [str(a) for a in args], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                         env=package_env(), preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    time.sleep(delay)
    p.send_signal(signal.SIGINT)
    t0 = time.perf_counter()
    out, err = p.communicate(timeout=120)
    return p.returncode, out, err, time.perf_counter() - t0


def test_granuflow_run_exits_130_and_writes_nothing(tmp_path):
    scene = tmp_path / "long.yaml"
    scene.write_text(LONG)
    code, out, err, waited = interrupted_cli(["run", scene, "--no-plots", "--out", tmp_path / "out"], 1.5)
    assert code == 130, (code, err)
    assert err == "granuflow: interrupted\n"
    assert out == ""
    assert waited < 2.0
    assert not (tmp_path / "out" / "summary.json").exists()


def test_granuflow_calibrate_exits_130_with_one_line(tmp_path):
    # in the first stage's Levenberg-Marquardt iterations (the whole calibration takes about 6 s); Ceres must not log
    # the evaluations the interrupt ended as failures
    code, out, err, waited = interrupted_cli(["calibrate", EXPERIMENTS, "--stages", STAGES, "--out",
                                              tmp_path / "cal", "--no-progress"], 1.5)
    assert code == 130, (code, err)
    assert err == "granuflow: interrupted\n"
    assert waited < 2.0
    assert not (tmp_path / "cal" / "estimates.csv").exists()
