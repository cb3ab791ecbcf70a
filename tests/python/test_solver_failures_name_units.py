"""Every solver failure names the time, the unit and the worst weighted residual, whichever integrator ran: an ODE
run on ARKODE or CVODES failed with no unit and a residual of 0 until the one run driver (issue 26)."""
import math
import os

import pytest

import granuflow as gf

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


@pytest.mark.parametrize("method", ["auto", "erk"])  # BDF and Adams get through
def test_a_two_dimensional_population_of_1e_300_particles_fails_naming_its_unit(monkeypatch, method):
    monkeypatch.chdir(os.path.join(ROOT, "flowsheets"))  # the scene reads its collision table from data/
    fs = gf.load("sen_2d_dem_kernel.yaml")
    fs.set("granulator.N0", 1e-300)
    with pytest.raises(gf.SolverError) as e:
        fs.simulate(t_end=2.0, method=method, warn=False, max_steps=2000)
    err = e.value
    assert err.unit == "granulator", str(err)
    assert 0 < err.t < 2.0, str(err)
    assert "unit 'granulator'" in str(err) and "worst weighted residual" in str(err)
    assert err.worst_residual > 0 and not math.isnan(err.worst_residual)
