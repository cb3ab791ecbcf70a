"""Installed like a package (docs/install_and_plugins.md): one version everywhere, and `pip install` of this checkout
into a fresh virtual environment (system site packages, no network: --no-build-isolation --no-index), then
`granuflow run` of the headline scene and `import granuflow` from another folder, find_package(granuflow) against the
installed package's CMake files, and the example plugin run by the installed command.

The install reuses the build folder (GRANUFLOW_PREBUILT_DIR, setup.py): pip compiles nothing, it installs that
folder (cmake --install) and its Python package into the wheel, so the test costs seconds, not a second build of the
core. The example plugin is the one the ctest plugin.example_build built against this build installed into a folder
(cmake --install, tests/tools/build_plugin_example.cmake; incremental here). That `pip install .` without a build
folder builds everything, setup.py's own path, docs/install_and_plugins.md shows."""
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


def test_one_version_everywhere():
    v = cmake_version()
    assert gf.__version__ == v
    assert cli("--version").stdout.strip() == f"granuflow {v} ({gf.build_info()['isa']})"
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
    run(["/usr/bin/python3", "-m", "venv", "--system-site-packages", "--without-pip", venv], timeout=300)
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "GRANUFLOW_PLUGIN_PATH")}
    env["GRANUFLOW_PREBUILT_DIR"] = BUILD
    # Debian's pip (system site packages) installs into the environment it runs from
    py = os.path.join(venv, "bin", "python")
    run([py, "-m", "pip", "install", "--no-build-isolation", "--no-index", ROOT], env=env,
        cwd=tmp_path, timeout=900)

    # from a folder that is neither the checkout nor the build
    away = tmp_path / "elsewhere"
    away.mkdir()
    exe = os.path.join(venv, "bin", "granuflow")
    isa = gf.build_info()["isa"]
    assert run([exe, "--version"], env=env, cwd=away).stdout.strip() == f"granuflow {gf.__version__} ({isa})"
    where = run([py, "-c", "import granuflow, granuflow.plugins as p; print(granuflow.__file__); "
                 "print(p.cmake_prefix()); print(*granuflow.build_info()['core_libraries'])"], env=env,
                cwd=away).stdout.split()
    assert where[0].startswith(venv) and where[1].startswith(venv)
    # the installed extension runs the installed core libraries, not the build folder's
    assert len(where) >= 5 and all(os.path.realpath(f).startswith(os.path.realpath(where[1])) for f in where[2:])
    run([exe, "run", SCENE, "--out", away / "out", "--no-plots", "--no-grid-check", "--quiet"], env=env, cwd=away,
        timeout=600)
    mine = cli("run", SCENE, "--out", tmp_path / "ref", "--no-plots", "--no-grid-check", "--quiet", timeout=600)
    assert mine.returncode == 0, mine.stderr
    installed = json.loads((away / "out" / "summary.json").read_text())["d50_um"]
    reference = json.loads((tmp_path / "ref" / "summary.json").read_text())["d50_um"]
    assert installed == reference  # the same libraries: the same bits

    # find_package(granuflow) against the pip-installed package's CMake files (configure only: the compile is the
    # example plugin's below, against the same files installed by cmake --install)
    project = tmp_path / "consumer"
    project.mkdir()
    (project / "CMakeLists.txt").write_text(
        "cmake_minimum_required(VERSION 3.18)\nproject(consumer LANGUAGES CXX)\n"
        f"find_package(granuflow {gf.__version__} EXACT REQUIRED)\n"
        "foreach(t framework kernels units calibration)\n"
        "  if(NOT TARGET granuflow::${t})\n    message(FATAL_ERROR \"no granuflow::${t}\")\n  endif()\nendforeach()\n"
        "get_target_property(inc granuflow::framework INTERFACE_INCLUDE_DIRECTORIES)\nmessage(STATUS \"inc=${inc}\")\n")
    conf = run(["cmake", "-S", project, "-B", project / "build", f"-DCMAKE_PREFIX_PATH={where[1]}"], env=env,
               timeout=300)
    assert f"inc={where[1]}/include" in conf.stdout

    # the example plugin (built against this build installed by cmake --install) run by the installed command
    cache = open(os.path.join(BUILD, "CMakeCache.txt")).read()
    launcher = "ccache" if "CMAKE_CXX_COMPILER_LAUNCHER:UNINITIALIZED=ccache" in cache else ""
    run(["cmake", f"-DBUILD={BUILD}", f"-DSOURCE={ROOT}", f"-DLAUNCHER={launcher}", "-P",
         os.path.join(ROOT, "tests", "tools", "build_plugin_example.cmake")], timeout=900)
    lib = os.path.join(BUILD, "plugin-example", "build", "libgranuflow_example_plugin.so")
    scene = away / "example_scene.yaml"
    scene.write_text(open(os.path.join(ROOT, "examples", "plugin", "example_scene.yaml")).read().replace(
        "build/libgranuflow_example_plugin.so", lib))
    run([exe, "run", scene, "--out", away / "plugin_out", "--no-plots", "--no-grid-check", "--quiet"], env=env,
        cwd=away, timeout=600)
    summary = json.loads((away / "plugin_out" / "summary.json").read_text())
    assert summary["T_tank_K"] == pytest.approx(324.45, abs=0.01)  # the tank's steady state (scene header)
