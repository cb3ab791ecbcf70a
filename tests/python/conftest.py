import hashlib
import json
import os
import subprocess
import sys

# The package lives in a build tree (CMake copies it next to the compiled _core). PYTHONPATH wins when it names
# one (e.g. another build directory); otherwise fall back to the repository's build/python.
ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
BUILD_PY = os.path.join(ROOT, "build", "python")
if BUILD_PY not in sys.path:
    sys.path.append(BUILD_PY)

import granuflow as gf  # noqa: E402  (after the path set-up above)

SCENE = os.path.join(ROOT, "flowsheets", "stoeckl_gf25_batch.yaml")
DEMO = os.path.join(ROOT, "flowsheets", "demo_tanks.yaml")
# The headline's d50 in um (docs/accuracy.md), and how far another CPU may move it: the build targets the machine it
# runs on (-march=native), and Eigen's SIMD kernels round with their packet width. Two build machines of this project,
# one with AVX-512, differ by 1.1e-13 relative. That a change moves no bit on one machine is what
# tests/tools/scene_snapshot.py checks; a change of the model moves the value by far more than CPU_REL.
HEADLINE_D50_UM = 499.701648945565
CPU_REL = 1e-12
# the python/ folder holding the granuflow package under test; the command line and subprocesses use the same one
PKG_PATH = os.path.dirname(os.path.dirname(os.path.abspath(gf.__file__)))


def package_env(**extra):
    """The environment of a subprocess that must import the package under test (not another build's)."""
    return dict(os.environ, PYTHONPATH=os.pathsep.join(filter(None, [PKG_PATH, os.environ.get("PYTHONPATH")])),
                **extra)


def cli(*args, timeout=120):
    """``granuflow ARGS`` through the launcher of the build that holds the package under test (its build dir's
    ``granuflow`` script; ``python -m granuflow`` where there is none)."""
    launcher = os.path.join(os.path.dirname(PKG_PATH), "granuflow")
    cmd = [launcher] if os.access(launcher, os.X_OK) else [sys.executable, "-m", "granuflow"]
    return subprocess.run(cmd + [str(a) for a in args], capture_output=True, text=True, timeout=timeout,
                          env=package_env())


def sha256(path):
    with open(path, "rb") as f:
        return hashlib.sha256(f.read()).hexdigest()


def strict_json(path):
    """JSON as the standard has it: NaN or Infinity in the file fail the test."""
    def no_nan(token):
        raise AssertionError(f"{path}: {token} in JSON")

    with open(path) as f:
        return json.loads(f.read(), parse_constant=no_nan)


def assert_bad_input(p, *needles, path=None):
    """Exit 2 with one stderr line 'granuflow: bad input: ...' that names `path` (when given) and every needle."""
    assert p.returncode == 2, (p.returncode, p.stderr)
    assert "Traceback" not in p.stderr, p.stderr
    lines = p.stderr.strip().splitlines()
    assert len(lines) == 1, p.stderr
    assert lines[0].startswith("granuflow: bad input: "), lines[0]
    if path is not None:
        assert str(path) in lines[0], (path, lines[0])
    for needle in needles:
        assert needle in lines[0], (needle, lines[0])


def scene_with(tmp_path, old, new, name="scene.yaml"):
    """A copy of the headline scene with its first `old` (which must occur) replaced by `new`."""
    with open(SCENE) as f:
        text = f.read()
    assert old in text, old
    path = tmp_path / name
    path.write_text(text.replace(old, new, 1))
    return path


def run_bad_scene(tmp_path, path, *needles, out=None):
    """`granuflow run` on bad input: exit 2 with one line naming `path` and the needles, the file untouched and
    no summary written."""
    before = sha256(path)
    out = out or tmp_path / "out"
    p = cli("run", path, "--out", out)
    assert_bad_input(p, *needles, path=path)
    assert sha256(path) == before
    assert not os.path.exists(os.path.join(out, "summary.json"))
    return p
