"""Flowsheet diagrams (issue 33 §4): every unit and connection of a scene in the Graphviz text, stream kinds as
labels, the sieve-mill loop's recycle marked and the headline's gas/vapour return not, probes dotted; the CLI writes
SVG and PNG that Graphviz really drew, and refuses an unknown format with one line."""
import os
import xml.etree.ElementTree as ET

import pytest
from conftest import cli

import granuflow as gf

HERE = os.path.dirname(os.path.abspath(__file__))
FLOWSHEETS = os.path.join(HERE, "..", "..", "flowsheets")
LOOP = os.path.join(FLOWSHEETS, "continuous_layering_sieve_mill.yaml")
HEADLINE = os.path.join(FLOWSHEETS, "stoeckl_gf25_batch.yaml")


def _edges(dot):
    return [line.strip() for line in dot.splitlines() if "->" in line and "label" in line]


def test_the_loops_recycle_is_marked_and_only_it():
    dot = gf.load(LOOP).diagram().dot
    recycles = [e for e in _edges(dot) if 'xlabel="recycle"' in e]
    assert len(recycles) == 1 and recycles[0].startswith('"recycle" -> "gran"')
    assert 'label="solids"' in recycles[0]
    for unit, typ in [("gran", "granulator"), ("sieve", "sieve"), ("mill", "mill"), ("product", "solids_product")]:
        assert f"<b>{unit}</b>" in dot and typ in dot


def test_headline_diagram_has_every_connection_with_its_kind():
    import yaml
    fs = gf.load(HEADLINE)
    dot = fs.diagram().dot
    scene = yaml.safe_load(fs.text)
    edges = _edges(dot)
    assert len(edges) == len(scene["connections"])
    assert not [e for e in edges if 'xlabel="recycle"' in e]          # a material return of gas or vapour is no recycle
    assert any('label="vapour"' in e and e.startswith('"bed" -> "gas"') for e in edges)
    probes = [e for e in edges if "(probe)" in e]
    assert probes and all("style=dotted" in e for e in probes)
    for name, spec in scene["units"].items():
        assert f"<b>{name}</b>" in dot and spec["type"] in dot


def test_inline_svg_is_real_graphviz_output():
    svg = gf.load(LOOP).diagram()._repr_svg_()
    root = ET.fromstring(svg[svg.index("<svg"):])
    texts = {t.text for t in root.iter("{http://www.w3.org/2000/svg}text")}
    assert {"gran", "sieve", "mill", "recycle", "product"} <= texts


def test_cli_draws_svg_and_png_and_refuses_other_formats(tmp_path):
    for ext in ("svg", "png"):
        out = tmp_path / f"loop.{ext}"
        r = cli("draw", LOOP, "--out", out)
        assert r.returncode == 0, r.stderr
        data = out.read_bytes()
        assert data.startswith(b"\x89PNG") if ext == "png" else b"<svg" in data
    r = cli("draw", LOOP, "--out", tmp_path / "loop.jpg")
    assert r.returncode == 2 and "extension '.jpg' not supported" in r.stderr and len(r.stderr.splitlines()) == 1


def _scenes():
    """The shipped scenes (sweep files in the same folder hold `variables:`, not `units:`)."""
    return sorted(f for f in os.listdir(FLOWSHEETS) if f.endswith(".yaml")
                  and "\nunits:" in open(os.path.join(FLOWSHEETS, f), encoding="utf-8").read())


@pytest.mark.parametrize("scene", _scenes())
def test_every_shipped_scene_draws(scene):
    d = gf.load(os.path.join(FLOWSHEETS, scene)).diagram()
    assert d.dot.count("[label=<<b>") >= 1 and "<svg" in d.svg


def test_a_controllers_signals_are_drawn_as_dashed_lines():
    dot = gf.load(os.path.join(FLOWSHEETS, "stoeckl_gf25_batch_controlled.yaml")).diagram().dot
    signals = [e for e in _edges(dot) if "style=dashed" in e and "constraint=false" in e]
    assert any(e.startswith('"gas" -> "tic" [label="measure gas.T"') for e in signals)
    assert any(e.startswith('"tic" -> "inlet" [label="drive inlet.T"') for e in signals)
    assert len(signals) == 2
