"""Plugins (docs/install_and_plugins.md): the example plugin (examples/plugin) built against this build installed
into a folder (cmake --install, find_package(granuflow)), its unit and kernel in a scene, in `units`, `kernels`,
`describe` and `docs`, and the refusals: another version, a file that is no shared library, a library without the
plugin's symbols, a bad GRANUFLOW_PLUGIN_PATH. The unit conformance checks on the plugin's scene are the ctest
plugin.example_conformance."""
import json
import math
import os
import shutil
import subprocess

import pandas as pd
import pytest

import granuflow as gf
from conftest import PKG_PATH, ROOT, assert_bad_input, cli, package_env

BUILD = os.path.dirname(PKG_PATH)
EXAMPLE = os.path.join(BUILD, "plugin-example")
SCENE = os.path.join(EXAMPLE, "example_scene.yaml")
LIB = os.path.join(EXAMPLE, "build", "libgranuflow_example_plugin.so")
K_B = 1.380649e-23  # J/K


@pytest.fixture(scope="module")
def example():
    """The example plugin, built as the ctest plugin.example_build builds it (incremental: seconds when it ran)."""
    cache = open(os.path.join(BUILD, "CMakeCache.txt")).read()
    launcher = "ccache" if "CMAKE_CXX_COMPILER_LAUNCHER:UNINITIALIZED=ccache" in cache else ""
    subprocess.run(["cmake", f"-DBUILD={BUILD}", f"-DSOURCE={ROOT}", f"-DLAUNCHER={launcher}", "-P",
                    os.path.join(ROOT, "tests", "tools", "build_plugin_example.cmake")], check=True,
                   capture_output=True, timeout=900)
    return LIB


def tiny_library(tmp_path, name, source):
    """A shared library from a few lines of C++ (no granuflow headers): for the refusals."""
    src = tmp_path / f"{name}.cpp"
    src.write_text(source)
    lib = tmp_path / f"lib{name}.so"
    subprocess.run(["c++", "-shared", "-fPIC", "-o", str(lib), str(src)], check=True, timeout=120)
    return lib


def test_example_scene_runs_with_the_plugin_unit_and_kernel(example, tmp_path):
    # through the command line, so that this process never loads the plugin (later tests compare the generated
    # reference with the built-in registries)
    p = cli("run", SCENE, "--out", tmp_path / "out", "--no-plots", "--no-grid-check", timeout=300)
    assert p.returncode == 0, p.stderr
    df = pd.read_csv(tmp_path / "out" / "timeseries.csv")
    df.columns = [c.split(" [")[0] for c in df.columns]
    t = df.iloc[:, 0].to_numpy()  # t [s]
    # the jacketed tank: T(t) = T_ss + (T0 - T_ss) exp(-t / tau), docs in the scene's header
    mcp, ua, m_cp = 0.5 * 4180.0, 500.0 * 4.0, 100.0 * 4180.0
    t_ss = (mcp * 300.0 + ua * 350.0) / (mcp + ua)
    tau = m_cp / (mcp + ua)
    exact = [t_ss + (300.0 - t_ss) * math.exp(-x / tau) for x in t]
    assert df["tank.T"].to_numpy() == pytest.approx(exact, rel=1e-6)
    assert df["tank.Q_jacket"].to_numpy()[-1] == pytest.approx(ua * (350.0 - df["tank.T"].to_numpy()[-1]), rel=1e-6)
    # Brownian aggregation: beta_ij >= 8 k_B T / (3 mu V) for every pair, so the number falls at least as fast as the
    # constant kernel's N0 / (1 + beta_min N0 t / 2); near-monodisperse, not much faster (within 25 %)
    n = df["sol.number"].to_numpy()
    beta_min = 8 * K_B * 293.15 / (3 * 1.0016e-3 * 1e-3)
    bound = 1e11 / (1 + beta_min * 1e11 * t[-1] / 2)
    assert n[-1] <= bound * (1 + 1e-6)
    assert n[-1] > 0.75 * bound
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    assert summary["T_tank_K"] == pytest.approx(df["tank.T"].to_numpy()[-1], rel=1e-9)
    assert gf.plugins.loaded_plugins() == []


def test_plugin_models_are_listed_described_and_documented(example, tmp_path):
    units = cli("--plugin", example, "units")
    assert units.returncode == 0, units.stderr
    line = next(x for x in units.stdout.splitlines() if x.startswith("jacketed_tank"))
    assert f"[plugin {os.path.realpath(example)}]" in line
    kernels = cli("--plugin", example, "kernels")
    assert any(x.strip().startswith("brownian") and "[plugin" in x for x in kernels.stdout.splitlines())
    one = cli("--plugin", example, "units", "jacketed_tank")
    assert one.returncode == 0 and "T_jacket" in one.stdout and "W/(m2 K)" in one.stdout
    desc = cli("describe", SCENE)
    assert desc.returncode == 0, desc.stderr
    assert "tank.U" in desc.stdout and "sol.agg_mu" in desc.stdout and "IAPWS" in desc.stdout
    docs = cli("--plugin", example, "docs", "--write", tmp_path / "docs")
    assert docs.returncode == 0, docs.stderr
    assert "overall heat transfer coefficient" in (tmp_path / "docs" / "units" / "jacketed_tank.md").read_text()
    assert "jacketed_tank" in (tmp_path / "docs" / "reference.md").read_text()
    assert "brownian" in (tmp_path / "docs" / "kernels" / "aggregation.md").read_text()


def test_search_path_loads_a_folder_of_plugins(example, tmp_path):
    folder = tmp_path / "plugins"
    folder.mkdir()
    shutil.copy(example, folder)
    p = subprocess.run([os.path.join(BUILD, "granuflow"), "units"], capture_output=True, text=True, timeout=120,
                       env=package_env(GRANUFLOW_PLUGIN_PATH=str(folder)))
    assert p.returncode == 0, p.stderr
    assert any(x.startswith("jacketed_tank") for x in p.stdout.splitlines())


def test_a_plugin_of_another_version_is_refused_in_one_line(tmp_path):
    # the registration would abort the process: it must not be called
    lib = tiny_library(tmp_path, "old", 'extern "C" const char* granuflow_plugin_abi() { return "granuflow 0.0.1 '
                       '(libstdc++ cxx11 ABI 1)"; }\n'
                       'extern "C" void granuflow_plugin_register() { __builtin_trap(); }\n')
    p = cli("--plugin", lib, "units")
    assert_bad_input(p, str(lib), "built against granuflow 0.0.1", f"this is granuflow {gf.__version__}", "rebuild")
    with pytest.raises(gf.ConfigError, match="built against granuflow 0.0.1"):
        gf.load_plugin(lib)


def test_files_that_are_no_plugins_are_refused_without_a_crash(tmp_path):
    text = tmp_path / "libtext.so"
    text.write_text("not a library\n")
    assert_bad_input(cli("--plugin", text, "units"), str(text), "cannot be loaded as a shared library")
    bare = tiny_library(tmp_path, "bare", "int answer() { return 42; }\n")
    assert_bad_input(cli("--plugin", bare, "units"), str(bare), "not a granuflow plugin", "GRANUFLOW_PLUGIN(")
    assert_bad_input(cli("--plugin", tmp_path / "missing.so", "units"), "missing.so", "no such file")
    assert_bad_input(cli("--plugin", tmp_path, "units"), "not a regular file")
    scene = tmp_path / "s.yaml"
    scene.write_text(open(os.path.join(ROOT, "flowsheets", "demo_tanks.yaml")).read()
                     + "plugins: [libtext.so]\n")
    assert_bad_input(cli("describe", scene), "plugins[0]", "libtext.so", "cannot be loaded")


def test_a_bad_plugin_path_is_one_line_on_the_command_line_and_a_warning_in_python(tmp_path):
    bad = tmp_path / "libtext.so"
    bad.write_text("x")
    env = package_env(GRANUFLOW_PLUGIN_PATH=str(bad))
    p = subprocess.run([os.path.join(BUILD, "granuflow"), "units"], capture_output=True, text=True, timeout=120,
                       env=env)
    assert_bad_input(p, "GRANUFLOW_PLUGIN_PATH", str(bad))
    q = subprocess.run(["/usr/bin/python3", "-c", "import granuflow; print(len(granuflow.unit_types()))"],
                       capture_output=True, text=True, timeout=120, env=env, cwd=tmp_path)
    assert q.returncode == 0 and int(q.stdout) > 20
    assert "PluginWarning" in q.stderr and str(bad) in q.stderr


def test_every_kernel_family_is_listed_for_plugins():
    """The plugin listing and the reference draw their families from one list (KernelRegistries::for_each): a
    family the reference documents (the drying curves and surfaces among them) is one a plugin's names show in."""
    from granuflow import _core, plugins

    families = set(_core.kernel_reference())
    assert {"drying_curve", "drying_surface", "aggregation", "comminution"} <= families
    assert set(plugins.origins()) == families | {"units"}
