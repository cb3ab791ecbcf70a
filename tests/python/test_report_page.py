"""The report page (issue 33 §5): `granuflow report OUT` writes one self-contained HTML page for a run, a steady
state, a sweep, a contour map and a calibration. Each page is rendered by headless Chromium (Debian's chromium,
installed by run.sh): the screenshot must show the page's banner, the flowsheet diagram's nodes and the embedded
plots, and the browser must report no console error and no failed load (the page works offline)."""
import os
import re
import shutil
import subprocess

import numpy as np
import pytest
from conftest import cli

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
FS = os.path.join(ROOT, "flowsheets")
CHROMIUM = shutil.which("chromium") or "/usr/bin/chromium"
BANNER = (0x1F, 0x4E, 0x79)      # report.py's header colour
NODE_FILL = (0xF4, 0xF4, 0xF4)   # the diagram's node fill (diagram.py)
PLOT_BLUE = (0x1F, 0x77, 0xB4)   # matplotlib's first line colour, in the embedded plots

COMMANDS = {
    "run": ["run", f"{FS}/stoeckl_gf25_batch.yaml"],
    "steady": ["steady", f"{FS}/demo_tanks.yaml"],
    "sweep": ["sweep", f"{FS}/stoeckl_gf25_table1.yaml", "--workers", "1", "--quiet"],
    "contour": ["contour", f"{FS}/stoeckl_gf25_batch.yaml", "--x", "inlet.T:degC:40:80:4", "--y",
                "nozzle.mdot:g/min:60:120:4", "--output", "d50_um", "--workers", "1", "--quiet"],
    "calibrate": ["calibrate", f"{FS}/calibration/synthetic_gf25_table1.yaml", "--stages",
                  f"{FS}/calibration/stages_paper001.yaml", "--workers", "2", "--quiet"],
}


@pytest.fixture(scope="module")
def pages(tmp_path_factory):
    base = tmp_path_factory.mktemp("report")
    out = {}
    for kind, args in COMMANDS.items():
        folder = base / kind
        r = cli(*args, "--out", folder, timeout=300)
        assert r.returncode == 0, r.stderr
        r = cli("report", folder)
        assert r.returncode == 0 and (folder / "report.html").is_file(), r.stderr
        out[kind] = folder / "report.html"
    return out


def _render(page, tmp_path, height=2400):
    """(screenshot as an RGB array, the browser's log) of a page rendered by headless Chromium."""
    shot = tmp_path / (page.parent.name + ".png")
    cmd = [CHROMIUM, "--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
           "--disable-background-networking", "--disable-component-update", "--disable-sync", "--hide-scrollbars",
           f"--user-data-dir={tmp_path / 'profile'}", f"--window-size=1280,{height}", f"--screenshot={shot}",
           "--enable-logging=stderr", "--v=0", page.as_uri()]
    done = subprocess.run(cmd, capture_output=True, text=True, timeout=120)
    assert done.returncode == 0 and shot.is_file(), done.stderr[-2000:]
    import matplotlib.image as mpimg
    img = (mpimg.imread(shot)[..., :3] * 255).round().astype(int)
    return img, done.stderr


def _problems(log):
    """Console errors and failed loads in Chromium's log."""
    return [line for line in log.splitlines()
            if re.search(r"CONSOLE|Failed to load resource|net::ERR_|Not allowed to load", line)]


def _share(img, colour, tol=3):
    return float(np.mean(np.all(np.abs(img - np.array(colour)) <= tol, axis=-1)))


def test_chromium_is_installed():
    assert os.access(CHROMIUM, os.X_OK), "run.sh installs Debian's chromium for this test"


@pytest.mark.parametrize("kind", list(COMMANDS))
def test_page_is_self_contained(pages, kind):
    text = pages[kind].read_text(encoding="utf-8")
    assert "<script" not in text.lower()
    assert not re.search(r"""(src|href)\s*=\s*["'](?!data:|#)""", text), "the page must not load anything"
    assert "url(" not in text and "@import" not in text
    for section in ("flowsheet", "results", "checks", "plots", "provenance"):
        assert f'id="{section}"' in text
    assert "granuflow " + COMMANDS[kind][0] in text   # the command that made the folder


@pytest.mark.parametrize("kind", list(COMMANDS))
def test_chromium_renders_each_page_without_errors(pages, kind, tmp_path):
    img, log = _render(pages[kind], tmp_path)
    assert not _problems(log), _problems(log)
    assert _share(img[:40], BANNER) > 0.8                     # the banner across the top
    assert _share(img[60:700], NODE_FILL) > 0.002             # the diagram's unit boxes
    if kind in ("run", "contour", "calibrate"):               # these folders hold plots
        assert _share(img, PLOT_BLUE, tol=10) > 1e-4 or _share(img, (0xFF, 0x7F, 0x0E), tol=10) > 1e-4


def test_run_page_shows_results_balances_and_warnings(pages):
    text = pages["run"].read_text(encoding="utf-8")
    assert "d50_um" in text and "499.702" in text                       # the headline's result with its unit
    assert "solids_rel" in text and "d90_um is null" in text             # balances and a null with its reason
    assert "estimated relative error" in text and "+16.11%" in text      # the grid check's estimate of d50
    assert "scene: stoeckl_gf25_batch" in text                           # the scene's own text


def test_console_check_catches_a_page_that_loads_from_the_network(tmp_path):
    bad = tmp_path / "bad" / "report.html"
    bad.parent.mkdir()
    bad.write_text('<!DOCTYPE html><html><body><img src="http://192.0.2.1/x.png">'
                   '<script>console.error("boom")</script></body></html>')
    _, log = _render(bad, tmp_path, height=300)
    assert _problems(log)


def test_report_refuses_a_folder_that_is_not_an_output(tmp_path):
    r = cli("report", tmp_path)
    assert r.returncode == 2 and "not an output folder of granuflow" in r.stderr
