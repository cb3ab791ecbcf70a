"""Settings as event actions and simultaneous events (docs/events_and_checkpoints.md): a unit rebuilt with a new
setting at a located event continues from its state like a run restarted by hand from a checkpoint with the setting
changed; a setting that would change the state layout is refused at load; events whose roots fall in one integrator
step are each located at their own time, and simultaneous ones fire in declaration order with a jump each, their
sensitivities against the analytic ones and finite differences."""
import os

import numpy as np
import pytest
from conftest import ROOT

import granuflow as gf

SETTINGS = os.path.join(ROOT, "flowsheets", "stoeckl_gf25_recipe_settings.yaml")
FAST = dict(warn=False, grid_check=False, accuracy=False)


def _text(old=None, new=None):
    with open(SETTINGS) as f:
        text = f.read()
    if old is not None:
        assert old in text, old
        text = text.replace(old, new, 1)
    return text


EVENT = ("  - {name: stop_spray, when: bed.d50 >= 450 um, do: {set: {nozzle.mdot: 0 kg/s, "
         "bed.breakage_scheme: cell_average}}, phase: drying}\n")


def test_settings_event_equals_a_restart_with_the_setting_changed(tmp_path):
    """(a) The run whose event switches the breakage scheme equals two runs stitched by hand: the scene without the
    event, checkpointed at the event's time, and a restart from that file with the spray off and the scheme switched
    in the scene. Before the event they differ only by where the integrator stopped (a located root or a breakpoint),
    so they agree to the solver's tolerance, and the scheme's effect after the event is far larger than that."""
    opts = dict(t_end=2 * 3600.0, n_out=25, rtol=1e-8, atol=1e-8, **FAST)
    a = tmp_path / "a.yaml"
    a.write_text(_text(EVENT, "  []\n").replace("events:\n  []\n", ""))
    event_run = gf.load(SETTINGS).simulate(**opts)
    assert [e["name"] for e in event_run.events] == ["stop_spray"]
    t_ev = event_run.events[0]["t"]
    first = gf.load(str(a)).simulate(checkpoints=[t_ev], checkpoint_dir=str(tmp_path), **opts)
    b = tmp_path / "b.yaml"
    b.write_text(a.read_text().replace("bed:\n    type: fluid_bed\n",
                                       "bed:\n    type: fluid_bed\n    settings: {breakage_scheme: cell_average}\n")
                 .replace("mdot: 90 g/min", "mdot: 0 g/min"))
    stitched = gf.load(str(b)).simulate(checkpoints=[t_ev], restart=first.checkpoint_files[0], **opts)
    d50 = event_run.output_names.index("bed.d50")
    assert np.allclose(stitched.outputs[:, d50], event_run.outputs[:, d50], rtol=1e-7, atol=0)  # 8e-9 measured
    # without the switch (the spray stopped only) the bed ends elsewhere, by far more than that tolerance
    c = tmp_path / "c.yaml"
    c.write_text(_text("bed.breakage_scheme: cell_average", "bed.outside: fold"))
    fixed = gf.load(str(c)).simulate(**opts)
    assert np.max(np.abs(fixed.outputs[:, d50] / event_run.outputs[:, d50] - 1)) > 1e-2  # 5.4 % measured
    # the flowsheet is given back with its own setting: a second run of it is the first again
    again = gf.load(SETTINGS)
    again.simulate(**opts)
    assert np.array_equal(again.simulate(**opts).outputs, event_run.outputs, equal_nan=True)  # no spray: NaN shares


def test_unmappable_setting_is_refused_at_load(tmp_path):
    """(b) A setting whose new value changes the unit's states cannot be carried over: one line naming the event, the
    setting and why."""
    p = tmp_path / "bad.yaml"
    p.write_text(_text("bed.breakage_scheme: cell_average", "particles.classes: 12"))
    with pytest.raises(gf.ConfigError) as e:
        gf.load(str(p))
    msg = str(e.value)
    assert "\n" not in msg
    assert "events[0] (stop_spray).do.set.particles.classes = '12': cannot change during a run" in msg
    assert "were laid out from the settings of particles" in msg
    p.write_text(_text("bed.breakage_scheme: cell_average", "bed.drying_curve: gamma"))
    with pytest.raises(gf.ConfigError, match=r"do.set.bed.drying_curve = 'gamma': cannot change during a run, it "
                                             r"changes the parameters \(adds drying_gamma\)"):
        gf.load(str(p))


RAMP = """
scene: ramp
description: a heated tank without flow, its temperature a straight line between events
t_end: 1000 s
output: {n: 11}
solver: {rtol: 1e-10, atol: 1e-12}
units:
  feed: {type: liquid_feed, params: {mdot: 0 kg/s, w: 0, T: 300 K}}
  tank: {type: stirred_tank, params: {mass: 100 kg, Q: 20 kW, T0: 300 K, w0: 0}}
  product: {type: liquid_product}
connections: [feed.out -> tank.in, tank.out -> product.in]
events:
  - {name: a, when: tank.T >= 310 K, do: {set: {EVENT_A}}}
  - {name: b, when: tank.T >= TB, do: {set: {EVENT_B}}}
"""


def _ramp(tmp_path, a, b, tb, **kw):
    p = tmp_path / "ramp.yaml"
    p.write_text(RAMP.replace("EVENT_A", a).replace("EVENT_B", b).replace("TB", tb))
    fs = gf.load(str(p))
    try:
        return fs, fs.simulate(**FAST, **kw)
    except gf.BalanceError as e:  # the tank's energy balance books its heating at the duty the run ends with
        return fs, e.result


def _fd(fs, param, rel=1e-4):
    p0 = fs.get(param)
    vals = []
    for sign in (1, -1):
        fs.set(param, p0 + sign * rel * p0)
        try:
            r = fs.simulate(**FAST)
        except gf.BalanceError as e:
            r = e.result
        vals.append(r["tank.T"][-1])
    fs.set(param, p0)
    return (vals[0] - vals[1]) / (2 * rel * p0)


def test_two_events_in_one_step_are_each_located_at_their_own_time(tmp_path):
    """T rises at Q/(m cp): a at 310 K (Q 20 -> 40 kW), b 0.05 K later (Q -> 10 kW), 0.52 s apart, closer than the
    integrator's typical step there (101 steps over the run). t_a = 10 m cp / Q1, t_b = t_a + 0.05 m cp / Q2 and
    T(t_end) = T_b + (t_end - t_b) Q3 / (m cp), so dT_end/dT0 = Q3/Q1 and dT_end/dm = -t_end Q3 / (m^2 cp)."""
    fs, r = _ramp(tmp_path, "tank.Q: 40 kW", "tank.Q: 10 kW", "310.05 K", sensitivities=["tank.T0", "tank.mass"])
    m, cp = 100.0, fs.get("tank.cp")
    t_a = 10 * m * cp / 20e3
    t_b = t_a + 0.05 * m * cp / 40e3
    assert [e["name"] for e in r.events] == ["a", "b"]
    assert r.events[0]["t"] == pytest.approx(t_a, rel=1e-10) and r.events[1]["t"] == pytest.approx(t_b, rel=1e-10)
    assert r["tank.T"][-1] == pytest.approx(310.05 + (1000 - t_b) * 10e3 / (m * cp), rel=1e-10)
    s = [r.sensitivity("tank.T", p)[-1] for p in r.sens_params]
    assert s[0] == pytest.approx(10e3 / 20e3, rel=1e-7)
    assert s[1] == pytest.approx(-1000 * 10e3 / (m * m * cp), rel=1e-7)
    assert s[0] == pytest.approx(_fd(fs, "tank.T0"), rel=1e-5)
    assert s[1] == pytest.approx(_fd(fs, "tank.mass"), rel=1e-5)


def test_simultaneous_events_fire_in_order_with_a_jump_each(tmp_path):
    """a and b cross at the same time: a raises the duty to 40 kW, b halves the mass; both fire at t_a in declaration
    order and T then rises at Q2/(m2 cp), so dT_end/dT0 = (Q2/m2) / (Q1/m) = 4."""
    fs, r = _ramp(tmp_path, "tank.Q: 40 kW", "tank.mass: 50 kg", "310 K", sensitivities=["tank.T0", "tank.cp"])
    cp = fs.get("tank.cp")
    t_a = 10 * 100 * cp / 20e3
    assert [(e["name"], e["t"]) for e in r.events] == [("a", r.events[0]["t"]), ("b", r.events[0]["t"])]
    assert r.events[0]["t"] == pytest.approx(t_a, rel=1e-10)
    assert r["tank.T"][-1] == pytest.approx(310 + (1000 - t_a) * 40e3 / (50 * cp), rel=1e-10)
    s = [r.sensitivity("tank.T", p)[-1] for p in r.sens_params]
    assert s[0] == pytest.approx(4.0, rel=1e-7)
    # T_end = 310 + 1000 Q2/(m2 cp) - (T_a - T0) (m Q2) / (m2 Q1): d/dcp = -1000 Q2 / (m2 cp^2)
    assert s[1] == pytest.approx(-1000 * 40e3 / (50 * cp * cp), rel=1e-7)
    assert s[0] == pytest.approx(_fd(fs, "tank.T0"), rel=1e-5)
    assert s[1] == pytest.approx(_fd(fs, "tank.cp"), rel=1e-5)
