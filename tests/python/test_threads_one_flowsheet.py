"""Several Python threads simulating one Flowsheet object at once (issue 12): every thread gets the serial answer,
bit for bit (runs never change the flowsheet; the core releases the GIL during a solve), also with the error
estimate, which builds refined flowsheets of its own."""
import concurrent.futures as cf

import numpy as np

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
