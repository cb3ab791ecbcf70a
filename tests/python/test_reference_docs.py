"""The reference in docs/ says what the code does: generated pages are up to date, the reference of a unit is the
registry's, every scene-format example runs, and the README's Python block runs as written."""
import pathlib
import re
import subprocess
import sys

import numpy as np
import pytest

import granuflow as gf
from granuflow import reference

ROOT = pathlib.Path(__file__).resolve().parents[2]
DOCS = ROOT / "docs"


def test_generated_reference_pages_are_up_to_date():
    pages = reference.pages()
    assert "units/fluid_bed.md" in pages and "kernels/aggregation.md" in pages
    stale = [rel for rel, text in pages.items() if not (DOCS / rel).exists() or (DOCS / rel).read_text() != text]
    assert stale == [], f"run `build/granuflow docs --write docs` (stale: {stale})"
    generated = {str(p.relative_to(DOCS)) for p in DOCS.glob("units/*.md")} | \
        {str(p.relative_to(DOCS)) for p in DOCS.glob("kernels/*.md")}
    assert generated <= set(pages), f"pages of removed units or kernels: {sorted(generated - set(pages))}"


def test_unit_reference_is_what_a_scene_builds():
    ref = gf.unit_reference("fluid_bed")
    ports = {p["name"]: p for p in ref["ports"]}
    assert ports["wetting"]["optional"] and not ports["gas"]["optional"]
    assert ports["wetting"]["kind"] == "wetting" and ports["vapour"]["direction"] == "out"
    settings = {s["name"]: s for s in ref["settings"]}
    assert settings["aggregation"]["default"] == "glass_transition"
    assert "none" in settings["breakage"]["choices"]
    fs = gf.load(str(ROOT / "flowsheets" / "stoeckl_gf25_batch.yaml"))
    for p in ref["params"]:  # the headline scene's bed is a fluid_bed: same parameters, units, bounds
        spec = fs.spec(f"bed.{p['name']}")
        assert (spec["unit"], spec["lower"], spec["upper"]) == (p["unit"], p["lower"], p["upper"]), p["name"]
    outs = {o["name"]: o["unit"] for o in ref["outputs"]}
    assert outs["d50"] == "m" and fs.unit_of("bed.d50") == "m"
    # the particle system's grid shapes the structure: 20 classes give the bed 20 mass states
    fine = fs.text.replace("settings: {classes: 10,", "settings: {classes: 20,")
    assert sum(n.startswith("bed.M_") for n in gf.load_text(fine, "fine").simulate(t_end=1).state_names) == 20
    assert gf.unit_reference("fluid_bed")["particle_system"] == "particles"
    assert str(ref) == (DOCS / "units" / "fluid_bed.md").read_text()  # printed, it is the reference page
    with pytest.raises(gf.ConfigError, match="classes"):
        gf.unit_reference("fluid_bed", {"classes": 1})
    with pytest.raises(gf.ConfigError, match="unknown"):
        gf.unit_reference("no_such_unit")


def test_units_command_prints_a_units_reference_and_rejects_unknown_names():
    exe = [sys.executable, "-m", "granuflow"]
    r = subprocess.run(exe + ["units", "wall_heat_loss"], capture_output=True, text=True)
    assert r.returncode == 0 and "`k_wall`" in r.stdout and "W/(m2 K)" in r.stdout and "paper 001" in r.stdout
    r = subprocess.run(exe + ["units", "fluid_bedd"], capture_output=True, text=True)
    assert r.returncode == 2 and "fluid_bed" in r.stderr and "Traceback" not in r.stderr
    r = subprocess.run(exe + ["kernels", "aggregation"], capture_output=True, text=True)
    assert r.returncode == 0 and "`glass_transition`" in r.stdout


def _blocks(path: pathlib.Path, lang: str) -> list[str]:
    return re.findall(rf"```{lang}\n(.*?)```", path.read_text(), flags=re.S)


def test_every_scene_format_example_runs():
    blocks = [b for b in _blocks(DOCS / "scene_format.md", "yaml") if re.match(r"^scene:", b)]
    assert len(blocks) >= 5
    from granuflow.plots.spec import plot_specs

    for k, text in enumerate(blocks):
        fs = gf.load_text(text, f"docs/scene_format.md example {k + 1}")
        plot_specs(fs, drawing=False)
        res = fs.simulate()
        assert np.isfinite(res.y).all(), k
        assert res.t[-1] == pytest.approx(fs.t_end)


def test_readme_python_block_runs_as_written(tmp_path):
    blocks = _blocks(ROOT / "README.md", "python")
    assert blocks, "the README has a Python block"
    code = "\n".join(blocks)
    env = {"PYTHONPATH": str(pathlib.Path(gf.__file__).resolve().parents[1]), "MPLBACKEND": "Agg"}
    r = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True, env=env, timeout=600)
    assert r.returncode == 0, r.stderr[-3000:]


def test_docs_are_self_contained():
    """Nothing in the repository's documents points outside it (a clone has no ../shared)."""
    texts = [p.read_text() for p in DOCS.rglob("*.md")] + [(ROOT / "README.md").read_text()]
    assert not any("../shared" in t or "shared/" in t for t in texts)
    for name in ("paper001_decisions.md", "verification.md", "design.md", "references.md", "scene_format.md",
                 "glossary.md"):
        assert (DOCS / name).exists(), name
