"""The time-series file is written in one pass over the result (issue 32): the same bytes as the per-column writer
it replaced (each column converted by quantity.from_si, NumPy's savetxt at %.10g), and repeated_outputs() the
outputs that equal a state of their unit at every time, found without comparing every output with every state."""
import numpy as np
import pytest
from conftest import SCENE

import granuflow as gf
from granuflow import outputs
from granuflow.quantity import from_si, label


@pytest.fixture(scope="module")
def res():
    return gf.load(SCENE).simulate(warn=False, grid_check=False)


def repeated_by_pairs(res):
    """The definition: an output equal (array_equal) to some state of the same unit over the whole run."""
    unit = lambda n: n.rpartition(".")[0]  # noqa: E731
    return [o for j, o in enumerate(res.output_names)
            if any(unit(s) == unit(o) and np.array_equal(res.y[:, i], res.outputs[:, j])
                   for i, s in enumerate(res.state_names))]


def per_column_csv(res, path):
    """The writer before issue 32: one from_si per column, then np.savetxt."""
    skip = set(repeated_by_pairs(res))
    cols = [("t [s]", res.t), ("t [min]", res.t / 60.0)]
    for names, block in ((res.state_names, res.y), (res.output_names, res.outputs)):
        for j, n in enumerate(names):
            if n not in skip:
                shown = outputs.display_unit(n, res.unit(n))
                cols.append((label(n, shown), from_si(block[:, j], shown, res.unit(n))))
    header = ",".join('"' + h + '"' if "," in h else h for h, _ in cols)
    np.savetxt(path, np.column_stack([v for _, v in cols]), delimiter=",", header=header, comments="", fmt="%.10g")


def test_repeated_outputs_are_those_equal_to_a_state_of_their_unit(res):
    found = res.repeated_outputs()
    assert found == repeated_by_pairs(res)
    assert any(".psd_m_" in n for n in found)  # the class masses, reported again for the size distribution
    # an output made equal to a state of its own unit repeats it (also with -0.0 for 0.0); with a NaN, never
    other = gf.load(SCENE).simulate(warn=False, grid_check=False)
    o = other.outputs.copy()
    j = other.output_names.index("bed.d50")
    i = next(k for k, n in enumerate(other.state_names) if n.startswith("bed.") and other.y[0, k] == 0)
    o[:, j] = other.y[:, i]
    o[0, j] = -0.0
    other.outputs = o
    assert "bed.d50" in other.repeated_outputs()
    o[-1, j] = np.nan
    assert "bed.d50" not in other.repeated_outputs()


def test_csv_has_the_bytes_of_the_per_column_writer(res, tmp_path):
    fresh = gf.load(SCENE).simulate(warn=False, grid_check=False)
    per_column_csv(fresh, tmp_path / "old.csv")
    fresh.to_csv(str(tmp_path / "new.csv"))
    old, new = (tmp_path / "old.csv").read_bytes(), (tmp_path / "new.csv").read_bytes()
    assert new == old
    assert b"bed.d50 [um]" in new  # sizes in um: the conversion ran
    table = fresh.table()
    assert list(table.columns) == new.decode().splitlines()[0].split(",")
    assert table.shape[0] == len(fresh.t)


def test_the_core_formats_every_double_as_python_does():
    # the rows of timeseries.csv come from the core (issue 32): "%.10g" of C and of Python agree on rounding (ties
    # included) and exponents, not on a NaN with its sign bit set, which Python writes "nan" and C "-nan"
    from granuflow import _core

    rng = np.random.default_rng(32)
    special = [0.0, -0.0, np.inf, -np.inf, np.nan, -np.nan, 5e-324, 2.2250738585072014e-308, 1.7976931348623157e308,
               1e-5, 1e16, 0.1, 2.5, 99999.999995, 1234567890.5, 0.00012345678905, 12345.678905]
    bits = rng.integers(0, 2**64 - 1, size=20000, dtype=np.uint64, endpoint=True)  # every double: NaNs, subnormals
    data = np.concatenate([special * 4, bits.view(np.float64), rng.lognormal(0, 20, 4000)])[:24060].reshape(-1, 12)
    assert _core.csv_rows(data) == "".join(",".join("%.10g" % x for x in row) + "\n" for row in data.tolist())
    assert _core.csv_rows(np.zeros((0, 3))) == ""


def test_a_result_pickles_with_its_arrays_summary_and_checks(tmp_path):
    """A result crosses a process pool or goes into a cache on disk: the core's buffers travel as arrays of their
    own, with the summary, warnings and grid check; the live flowsheet does not (None after unpickling)."""
    import pickle

    r = gf.load(SCENE).simulate(warn=False, grid_check=True, sensitivities=["wall.k_wall"])
    _ = r.y  # one array taken as a NumPy view of the core's buffer before pickling, the others not yet
    q = pickle.loads(pickle.dumps(r))
    for name in ("t", "y", "yp", "outputs", "sens"):
        np.testing.assert_array_equal(getattr(q, name), getattr(r, name), err_msg=name)
    assert q.sens.shape == (len(r.t), 1, len(r.state_names))
    assert q.summary == r.summary and q.warnings == r.warnings and q.stats == r.stats
    assert q.grid_check.errors == r.grid_check.errors and q.grid_check.suggest == r.grid_check.suggest
    assert q.balance_closure() == r.balance_closure()
    assert r.flowsheet is not None and q.flowsheet is None
    a, b = tmp_path / "a.csv", tmp_path / "b.csv"
    r.to_csv(str(a))
    q.to_csv(str(b))
    assert a.read_bytes() == b.read_bytes()
