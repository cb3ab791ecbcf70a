"""Instruction-set copies of the core libraries picked at run time (cmake/granuflowIsaVariants.cmake; a pip build
carries framework, kernels and units for the x86-64 baseline and for x86-64-v3, docs/install_and_plugins.md).

The function that makes the core libraries' copies is applied to a two-library probe (tests/isa_probe), installed as
the wheel is laid out (<prefix>/lib and <prefix>/lib/glibc-hwcaps/x86-64-v3): on a CPU the loader deems x86-64-v3
capable both libraries are the v3 copies, compiled with AVX2 and FMA, the lower one found through the upper copy's run
path; with the loader limited to the baseline (ld.so --glibc-hwcaps-mask x86-64, as docs/install_and_plugins.md
forces it) both are the baseline copies. A module built once for the baseline against the upper library (as a plugin
against an installed granuflow) reaches the copy the process runs, and either way Eigen lays fixed-size objects out
as the baseline does (16-byte alignment), the condition for one extension and one plugin to work with either copy.
A few seconds of compiling (ccache)."""
import os
import re
import subprocess

import pytest

import granuflow as gf
from conftest import PKG_PATH, ROOT, cli

BUILD = os.path.dirname(PKG_PATH)
LD_SO = "/lib64/ld-linux-x86-64.so.2"


def run(cmd, **kw):
    p = subprocess.run([str(c) for c in cmd], capture_output=True, text=True, timeout=600, **kw)
    assert p.returncode == 0, (cmd, p.stdout[-3000:], p.stderr[-3000:])
    return p


def loader_levels():
    """The glibc-hwcaps levels this loader searches on this CPU (`ld.so --help`)."""
    text = run([LD_SO, "--help"]).stdout
    return set(re.findall(r"^\s+(x86-64-v\d) \(supported, searched\)", text, re.M))


@pytest.fixture(scope="module")
def probe(tmp_path_factory):
    if not os.path.exists(LD_SO) or "x86-64-v2" not in run([LD_SO, "--help"]).stdout:
        pytest.skip("needs glibc >= 2.33 on x86-64 (glibc-hwcaps subdirectories)")
    build = os.path.join(BUILD, "isa-probe")
    prefix = tmp_path_factory.mktemp("isa") / "prefix"
    cache = open(os.path.join(BUILD, "CMakeCache.txt")).read()
    launcher = ["-DCMAKE_CXX_COMPILER_LAUNCHER=ccache"] if "COMPILER_LAUNCHER:UNINITIALIZED=ccache" in cache else []
    run(["cmake", "-S", os.path.join(ROOT, "tests", "isa_probe"), "-B", build, "-DCMAKE_BUILD_TYPE=Release",
         f"-DGRANUFLOW_SOURCE_DIR={ROOT}", "-DGRANUFLOW_ISA_VARIANTS=x86-64-v3", *launcher])
    run(["cmake", "--build", build])
    run(["cmake", "--install", build, "--prefix", prefix])
    return prefix


def probe_says(prefix, *loader):
    out = run([*loader, prefix / "bin" / "isa_probe", prefix / "lib" / "libisa_plugin.so"]).stdout
    said = dict(line.split(" ", 1) for line in out.splitlines() if not line.startswith("file "))
    files = [os.path.realpath(line[5:]) for line in out.splitlines() if line.startswith("file ")]
    return said, files


def test_the_loader_picks_the_v3_copies_on_a_v3_cpu(probe):
    if "x86-64-v3" not in loader_levels():
        pytest.skip("this CPU lacks x86-64-v3 (AVX2, FMA, BMI2, ...): the loader takes the baseline copies")
    said, files = probe_says(probe)
    assert said == {"top": "x86-64-v3 avx2+fma", "base": "x86-64-v3 avx2+fma", "align": "16",
                    "plugin": "x86-64-v3 avx2+fma"}
    v3 = os.path.realpath(probe / "lib" / "glibc-hwcaps" / "x86-64-v3")
    assert [os.path.dirname(f) for f in files] == [v3, v3]


def test_the_baseline_copies_under_the_loaders_mask(probe):
    said, files = probe_says(probe, LD_SO, "--glibc-hwcaps-mask", "x86-64")
    assert said == {"top": "x86-64 baseline", "base": "x86-64 baseline", "align": "16", "plugin": "x86-64 baseline"}
    lib = os.path.realpath(probe / "lib")
    assert [os.path.dirname(f) for f in files] == [lib, lib]


def test_build_info_names_this_builds_instruction_set():
    cache = open(os.path.join(BUILD, "CMakeCache.txt")).read()
    native = re.search(r"^GRANUFLOW_NATIVE:BOOL=(ON|TRUE|1)$", cache, re.M) is not None
    info = gf.build_info()
    assert info["isa"] == ("native" if native else "x86-64")
    assert info["version"] == gf.__version__
    names = sorted(os.path.basename(p) for p in info["core_libraries"])
    assert {"libgranuflow_framework.so", "libgranuflow_kernels.so", "libgranuflow_units.so"} <= set(names)
    assert cli("--version").stdout.strip() == f"granuflow {gf.__version__} ({info['isa']})"
