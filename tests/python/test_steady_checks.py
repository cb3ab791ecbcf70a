"""Every check a run makes also runs on a steady state: the ends of the size grids (a sieve that passes everything
put 100 % of the loop's mass in the top class without a word) and the balance closure, which is |in - out| / max
where something flows and undefined (null, with a note saying why) where nothing does (in = 0 against out = 6.8e-37
gave a closure of 1.0); and a controller that misses its set point at the steady state says so (issue 29)."""
import json
import os
import subprocess
import sys

import granuflow as gf
from granuflow.steady import NO_FLOW, boundary_balance, steady_report

LOOP = os.path.join(os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))), "flowsheets",
                    "continuous_layering_sieve_mill.yaml")


def test_zero_flows_have_no_closure_and_real_flows_close_by_their_difference():
    raw = {"boundary_flows": {"solids": {"in": 0.0, "out": 6.8e-37}, "water": {"in": 2.0e-3, "out": 1.9e-3},
                              "energy": {"in": 1.0e4, "out": 1.0e4}}}
    bal = boundary_balance(raw)
    assert bal["solids"]["rel"] is None and "nothing flows" in bal["solids"]["note"]
    assert abs(bal["water"]["rel"] - 0.05) < 1e-12 and "note" not in bal["water"]
    assert bal["energy"]["rel"] == 0.0 and "note" not in bal["energy"]
    # just above the floor a mismatch counts in full
    tiny = {"boundary_flows": {"solids": {"in": 0.0, "out": 10 * NO_FLOW}}}
    assert boundary_balance(tiny)["solids"]["rel"] == 1.0


def test_a_steady_state_piled_in_the_top_class_warns_as_a_run_does():
    fs = gf.load(LOOP)
    assert steady_report(fs, stability=False)["warnings"] == []
    fs.set("sieve.upper_d_cut", 1.0)  # 1 m: nothing goes to the mill, the granules grow into the top class
    rep = steady_report(fs, stability=False)
    assert any("top size class" in w and "at the steady state" in w and "d_max" in w for w in rep["warnings"]), \
        rep["warnings"]


def test_a_loop_with_the_spray_off_has_no_closure_and_says_the_bed_misses_its_set_point():
    fs = gf.load(LOOP)
    fs.set_input("gran.m_spray", [0.0, 1.0], [0.0, 0.0], interp="step")
    rep = steady_report(fs, stability=True)
    solids = rep["balance"]["solids"]
    # nothing changes the bed: its eigenvalue is zero, neither growth nor decay (it was "unstable" at 1e-25 1/s)
    assert rep["stability"]["stable"] is None and "neutral" in rep["stability"]["note"], rep["stability"]
    assert solids["rel"] is None and "nothing flows" in solids["note"], solids
    missed = [w for w in rep["warnings"] if "misses its set point" in w]
    assert len(missed) == 1, rep["warnings"]
    # the ideal controller cannot discharge what never comes in: the bed keeps what it started with, not 100 kg
    mass = rep["bed_mass_kg"]
    assert abs(mass - 100.0) > 1.0, mass
    assert "unit gran (granulator)" in missed[0] and "gran.M_set = 100 kg" in missed[0], missed[0]
    assert f"gran.mass = {mass:.6g}"[:14] in missed[0], (mass, missed[0])
    # with the spray on, the controller holds its set point and nothing is said
    assert not any("set point" in w for w in steady_report(gf.load(LOOP), stability=False)["warnings"])


def test_the_command_line_writes_the_missed_set_point_and_the_undefined_closure(tmp_path):
    text = open(LOOP).read().replace("values: [200 kg/h, 240 kg/h]", "values: [0 kg/h, 0 kg/h]")
    assert "values: [0 kg/h, 0 kg/h]" in text
    scene = tmp_path / "loop_no_spray.yaml"
    scene.write_text(text)
    r = subprocess.run([sys.executable, "-m", "granuflow", "steady", str(scene), "--out", str(tmp_path / "o")],
                       capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    assert "warning: unit gran (granulator) misses its set point" in r.stderr and "gran.M_set = 100 kg" in r.stderr
    rep = json.loads((tmp_path / "o" / "steady.json").read_text())
    assert rep["balance"]["solids"]["rel"] is None and any("misses its set point" in w for w in rep["warnings"])
    assert "UNSTABLE" not in r.stdout and "neutral" in r.stdout, r.stdout
