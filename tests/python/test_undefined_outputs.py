"""Issue 29: a size of nothing is not a number, and solids do not vanish from an empty bed.

- "No product" is not a size: a loop that discharges nothing (k_discharge = 0) reported its product d50 as 0.0 um.
  A size statistic of an empty population or stream is NaN in the time series and null in summary.json, with the
  reason in `null_reasons`; never 0.
- Solids vanish from an empty bed: the sieve-mill loop with bed_mass = 0 took 1,800 kg of sprayed solids in 30 h
  and reported a bed of 0 kg, solids_rel 1.0 and d50 0.0 um. The spray layers onto the particles' surface and the
  model has no nucleation from the spray, so an empty bed under a spray is refused with one line.
"""
import math
import os

import numpy as np
import pytest

import granuflow as gf

from conftest import ROOT, assert_bad_input, cli, strict_json

FREE = os.path.join(ROOT, "flowsheets", "continuous_layering_free_holdup.yaml")
LOOP = os.path.join(ROOT, "flowsheets", "continuous_layering_sieve_mill.yaml")


def test_no_product_has_no_size_in_the_summary(tmp_path):
    out = tmp_path / "out"
    p = cli("run", FREE, "--set", "gran.k_discharge=0", "--t-end", "10 h", "--out", out, "--no-plots")
    assert p.returncode == 0, p.stderr
    s = strict_json(out / "summary.json")  # no NaN in the file
    assert s["product_kg_s"] == 0.0  # nothing is discharged: the product stream is empty
    for key in ("d10_um", "d50_um", "d90_um"):
        assert s[key] is None, (key, s[key])
        assert "undefined" in s["null_reasons"][key] and "no particles" in s["null_reasons"][key]
    # the bed itself has a size, and says nothing
    assert s["bed_mass_kg"] > 0 and "bed_mass_kg" not in s["null_reasons"]


def test_every_size_of_an_empty_population_or_stream_is_nan_not_zero():
    fs = gf.load(FREE)
    # no spray and no bed: the granulator is empty until the seeds arrive; its product stream is empty at t = 0
    fs.update({"gran.k_discharge": 0.0, "seeds.mdot": 0.0})
    res = fs.simulate(t_end=3600.0, n_out=3, warn=False)
    for name in ("product.d10", "product.d50", "product.d90", "mill.d50_in", "mill.d50_out"):
        assert np.all(np.isnan(res[name])), (name, res[name])
    # a filled population keeps its sizes
    assert np.all(res["gran.d50"] > 0) and np.all(np.isfinite(res["gran.sigma"]))
    empty = gf.load(FREE)
    empty.update({"gran.bed_mass": 0.0, "gran.m_spray": 0.0, "seeds.mdot": 0.0})
    r = empty.simulate(t_end=3600.0, n_out=3, warn=False)
    for name in ("gran.d10", "gran.d50", "gran.d90", "gran.d_mean", "gran.sigma", "gran.d32"):
        assert np.all(np.isnan(r[name])), (name, r[name])
    assert r.summary["d50_um"] is None and "d50_um" in r.summary["null_reasons"]
    assert not any(isinstance(v, float) and math.isnan(v) for v in r.summary.values())


def test_an_empty_bed_under_a_spray_is_refused_in_one_line(tmp_path):
    p = cli("run", LOOP, "--set", "gran.bed_mass=0", "--t-end", "30 h", "--out", tmp_path / "o", "--no-plots")
    assert_bad_input(p, "bed_mass = 0 kg", "m_spray", "empty bed")
    assert not (tmp_path / "o" / "summary.json").exists()
    # a spray switched on later over the empty bed is refused as well (the check runs at every input step)
    with open(LOOP) as f:
        text = f.read()
    text = text.replace("values: [200 kg/h, 240 kg/h]", "values: [0 kg/h, 240 kg/h]").replace(
        "bed_mass: 100 kg,", "bed_mass: 0 kg,")
    later = tmp_path / "later.yaml"
    later.write_text(text)
    p = cli("run", later, "--out", tmp_path / "o2", "--no-plots")
    assert_bad_input(p, "bed_mass = 0 kg", "t = 216000 s")
    fs = gf.load(LOOP)
    fs.set("gran.bed_mass", 0.0)
    with pytest.raises(gf.ConfigError, match="bed_mass"):
        fs.simulate(t_end=3600.0)
