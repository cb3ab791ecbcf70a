"""Build of the Python package with CMake: configure, build and `cmake --install` the libraries, their headers, the
CMake package and the extension into the wheel (granuflow/ and granuflow/sdk/). The version is the project's, read
from the top-level CMakeLists.txt (the one place it is defined).

Environment:
  GRANUFLOW_CMAKE_ARGS        extra CMake arguments, split like a shell would (e.g. -DGRANUFLOW_NATIVE=ON)
  GRANUFLOW_PIP_BUILD_DIR     the CMake build folder (default build-pip/ in the checkout; kept, so a second
                              install is incremental)
  GRANUFLOW_PREBUILT_DIR      an already built CMake folder of this checkout (e.g. build/): nothing is configured or
                              compiled; its libraries, headers and CMake package are installed into the wheel
                              (cmake --install --prefix) and its Python package (build/python/granuflow) copied
                              beside them. The wheel then has that folder's options (GRANUFLOW_NATIVE ...).
  GRANUFLOW_ISA_VARIANTS      the x86-64 levels the core libraries are built for besides the baseline, separated by
                              ';' (default x86-64-v3; empty: the baseline only); not with -DGRANUFLOW_NATIVE=ON
  CMAKE_CXX_COMPILER_LAUNCHER passed to CMake (e.g. ccache)
  CMAKE_BUILD_PARALLEL_LEVEL  build jobs (default: the number of CPUs)
A pip build is portable (GRANUFLOW_NATIVE=OFF): the wheel runs on any x86-64 machine. Its three core libraries
(framework, kernels, units) are in it twice: for the x86-64 baseline in granuflow/sdk/lib and for x86-64-v3 (AVX2,
FMA) in granuflow/sdk/lib/glibc-hwcaps/x86-64-v3, which glibc's loader takes instead on a CPU that has it (the
second build of the core takes about as long as the first). granuflow.build_info() and `granuflow --version` say
which copy a process runs.
"""
import os
import pathlib
import re
import shlex
import shutil
import subprocess
import sys

from setuptools import Extension, setup
from setuptools.command.build_ext import build_ext

ROOT = pathlib.Path(__file__).resolve().parent


def project_version() -> str:
    m = re.search(r"^project\(granuflow VERSION ([0-9.]+)", (ROOT / "CMakeLists.txt").read_text(), re.M)
    if not m:
        raise RuntimeError("CMakeLists.txt: no `project(granuflow VERSION x.y.z` line")
    return m.group(1)


def cache_value(build_dir: pathlib.Path, key: str) -> str:
    m = re.search(rf"^{key}:[A-Z]+=(.*)$", (build_dir / "CMakeCache.txt").read_text(), re.M)
    return m.group(1) if m else ""


def install_prebuilt(build_dir: pathlib.Path, pkg_root: pathlib.Path) -> None:
    """The wheel's content from a folder that is built already: what `cmake --install` puts into the SDK, and the
    Python package the build assembled (build/python/granuflow), its extension finding the SDK's libraries."""
    src = build_dir / "python" / "granuflow"
    cores = sorted(src.glob("_core.*.so"))
    if not (build_dir / "CMakeCache.txt").is_file() or not cores:
        raise RuntimeError(f"GRANUFLOW_PREBUILT_DIR={build_dir}: not a built granuflow CMake folder with the Python "
                           "module (no CMakeCache.txt or python/granuflow/_core*.so); build it first")
    sdk = pkg_root / "granuflow" / "sdk"
    subprocess.run(["cmake", "--install", str(build_dir), "--prefix", str(sdk)], check=True)
    shutil.copytree(src, pkg_root / "granuflow", dirs_exist_ok=True,
                    ignore=shutil.ignore_patterns("__pycache__", "*.pyc", "sdk"))
    # the build tree's extension looks for the libraries in the build folder; the installed one beside itself
    libdir = cache_value(build_dir, "CMAKE_INSTALL_LIBDIR") or "lib"
    script = build_dir / "granuflow_wheel_rpath.cmake"
    script.write_text("".join(f'file(RPATH_SET FILE "{pkg_root / "granuflow" / ext.name}" '
                              f'NEW_RPATH "$ORIGIN/sdk/{libdir}")\n'
                              for ext in sorted(src.glob("_*.so"))))  # _core and _calibration
    subprocess.run(["cmake", "-P", str(script)], check=True)


class CMakeBuild(build_ext):
    def build_extension(self, ext):
        pkg_root = pathlib.Path(self.get_ext_fullpath(ext.name)).resolve().parent.parent  # holds granuflow/
        if os.environ.get("GRANUFLOW_PREBUILT_DIR"):
            install_prebuilt(pathlib.Path(os.environ["GRANUFLOW_PREBUILT_DIR"]).resolve(), pkg_root)
            return
        build_dir = pathlib.Path(os.environ.get("GRANUFLOW_PIP_BUILD_DIR", ROOT / "build-pip")).resolve()
        args = ["-G", "Ninja", "-DCMAKE_BUILD_TYPE=Release", "-DGRANUFLOW_NATIVE=OFF", "-DGRANUFLOW_BUILD_TESTS=OFF",
                "-DGRANUFLOW_BUILD_PYTHON=ON", f"-DPython_EXECUTABLE={sys.executable}",
                f"-DCMAKE_INSTALL_PREFIX={pkg_root / 'granuflow' / 'sdk'}", "-DCMAKE_INSTALL_LIBDIR=lib",
                f"-DGRANUFLOW_PYTHON_INSTALL_DIR={pkg_root}"]
        if os.environ.get("CMAKE_CXX_COMPILER_LAUNCHER"):
            args.append(f"-DCMAKE_CXX_COMPILER_LAUNCHER={os.environ['CMAKE_CXX_COMPILER_LAUNCHER']}")
        extra = shlex.split(os.environ.get("GRANUFLOW_CMAKE_ARGS", ""))
        if not any(re.fullmatch(r"-DGRANUFLOW_NATIVE(:BOOL)?=(ON|1|TRUE|YES|Y)", a, re.I) for a in extra):
            args.append(f"-DGRANUFLOW_ISA_VARIANTS={os.environ.get('GRANUFLOW_ISA_VARIANTS', 'x86-64-v3')}")
        args += extra
        jobs = str(os.environ.get("CMAKE_BUILD_PARALLEL_LEVEL") or self.parallel or os.cpu_count() or 1)
        subprocess.run(["cmake", "-S", str(ROOT), "-B", str(build_dir), *args], check=True)
        subprocess.run(["cmake", "--build", str(build_dir), "-j", jobs], check=True)
        subprocess.run(["cmake", "--install", str(build_dir)], check=True)


setup(
    version=project_version(),
    packages=[],  # the package is installed by CMake (python/CMakeLists.txt), the extension beside it
    ext_modules=[Extension("granuflow._core", sources=[])],
    cmdclass={"build_ext": CMakeBuild},
    options={"build": {"build_base": "build-pip/setuptools"}},
    zip_safe=False,
)
