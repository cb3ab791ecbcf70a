"""Several Python threads simulating one Flowsheet object at once (issue 12): every thread gets the serial answer,
bit for bit (runs never change the flowsheet; the core releases the GIL during a solve), also with the error
estimate, which builds refined flowsheets of its own."""
import concurrent.futures as cf

import numpy as np
import pytest

from conftest import SCENE

import granuflow as gf


def test_threads_on_one_flowsheet_give_the_serial_answer():
    fs = gf.load(SCENE)
    serial = fs.simulate(warn=False)
    with cf.ThreadPoolExecutor(max_workers=4) as pool:
        results = list(pool.map(lambda _: fs.simulate(warn=False), range(8)))
    for r in results:
        assert np.array_equal(r.y, serial.y)
        assert np.array_equal(r.outputs, serial.outputs)


def test_threads_with_error_estimates_on_one_flowsheet():
    fs = gf.load(SCENE)
    serial = fs.simulate(t_end=600.0, warn=False, error_estimate=True).error_estimate["d50_um"]
    with cf.ThreadPoolExecutor(max_workers=3) as pool:
        results = list(pool.map(lambda _: fs.simulate(t_end=600.0, warn=False, error_estimate=True), range(3)))
    for r in results:
        e = r.error_estimate["d50_um"]
        assert (e.value, e.discretization, e.integration) == (serial.value, serial.discretization, serial.integration)


def test_a_run_on_a_kept_system_equals_a_run_on_a_new_flowsheet():
    """Runs take the system a finished run gave back (Flowsheet::take_system): it must start like a new one, with the
    parameters, inputs and options of this run, and count only this run's work. Each run here is compared, bit for
    bit, with the same run on a flowsheet loaded afresh."""
    def fresh(**changes):
        f = gf.load(SCENE)
        for k, v in changes.items():
            f.set(k, v)
        return f

    fs = gf.load(SCENE)
    first = fs.simulate(t_end=900.0, warn=False)
    for run, reference in [
        (lambda: fs.simulate(t_end=900.0, warn=False), lambda: fresh().simulate(t_end=900.0, warn=False)),
        # a kernel parameter (the engine's tables are rebuilt) and an operating one
        (lambda: (fs.update({"bed.agg_ln_beta0": -16.5, "nozzle.mdot": 1.5e-3}),
                  fs.simulate(t_end=900.0, warn=False))[1],
         lambda: fresh(**{"bed.agg_ln_beta0": -16.5, "nozzle.mdot": 1.5e-3}).simulate(t_end=900.0, warn=False)),
        # with sensitivities, then without again
        (lambda: fs.simulate(t_end=900.0, warn=False, sensitivities=["bed.agg_ln_beta0"]),
         lambda: fresh(**{"bed.agg_ln_beta0": -16.5, "nozzle.mdot": 1.5e-3}).simulate(
             t_end=900.0, warn=False, sensitivities=["bed.agg_ln_beta0"])),
        (lambda: fs.simulate(t_end=900.0, warn=False),
         lambda: fresh(**{"bed.agg_ln_beta0": -16.5, "nozzle.mdot": 1.5e-3}).simulate(t_end=900.0, warn=False)),
    ]:
        got, want = run(), reference()
        assert np.array_equal(got.y, want.y) and np.array_equal(got.outputs, want.outputs)
        assert got.stats["residuals"] == want.stats["residuals"] and got.stats["jacobians"] == want.stats["jacobians"]
    assert not np.array_equal(got.y, first.y)  # the changed parameters did change the run
    # a run that fails gives its system up; the next run starts like a new one
    with pytest.raises(gf.SolverError):
        fs.simulate(t_end=900.0, warn=False, max_steps=20)
    got = fs.simulate(t_end=900.0, warn=False)
    want = fresh(**{"bed.agg_ln_beta0": -16.5, "nozzle.mdot": 1.5e-3}).simulate(t_end=900.0, warn=False)
    assert np.array_equal(got.y, want.y) and got.stats["residuals"] == want.stats["residuals"]
