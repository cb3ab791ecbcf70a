"""The ends of the size grid (issue 12): the mass fraction at or beyond each end is reported (summary.json
`grid_end`), and a result whose grid clips the distribution, or whose initial distribution lies outside the grid,
warns: in summary.json under `warnings`, on stderr, and as a Python GridWarning."""
import json
import warnings

import pytest

from conftest import SCENE, cli, sha256

import granuflow as gf
from granuflow import outputs, sweep

with open(SCENE) as _f:
    HEADLINE = _f.read()
GRID = "settings: {classes: 10, d_min: 50e-6, d_max: 1000e-6}"
assert GRID in HEADLINE


def headline(old=None, new=None):
    text = HEADLINE if old is None else HEADLINE.replace(old, new, 1)
    return gf.load_text(text, "scene.yaml")


def test_the_headline_grid_clips_the_product_and_says_so():
    with pytest.warns(gf.GridWarning, match="top size class") as caught:
        r = headline().simulate()
    # the top class, d90 inside it, and the grid error of the grid check (issue 28)
    assert len(caught) == 3
    ends = r.grid_ends()
    top = ends["bed.top_class"]
    # the fraction is the fluid bed's own top_class_fraction (OutputRole kGridEnd), not a count of collisions
    assert top["final"] == pytest.approx(r["bed.top_class_fraction"][-1], rel=1e-12)
    assert 0.15 < top["final"] < 0.3 and top["final"] <= 1.0
    assert top["initial"] < 1e-3  # the initial distribution is inside the grid
    assert top["d_um"] == pytest.approx(1000.0)
    # the fraction is that of the mass: the last class over the bed's solids
    m = r.psd(r.t[-1])["mass_kg"].to_numpy()
    assert top["final"] == pytest.approx(m[-1] / m.sum(), rel=1e-12)
    s = r.summary
    assert s["grid_end"]["bed.top_class"]["final"] == pytest.approx(top["final"])
    assert len(s["warnings"]) == 3
    w = s["warnings"][0]
    # numerical smearing (20.8 % on 10 classes, 9.9 % on 19: towards zero), so the cure is more classes, not d_max
    for needle in ("bed:", "20.8 %", "top size class (1000 um)", "numerical smearing", "more classes",
                   "not a wider grid (d_max)"):
        assert needle in w, (needle, w)


def test_a_wider_grid_does_not_warn():
    # 3 mm top pivot, the same class width as the headline's: the end classes stay nearly empty
    r = headline(GRID, "settings: {classes: 15, d_min: 50e-6, d_max: 3000e-6}").simulate(warn=False)
    assert r.warnings == []  # (the grid check is off with warn=False; on, it would report d90's grid error)
    ends = r.grid_ends()
    assert ends["bed.top_class"]["max"] < outputs.GRID_END_WARNING
    assert ends["bed.bottom_class"]["max"] < outputs.GRID_END_WARNING
    with warnings.catch_warnings():
        warnings.simplefilter("error", gf.GridWarning)
        wide = headline(GRID, "settings: {classes: 15, d_min: 50e-6, d_max: 3000e-6}")
        wide.simulate(t_end=60.0, grid_check=False)


def test_an_initial_distribution_outside_the_grid_warns_at_t0():
    # d50_0 = 1 cm on a grid ending at 1 mm: folded into the top class, d50 starts at the top pivot
    fs = headline()
    fs.set("bed.d50_0", "1 cm")
    with pytest.warns(gf.GridWarning, match="initial size distribution lies outside the grid"):
        r = fs.simulate(t_end=60.0)
    assert r.grid_ends()["bed.top_class"]["initial"] > 0.99
    assert r["bed.d50"][0] == pytest.approx(r.grid_ends()["bed.top_class"]["d_um"] * 1e-6, rel=0.05)
    assert "% of the initial mass is in the top size class (1000 um)" in r.warnings[0]
    assert "d_min, d_max" in r.warnings[0]
    # the bottom end too: d50_0 = 5 um below a 50 um bottom pivot
    fs.set("bed.d50_0", "5 um")
    r = fs.simulate(t_end=60.0, warn=False)
    assert r.grid_ends()["bed.bottom_class"]["initial"] > 0.99
    assert "bottom size class" in r.warnings[0]


def test_the_command_line_warns_on_stderr_and_in_summary_json(tmp_path):
    before = sha256(SCENE)
    p = cli("run", SCENE, "--out", tmp_path / "out", "--no-plots")
    assert p.returncode == 0, p.stderr
    lines = p.stderr.strip().splitlines()
    assert len(lines) == 3 and lines[0].startswith("granuflow: warning: bed: 20.8 % of the mass"), p.stderr
    s = json.loads((tmp_path / "out" / "summary.json").read_text())
    assert s["warnings"] == [x[len("granuflow: warning: "):] for x in lines]
    assert s["units"]["grid_end"].startswith("mass fraction")
    assert sha256(SCENE) == before


def test_sweep_points_carry_the_warning_in_their_message():
    df = sweep.run_sweep(headline(), [{"nozzle.mdot": "30 g/min"}, {"nozzle.mdot": "120 g/min"}], ["d50_um"],
                         progress=False, workers=1)
    assert df["status"].tolist() == ["ok", "ok"]
    # little spray, little growth: inside the grid; a lot of spray: clipped
    assert df["message"][0] == ""
    assert df["message"][1].startswith("warning: bed:") and "top size class" in df["message"][1]


def test_no_stale_output_names():
    import inspect

    assert "mass_through_top" not in inspect.getsource(outputs)  # the collision count of old, gone from the core
    assert not any("mass_through_top" in n for n in headline().output_names)
    assert outputs.readable("bed.top_class_fraction") == "mass fraction in the top class (bed)"
    assert 0 < outputs.GRID_END_WARNING < 0.5
