"""Aggregation kernels written in Python (granuflow.register_kernel): selected in a pbm_batch scene by name, they
reproduce the compiled kernels, are evaluated once per run, and bad ones fail with a ValueError naming the kernel
and the problem."""
import itertools
import os
from concurrent.futures import ThreadPoolExecutor

import numpy as np
import pytest
import yaml

import granuflow as gf

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
SCENE = os.path.join(ROOT, "flowsheets", "pbm_constant_kernel.yaml")
_ids = itertools.count()


def unique(stem: str) -> str:
    """Kernel names are process-wide: one fresh name per registration."""
    return f"pytest_{stem}_{next(_ids)}_{os.getpid()}"


def scene(kernel: str, scheme: str = "cell_average", t_end: float | None = None, **params):
    """The constant-kernel verification scene with another kernel, scheme or end time."""
    with open(SCENE) as f:
        doc = yaml.safe_load(f)
    unit = doc["units"]["pbm"]
    unit["settings"].update(aggregation=kernel, aggregation_scheme=scheme)
    unit["params"] = {k: v for k, v in unit["params"].items() if not k.startswith("agg_")} | params
    if t_end is not None:
        doc["t_end"] = f"{t_end} s"
        doc["output"] = {"times": [0.0, t_end / 10, t_end]}
    return gf.load_text(yaml.safe_dump(doc), f"{SCENE} ({kernel}, {scheme})")


def assert_same_states(a, b, rel=1e-10):
    assert a.state_names == b.state_names
    scale = np.max(np.abs(a.y), axis=0) + 1e-300
    assert np.max(np.abs(a.y - b.y) / scale) <= rel


def assert_same_solution(a, b, rtol=1e-8, atol=1e-11, factor=300.0):
    """Two runs of one problem whose right-hand sides differ in rounding (the compiled constant and sum kernels sum
    with prefix sums, a Python kernel through its pair matrix), so their step sequences differ: the states agree
    within a few hundred times the scene's tolerance (the cell average's packet split is discontinuous in the
    state, which lets step-sequence differences grow), and the number and characteristic sizes to 1e-6. A kernel
    off by 0.1 % misses both by orders of magnitude."""
    assert a.state_names == b.state_names
    assert np.max(np.abs(a.y - b.y) / (rtol * np.abs(a.y) + atol)) <= factor
    for m in ("pbm.number", "pbm.d50", "pbm.d90"):
        assert b[m] == pytest.approx(a[m], rel=1e-6)


@pytest.mark.parametrize("scheme", ["cell_average", "fixed_pivot"])
def test_python_constant_kernel_reproduces_the_compiled_one(scheme):
    name = unique("constant")
    gf.register_kernel(name, lambda d, v: np.ones((d.size, d.size)), description="beta = 1 1/s")
    compiled = scene("constant", scheme).simulate()
    python = scene(name, scheme).simulate()
    assert_same_solution(compiled, python)
    assert python["pbm.number"][-1] == pytest.approx(1 / 51, rel=2e-3)  # Scott: N0 / (1 + tau / 2), tau = 100
    assert name in gf.aggregation_kernels() and "beta = 1 1/s" in gf.aggregation_kernels()[name]


def test_python_sum_kernel_gets_the_pivot_sizes():
    seen = {}

    def golovin(d, v):
        seen.update(d=d.copy(), v=v.copy(), writeable=d.flags.writeable or v.flags.writeable)
        return np.add.outer(v, v)

    name = unique("sum")
    gf.register_kernel(name, golovin)
    compiled = scene("sum", "cell_average", t_end=3.0).simulate()
    # without the grid check: its solve on a grid twice as fine would call the kernel last, with that grid's sizes
    python = scene(name, "cell_average", t_end=3.0).simulate(grid_check=False)
    assert_same_solution(compiled, python)
    v = 2.0 ** -12 * 2.0 ** np.arange(28)  # the scene's doubling grid; pivots at the volume midpoints
    np.testing.assert_allclose(seen["v"], 0.5 * (v[:-1] + v[1:]), rtol=1e-14)
    np.testing.assert_allclose(np.pi / 6 * seen["d"] ** 3, seen["v"], rtol=1e-12)
    assert not seen["writeable"]


def test_state_independent_python_kernel_runs_once_per_run():
    calls = []
    name = unique("counted")
    gf.register_kernel(name, lambda d, v: calls.append(1) or np.full((d.size, d.size), 0.5))
    fs = scene(name)
    for _ in range(3):
        fs.simulate(grid_check=False)  # (the grid check's solve on a finer grid would be a run of its own)
    assert len(calls) == 3


def test_python_kernel_in_threads_takes_the_gil():
    name = unique("threads")
    gf.register_kernel(name, lambda d, v: np.ones((d.size, d.size)))
    fs = scene(name, "fixed_pivot")
    with ThreadPoolExecutor(2) as pool:
        results = list(pool.map(lambda f: f.simulate(), [fs.clone() for _ in range(4)]))
    for r in results[1:]:
        assert_same_states(results[0], r, rel=0.0)


def _n(d):
    return d.size


BAD = [
    ("shape", lambda d, v: np.ones((3, 3)), r"returned an array of shape \(3, 3\), expected \(27, 27\)"),
    ("vector", lambda d, v: np.ones(_n(d)), r"returned an array of shape \(27,\), expected \(27, 27\)"),
    ("none", lambda d, v: None, r"returned None, expected a real \(27, 27\) array"),
    ("text", lambda d, v: "beta", r"returned str, expected a real \(27, 27\) array"),
    ("negative", lambda d, v: np.full((_n(d), _n(d)), -1.0), r"beta\[0, 0\] = -1 1/s: violates beta >= 0"),
    ("nan", lambda d, v: np.where(np.eye(_n(d)) > 0, np.nan, 1.0), r"beta\[0, 0\] = nan 1/s: violates beta finite"),
    ("asymmetric", lambda d, v: np.triu(np.ones((_n(d), _n(d)))),
     r"beta\[0, 1\] = 1 1/s but beta\[1, 0\] = 0 1/s: violates symmetry"),
    ("raises", lambda d, v: 1 / 0, r"fn\(diameters_m, volumes_m3\) raised ZeroDivisionError: division by zero"),
]


@pytest.mark.parametrize("stem,fn,message", BAD, ids=[b[0] for b in BAD])
def test_bad_python_kernel_names_the_kernel_and_the_problem(stem, fn, message):
    name = unique(stem)
    gf.register_kernel(name, fn)
    fs = scene(name)
    with pytest.raises(ValueError, match=rf"aggregation kernel '{name}' \(Python\): {message}") as err:
        fs.simulate()
    assert isinstance(err.value, gf.ConfigError)


def test_registration_errors():
    name = unique("dup")
    gf.register_kernel(name, lambda d, v: np.ones((d.size, d.size)))
    with pytest.raises(ValueError, match=rf"aggregation kernel '{name}' is already registered .*replace=True"):
        gf.register_kernel(name, lambda d, v: np.ones((d.size, d.size)))
    with pytest.raises(ValueError, match="aggregation kernel 'constant' is built in and cannot be replaced"):
        gf.register_kernel("constant", lambda d, v: np.ones((d.size, d.size)), replace=True)
    for bad in ("none", "", "two words", "a:b"):
        with pytest.raises(ValueError, match=f"aggregation kernel name '{bad}': violates"):
            gf.register_kernel(bad, lambda d, v: np.ones((d.size, d.size)))
    with pytest.raises(TypeError, match="fn must be callable"):
        gf.register_kernel(unique("int"), 3)
    with pytest.raises(ValueError, match=r"unknown aggregation kernel|allowed"):
        scene("no_such_kernel_anywhere")


def test_replace_swaps_the_function_for_flowsheets_built_afterwards():
    name = unique("replace")
    gf.register_kernel(name, lambda d, v: np.ones((d.size, d.size)))
    before = scene(name)
    gf.register_kernel(name, lambda d, v: np.full((d.size, d.size), 2.0), replace=True)
    after = scene(name)
    n_before = before.simulate()["pbm.number"][-1]
    n_after = after.simulate()["pbm.number"][-1]
    assert n_before == pytest.approx(1 / 51, rel=2e-3)  # built with beta = 1
    assert n_after == pytest.approx(1 / 101, rel=2e-3)  # beta = 2: tau = 200
    assert name in gf.kernels.python_kernels()
