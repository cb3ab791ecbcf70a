"""Every notebook in flowsheets/notebooks runs headless from top to bottom without an error (nbclient)."""
import glob
import json
import os
import re
import sys
import time

import pytest
from conftest import PKG_PATH, ROOT

NOTEBOOKS = sorted(glob.glob(os.path.join(ROOT, "flowsheets", "notebooks", "*.ipynb")))

nbformat = pytest.importorskip("nbformat", reason="Debian python3-nbformat")
nbclient = pytest.importorskip("nbclient", reason="Debian python3-nbclient")
pytest.importorskip("ipykernel", reason="Debian python3-ipykernel")


@pytest.fixture()
def kernel_env(tmp_path, monkeypatch):
    """A private kernelspec 'python3' that runs this interpreter (Debian's /usr/bin/python3, which sees NumPy,
    pandas and matplotlib), found first through JUPYTER_PATH; the kernel inherits the package path."""
    spec = tmp_path / "jupyter" / "kernels" / "python3"
    spec.mkdir(parents=True)
    (spec / "kernel.json").write_text(json.dumps({
        "argv": [sys.executable, "-m", "ipykernel_launcher", "-f", "{connection_file}"],
        "display_name": "Python 3 (granuflow tests)", "language": "python"}))
    monkeypatch.setenv("JUPYTER_PATH", str(tmp_path / "jupyter"))
    monkeypatch.setenv("GRANUFLOW_PYTHONPATH", PKG_PATH)
    monkeypatch.setenv("PYTHONPATH", os.pathsep.join(filter(None, [PKG_PATH, os.environ.get("PYTHONPATH")])))
    monkeypatch.setenv("MPLCONFIGDIR", str(tmp_path / "mpl"))
    monkeypatch.setenv("PYDEVD_DISABLE_FILE_VALIDATION", "1")  # quiet debugpy in the kernel
    monkeypatch.delenv("GRANUFLOW_ROOT", raising=False)


def test_there_are_notebooks():
    assert NOTEBOOKS, "flowsheets/notebooks/*.ipynb"


@pytest.mark.parametrize("path", NOTEBOOKS, ids=[os.path.basename(p) for p in NOTEBOOKS])
def test_notebook_runs_headless(path, kernel_env):
    nb = nbformat.read(path, as_version=4)
    before = open(path, "rb").read()
    client = nbclient.NotebookClient(nb, timeout=120, kernel_name="python3",
                                     resources={"metadata": {"path": os.path.dirname(path)}})
    t0 = time.perf_counter()
    client.execute()  # raises CellExecutionError naming the cell and the traceback
    wall = time.perf_counter() - t0
    print(f"{os.path.basename(path)}: {wall:.1f} s")
    errors = [o for c in nb.cells if c.cell_type == "code" for o in c.get("outputs", []) if o.output_type == "error"]
    assert not errors
    # a notebook that prints where granuflow came from used the package under test, not another installation
    for c in nb.cells:
        for o in c.get("outputs", []) if c.cell_type == "code" else []:
            text = o.get("text", "") if o.output_type == "stream" else ""
            if text.startswith("granuflow ") and " from " in text:
                assert PKG_PATH in text, text
    # every notebook that builds a flowsheet shows it (Flowsheet.diagram(): an SVG Graphviz drew); the Monte Carlo
    # has no flowsheet
    svgs = [o["data"]["image/svg+xml"] for c in nb.cells if c.cell_type == "code" for o in c.get("outputs", [])
            if "image/svg+xml" in o.get("data", {})]
    if any(re.search(r"\bgf\.load(_text)?\(", c.source) for c in nb.cells if c.cell_type == "code"):
        assert any("<svg" in s and "class=\"node\"" in s for s in svgs), "the notebook shows no flowsheet diagram"
    assert open(path, "rb").read() == before  # executed in memory; the file stays as committed
    assert wall < 90, f"{os.path.basename(path)} took {wall:.0f} s; keep notebooks small"
