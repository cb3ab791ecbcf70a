"""State events of a recipe (docs/events_and_checkpoints.md): located at the threshold by the integrator, actions
applied there, the phases and times in the results, sensitivities across events against finite differences, and
bad event input refused with one line."""
import os

import numpy as np
import pytest
from conftest import ROOT, assert_bad_input, cli, strict_json

import granuflow as gf

RECIPE = os.path.join(ROOT, "flowsheets", "stoeckl_gf25_recipe.yaml")


def _recipe_text():
    with open(RECIPE) as f:
        return f.read()


def _variant(tmp_path, old, new, name="recipe.yaml"):
    text = _recipe_text()
    assert old in text, old
    path = tmp_path / name
    path.write_text(text.replace(old, new, 1))
    return path


def test_recipe_events_located_at_their_thresholds():
    res = gf.load(RECIPE).simulate(warn=False, grid_check=False, accuracy=False)
    names = [e["name"] for e in res.events]
    assert names == ["stop_spray", "hot_air", "dry"]
    t = [e["t"] for e in res.events]
    assert 0 < t[0] < t[1] < t[2] < 3 * 3600.0
    # the run stops at the last event: its final output is the event's time, and the condition holds there exactly
    assert res.t[-1] == t[2]
    assert res["bed.moisture"][-1] == pytest.approx(0.015, rel=1e-7)
    # the spray stops at d50 = 450 um (test_event_time_matches_an_interpolated_crossing: where), and the spray rate
    # is zero from then on
    before = res.t < t[0]
    assert res["bed.d50"][before].max() < 450e-6
    after = res.t > t[0]
    assert np.all(res["nozzle.mdot"][after] == 0.0) and res["nozzle.mdot"][before].min() > 1e-3
    # the hot air enters at hot_air: the outlet gas, cooled below 55 degC by the spray and drying, passes it after
    assert res["gas.T"][(res.t > 600.0) & (res.t < t[1])].max() < 273.15 + 55.0 < res["gas.T"][-1]
    phases = res.phases
    assert [p["name"] for p in phases] == ["start", "drying", "hot drying"]  # the stop begins none
    assert phases[-1]["t_end_s"] == t[2]
    assert phases[1]["t_start_s"] == t[0] and phases[0]["t_end_s"] == t[0]
    assert res.summary["events"][0]["name"] == "stop_spray"


def test_recipe_cli_writes_events_and_plots(tmp_path):
    p = cli("run", RECIPE, "--out", tmp_path / "out", "--no-grid-check")
    assert p.returncode == 0, p.stderr
    s = strict_json(tmp_path / "out" / "summary.json")
    assert [e["name"] for e in s["events"]] == ["stop_spray", "hot_air", "dry"]
    assert [ph["name"] for ph in s["phases"]] == ["start", "drying", "hot drying"]
    assert s["t_end_s"] == s["events"][-1]["t_s"]
    assert (tmp_path / "out" / "moisture.png").stat().st_size > 0


def test_event_time_matches_an_interpolated_crossing():
    """The located time of stop_spray agrees with the crossing of d50 through 450 um in a run without events whose
    outputs are dense around it (the same trajectory up to the event)."""
    res = gf.load(RECIPE).simulate(warn=False, grid_check=False, accuracy=False)
    t_ev = res.events[0]["t"]
    ref = gf.load(os.path.join(ROOT, "flowsheets", "stoeckl_gf25_batch.yaml"))
    r = ref.simulate(t_out=np.linspace(t_ev - 20, t_ev + 20, 81), warn=False, grid_check=False, accuracy=False)
    d = r["bed.d50"]
    k = np.argmax(d >= 450e-6)
    t_cross = r.t[k - 1] + (450e-6 - d[k - 1]) / (d[k] - d[k - 1]) * (r.t[k] - r.t[k - 1])
    assert t_ev == pytest.approx(t_cross, abs=0.05)


SENS_SCENE = ("  - {name: dry, after: hot_air, when: bed.moisture < 1.5 %, do: stop}\n", "")


# The outputs each parameter moves well above the finite differences' noise at rtol 1e-10 (the bed moisture's
# dependence on the initial size is 1e-5 per m, where central differences scatter by 3 % with the step).
@pytest.mark.parametrize("param, rel, names", [("bed.d50_0", 1e-3, ("bed.d10", "bed.d50", "bed.d90")),
                                               ("inlet.V_dot", 1e-3, ("bed.d50", "bed.d90", "bed.moisture"))])
def test_sensitivities_across_events_match_finite_differences(tmp_path, param, rel, names):
    """Both events' times move with the parameter (through d50 and the moisture), so the output sensitivities after
    them are right only with the jump conditions applied at each event."""
    path = _variant(tmp_path, *SENS_SCENE)
    fs = gf.load(path)
    opts = dict(t_end=95 * 60.0, t_out=[0.0, 95 * 60.0], rtol=1e-10, atol=1e-10, warn=False, grid_check=False,
                accuracy=False)
    res = fs.simulate(sensitivities=[param], **opts)
    assert [e["name"] for e in res.events] == ["stop_spray", "hot_air"]  # both events before the compared time
    p0 = fs.get(param)
    h = rel * p0
    vals = []
    for sign in (1, -1):
        fs.set(param, p0 + sign * h)
        vals.append(fs.simulate(**opts).outputs[-1])
    fs.set(param, p0)
    fd = (vals[0] - vals[1]) / (2 * h)
    exact = res.output_sens[-1, 0]
    for name in names:
        j = res.output_names.index(name)
        assert abs(exact[j] - fd[j]) <= 2e-3 * abs(fd[j]), (name, exact[j], fd[j])


def test_event_setting_a_sensitivity_parameter_is_refused():
    fs = gf.load(RECIPE)
    with pytest.raises(gf.ConfigError, match="sensitivity parameter 'inlet.T' is set by event 'hot_air'"):
        fs.simulate(sensitivities=["inlet.T"], warn=False, grid_check=False, accuracy=False)


def test_events_refused_on_an_ode_method(tmp_path):
    path = _variant(tmp_path, "solver: {rtol: 1e-6, atol: 1e-6}", "solver: {rtol: 1e-6, atol: 1e-6, method: bdf}")
    with pytest.raises(gf.ConfigError, match="events, checkpoints and restarts need IDAS"):
        gf.load(path).simulate(warn=False, grid_check=False, accuracy=False)


BAD_EVENTS = {
    "unknown quantity": ("when: bed.d50 >= 450 um", "when: bed.d55 >= 450 um",
                         ["events[0] (stop_spray).when", "'bed.d55' is neither a state nor a reported output"]),
    "wrong unit": ("when: bed.d50 >= 450 um", "when: bed.d50 >= 450 kg", ["events[0] (stop_spray).when", "kg"]),
    "no operator": ("when: bed.d50 >= 450 um", "when: bed.d50 is 450 um",
                    ["events[0] (stop_spray).when = 'bed.d50 is 450 um'", ">=, >, <=, <"]),
    "a setting": ("do: {set: {nozzle.mdot: 0 kg/s}}", "do: {set: {bed.aggregation: 0}}",
                  ["events[0] (stop_spray).do.set.bed.aggregation", "not a parameter", "settings"]),
    "out of bounds": ("do: {set: {nozzle.mdot: 0 kg/s}}", "do: {set: {nozzle.mdot: -1 kg/s}}",
                      ["events[0] (stop_spray).do.set.nozzle.mdot = -1 kg/s", "0 <= value <= 1 kg/s"]),
    "after unknown": ("after: stop_spray,", "after: stop_spraying,",
                      ["events[1] (hot_air).after = 'stop_spraying'", "not an event declared before"]),
    "unknown key": ("phase: drying}", "phase: drying, once: true}",
                    ["events[0] (stop_spray).once", "unknown key (allowed: name, when, do, phase, after, repeat)"]),
    "quadrature": ("when: bed.d50 >= 450 um", "when: nozzle.balance_water_in >= 1 kg",
                   ["events[0] (stop_spray).when", "quadrature"]),
}


@pytest.mark.parametrize("case", sorted(BAD_EVENTS))
def test_bad_events_one_line(tmp_path, case):
    old, new, needles = BAD_EVENTS[case]
    path = _variant(tmp_path, old, new)
    p = cli("run", path, "--out", tmp_path / "out", "--no-plots")
    assert_bad_input(p, *needles, path=path)


LOOP = os.path.join(ROOT, "flowsheets", "continuous_layering_sieve_mill.yaml")
LOOP_LOCATED = os.path.join(ROOT, "flowsheets", "continuous_layering_sieve_mill_located_valve.yaml")


def test_located_valve_of_the_sieve_mill_loop():
    """The loop's discharge valve switched by events: at capacity the discharge is exactly mdot_max, following it is
    exactly the controller's demand (the bed held at M_set without the smoothing's offset), and the product agrees
    with the smoothed valve's within the smoothing's effect."""
    res = gf.load(LOOP_LOCATED).simulate(warn=False, grid_check=False, accuracy=False)
    names = [e["name"] for e in res.events]
    assert names[0] == "valve_at_capacity" and "valve_follows" in names
    t_cap, t_follow = res.events[0]["t"], next(e["t"] for e in res.events if e["name"] == "valve_follows")
    at_cap = (res.t > t_cap) & (res.t < t_follow)
    assert at_cap.sum() > 3
    assert np.all(res["gran.discharge_mdot"][at_cap] == pytest.approx(1000.0 / 3600.0, rel=1e-5))
    following = res.t > t_follow
    assert np.allclose(res["gran.discharge_mdot"][following], res["gran.discharge_demand"][following], rtol=1e-5)
    assert res["gran.mass"][-1] == pytest.approx(100.0, rel=1e-9)
    smooth = gf.load(LOOP).simulate(warn=False, grid_check=False, accuracy=False)
    assert res.summary["d50_um"] == pytest.approx(smooth.summary["d50_um"], rel=1e-5)


THERMOSTAT = """events:
  - {name: heater_off, when: tank2.T > 320 K, do: {set: {feed.T: 300 K}}, repeat: true}
  - {name: heater_on, when: tank2.T < 315 K, do: {set: {feed.T: 350 K}}, repeat: true}
summary:"""


def test_two_position_switch_of_an_input(tmp_path):
    """A thermostat on the demo tanks: the feed temperature's step input is switched to constants by two repeating
    events; tank 2 then stays between the thresholds (but for the lag of tank 1), and the run leaves the flowsheet's
    input as it was (a second run of the same flowsheet gives the same results)."""
    with open(os.path.join(ROOT, "flowsheets", "demo_tanks.yaml")) as f:
        text = f.read().replace("summary:", THERMOSTAT, 1)
    path = tmp_path / "thermostat.yaml"
    path.write_text(text)
    fs = gf.load(path)
    res = fs.simulate(t_end=6000.0, n_out=601, warn=False, grid_check=False, accuracy=False)
    names = [e["name"] for e in res.events]
    assert len(names) >= 3 and names[:3] == ["heater_off", "heater_on", "heater_off"]
    assert all(a != b for a, b in zip(names, names[1:]))  # the switch alternates
    t2 = res["tank2.T"][res.t > res.events[1]["t"]]
    assert 312.0 < t2.min() < 315.0 and 320.0 < t2.max() < 323.0
    again = fs.simulate(t_end=6000.0, n_out=601, warn=False, grid_check=False, accuracy=False)
    assert np.array_equal(res.y, again.y) and again.events == res.events


def test_an_event_that_never_fires_is_named(tmp_path):
    # d50 starts at 200 um: "d50 >= 100 um" already holds when the event is armed, so it never crosses; the run goes
    # to its end without the later events, and the result says which events never fired
    path = _variant(tmp_path, "when: bed.d50 >= 450 um", "when: bed.d50 >= 100 um")
    res = gf.load(path).simulate(warn=False, grid_check=False, accuracy=False)
    assert res.events == []
    notes = [w for w in res.warnings if "never fired" in w]
    assert len(notes) == 3 and "event stop_spray (bed.d50 >= 100 um) never fired" in notes[0]
    # the shipped recipe fires all three, and its stop event ends the run: nothing to say
    res = gf.load(RECIPE).simulate(warn=False, grid_check=False, accuracy=False)
    assert len(res.events) == 3 and not [w for w in res.warnings if "never fired" in w]
