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


def test_kernel_tables_kept_for_a_sensitivity_run_follow_their_inputs():
    """A sensitivity run keeps the aggregation's h K and the breakage tables it built from the kernel parameters'
    Jets, and reuses them while the same Jets come back (population_work.hpp, Work::kh_params). Here the rate
    constants of both mechanisms are driven through time while the derivatives are taken by two other parameters of
    the same kernels, so the kept tables must be rebuilt whenever a value moves: the derivatives at the end must
    equal central differences of runs at a tight tolerance (kept tables that only watched the derivatives were off
    by 13 %)."""
    params = ["bed.agg_tau_spray", "bed.frag_q_frag"]
    tight = dict(t_end=1200.0, warn=False, rtol=1e-9, atol=1e-9, grid_check=False)

    def scene(shift=None):
        fs = gf.load(SCENE)
        for name, dv in (shift or {}).items():
            fs.set(name, fs.get(name) + dv)
        fs.set_input("bed.agg_ln_beta0", [0, 600, 1200], [-17.3, -16.6, -17.0])
        fs.set_input("bed.sel_k_break", [0, 400, 1200], [1.3e-3, 3e-3, 0.5e-3])
        return fs

    sens = scene().simulate(sensitivities=params, **tight).sens[-1]
    for k, name in enumerate(params):
        h = 1e-3 * abs(gf.load(SCENE).get(name))
        up = scene({name: h}).simulate(**tight).y[-1]
        down = scene({name: -h}).simulate(**tight).y[-1]
        fd = (up - down) / (2 * h)
        assert np.max(np.abs(sens[k] - fd)) <= 1e-4 * np.max(np.abs(fd)), name
