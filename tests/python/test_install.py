"""Installed like a package (docs/install_and_plugins.md): one version everywhere, and `pip install` of this checkout
into a fresh virtual environment (system site packages, no network: --no-build-isolation --no-index), then
`granuflow run` of the headline scene and `import granuflow` from another folder, and the example plugin built
against the installed package's CMake files.

The install test (marker `install`, part of the README's test command) costs one CMake build with ccache: its
CMake folder sits beside the build folder (build-pip-test) and its environment under it (build/pip-test), so paths,
and with them ccache's entries, stay the same from run to run, and it configures the pip build as the build folder
is configured (GRANUFLOW_NATIVE, tests), so the objects are ccache hits of that build. What a plain
`pip install .` changes, the portable default GRANUFLOW_NATIVE=OFF, docs/install_and_plugins.md discusses."""
import json
import os
import re
import shutil
import subprocess
import sys

import pytest

import granuflow as gf
from conftest import PKG_PATH, ROOT, SCENE, cli

BUILD = os.path.dirname(PKG_PATH)
HERE = os.path.join(BUILD, "pip-test")


def cmake_version():
    return re.search(r"^project\(granuflow VERSION ([0-9.]+)", open(os.path.join(ROOT, "CMakeLists.txt")).read(),
                     re.M).group(1)


def cache_value(key):
    m = re.search(rf"^{key}:[A-Z]+=(.*)$", open(os.path.join(BUILD, "CMakeCache.txt")).read(), re.M)
    return m.group(1) if m else ""


def test_one_version_everywhere():
    v = cmake_version()
    assert gf.__version__ == v
    assert cli("--version").stdout.strip() == f"granuflow {v}"
    assert gf.plugins.abi_tag().startswith(f"granuflow {v} ")
    header = open(os.path.join(BUILD, "generated", "include", "granuflow", "version.hpp")).read()
    assert f'#define GRANUFLOW_VERSION "{v}"' in header
    setup = subprocess.run([sys.executable, os.path.join(ROOT, "setup.py"), "--version"], capture_output=True,
                           text=True, cwd=ROOT, timeout=60)
    assert setup.stdout.strip().splitlines()[-1] == v
    cff = open(os.path.join(ROOT, "CITATION.cff")).read()
    assert re.search(rf"^version: {re.escape(v)}$", cff, re.M)
    assert f"## {v} " in open(os.path.join(ROOT, "CHANGELOG.md")).read()
    # no second definition in the sources
    init = open(os.path.join(ROOT, "python", "granuflow", "__init__.py")).read()
    assert not re.search(r"__version__\s*=", init)


def run(cmd, **kw):
    p = subprocess.run([str(c) for c in cmd], capture_output=True, text=True, **kw)
    assert p.returncode == 0, (cmd, p.stdout[-3000:], p.stderr[-3000:])
    return p


@pytest.mark.install
def test_pip_install_into_a_fresh_venv_and_run_from_another_folder(tmp_path):
    venv = os.path.join(HERE, "venv")
    shutil.rmtree(venv, ignore_errors=True)
    run(["/usr/bin/python3", "-m", "venv", "--system-site-packages", venv], timeout=300)
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "GRANUFLOW_PLUGIN_PATH")}
    # beside the build folder, at its depth: ccache configured with base_dir hashes include paths relative to the
    # build folder, so only a folder at the same depth hits the build's entries
    env["GRANUFLOW_PIP_BUILD_DIR"] = BUILD + "-pip-test"
    launcher = cache_value("CMAKE_CXX_COMPILER_LAUNCHER")
    if launcher:
        env["CMAKE_CXX_COMPILER_LAUNCHER"] = launcher
    native = cache_value("GRANUFLOW_NATIVE") or "ON"
    tests = cache_value("GRANUFLOW_BUILD_TESTS") or "ON"
    env["GRANUFLOW_CMAKE_ARGS"] = f"-DGRANUFLOW_NATIVE={native} -DGRANUFLOW_BUILD_TESTS={tests}"
    run([os.path.join(venv, "bin", "pip"), "install", "--no-build-isolation", "--no-index", ROOT], env=env,
        cwd=tmp_path, timeout=3600)

    # from a folder that is neither the checkout nor the build
    away = tmp_path / "elsewhere"
    away.mkdir()
    exe = os.path.join(venv, "bin", "granuflow")
    assert run([exe, "--version"], env=env, cwd=away).stdout.strip() == f"granuflow {gf.__version__}"
    where = run([os.path.join(venv, "bin", "python"), "-c",
                 "import granuflow, granuflow.plugins as p; print(granuflow.__file__); print(p.cmake_prefix())"],
                env=env, cwd=away).stdout.split()
    assert where[0].startswith(venv) and where[1].startswith(venv)
    run([exe, "run", SCENE, "--out", away / "out", "--no-plots", "--no-grid-check", "--quiet"], env=env, cwd=away,
        timeout=600)
    mine = cli("run", SCENE, "--out", tmp_path / "ref", "--no-plots", "--no-grid-check", "--quiet", timeout=600)
    assert mine.returncode == 0, mine.stderr
    installed = json.loads((away / "out" / "summary.json").read_text())["d50_um"]
    reference = json.loads((tmp_path / "ref" / "summary.json").read_text())["d50_um"]
    assert installed == reference  # the same compiler options: the same bits

    # the example plugin against the pip-installed package's CMake files, run by the installed command
    plugin_build = os.path.join(HERE, "plugin")
    cmake = ["cmake", "-S", os.path.join(ROOT, "examples", "plugin"), "-B", plugin_build, "-G", "Ninja",
             "-DCMAKE_BUILD_TYPE=Release", f"-DCMAKE_PREFIX_PATH={where[1]}"]
    run(cmake + ([f"-DCMAKE_CXX_COMPILER_LAUNCHER={launcher}"] if launcher else []), env=env, timeout=300)
    run(["cmake", "--build", plugin_build], env=env, timeout=900)
    scene = away / "example_scene.yaml"
    scene.write_text(open(os.path.join(ROOT, "examples", "plugin", "example_scene.yaml")).read().replace(
        "build/libgranuflow_example_plugin.so", os.path.join(plugin_build, "libgranuflow_example_plugin.so")))
    run([exe, "run", scene, "--out", away / "plugin_out", "--no-plots", "--no-grid-check", "--quiet"], env=env,
        cwd=away, timeout=600)
    summary = json.loads((away / "plugin_out" / "summary.json").read_text())
    assert summary["T_tank_K"] == pytest.approx(324.45, abs=0.01)  # the tank's steady state (scene header)
