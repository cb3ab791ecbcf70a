"""The balance closure of a steady state: |in - out| / max where something flows, 0 with a note where nothing does
(a spray switched off gave a solids closure of 1.0 from in = 0 against out = 6.8e-37)."""
from granuflow.steady import NO_FLOW, boundary_balance


def test_zero_flows_close_with_a_note_and_real_flows_by_their_difference():
    raw = {"boundary_flows": {"solids": {"in": 0.0, "out": 6.8e-37}, "water": {"in": 2.0e-3, "out": 1.9e-3},
                              "energy": {"in": 1.0e4, "out": 1.0e4}}}
    bal = boundary_balance(raw)
    assert bal["solids"]["rel"] == 0.0 and "nothing flows" in bal["solids"]["note"]
    assert abs(bal["water"]["rel"] - 0.05) < 1e-12 and "note" not in bal["water"]
    assert bal["energy"]["rel"] == 0.0 and "note" not in bal["energy"]
    # just above the floor a mismatch counts in full
    tiny = {"boundary_flows": {"solids": {"in": 0.0, "out": 10 * NO_FLOW}}}
    assert boundary_balance(tiny)["solids"]["rel"] == 1.0
