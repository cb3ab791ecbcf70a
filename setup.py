"""Build of the Python package with CMake: configure, build and `cmake --install` the libraries, their headers, the
CMake package and the extension into the wheel (granuflow/ and granuflow/sdk/). The version is the project's, read
from the top-level CMakeLists.txt (the one place it is defined).

Environment:
  GRANUFLOW_CMAKE_ARGS        extra CMake arguments, split like a shell would (e.g. -DGRANUFLOW_NATIVE=ON)
  GRANUFLOW_PIP_BUILD_DIR     the CMake build folder (default build-pip/ in the checkout; kept, so a second
                              install is incremental)
  CMAKE_CXX_COMPILER_LAUNCHER passed to CMake (e.g. ccache)
  CMAKE_BUILD_PARALLEL_LEVEL  build jobs (default: the number of CPUs)
A pip build is portable (GRANUFLOW_NATIVE=OFF): the wheel runs on any x86-64 machine.
"""
import os
import pathlib
import re
import shlex
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


class CMakeBuild(build_ext):
    def build_extension(self, ext):
        pkg_root = pathlib.Path(self.get_ext_fullpath(ext.name)).resolve().parent.parent  # holds granuflow/
        build_dir = pathlib.Path(os.environ.get("GRANUFLOW_PIP_BUILD_DIR", ROOT / "build-pip")).resolve()
        args = ["-G", "Ninja", "-DCMAKE_BUILD_TYPE=Release", "-DGRANUFLOW_NATIVE=OFF", "-DGRANUFLOW_BUILD_TESTS=OFF",
                "-DGRANUFLOW_BUILD_PYTHON=ON", f"-DPython_EXECUTABLE={sys.executable}",
                f"-DCMAKE_INSTALL_PREFIX={pkg_root / 'granuflow' / 'sdk'}", "-DCMAKE_INSTALL_LIBDIR=lib",
                f"-DGRANUFLOW_PYTHON_INSTALL_DIR={pkg_root}"]
        if os.environ.get("CMAKE_CXX_COMPILER_LAUNCHER"):
            args.append(f"-DCMAKE_CXX_COMPILER_LAUNCHER={os.environ['CMAKE_CXX_COMPILER_LAUNCHER']}")
        args += shlex.split(os.environ.get("GRANUFLOW_CMAKE_ARGS", ""))
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
