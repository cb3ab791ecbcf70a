"""Units and kernels from shared libraries loaded at run time (docs/install_and_plugins.md).

A plugin is built against an installed granuflow (``find_package(granuflow)``; :func:`cmake_prefix` says where a
pip-installed package keeps its CMake files) and loaded by a scene's ``plugins:`` list, by
:func:`load_plugin`, by ``granuflow --plugin LIB``, or from the folders and files of the environment variable
``GRANUFLOW_PLUGIN_PATH`` when granuflow is imported. What it registers then appears in ``granuflow units``,
``kernels``, ``describe`` and ``docs`` like the built-in models.
"""
from __future__ import annotations

import os
import sys
import warnings

from . import _core

ENV_PATH = "GRANUFLOW_PLUGIN_PATH"
# The refusal of a plugin of GRANUFLOW_PLUGIN_PATH at import, which the command line reports as its error instead.
env_error: str | None = None


class PluginWarning(UserWarning):
    """A plugin named by GRANUFLOW_PLUGIN_PATH could not be loaded when granuflow was imported."""


def build_info() -> dict:
    """What this process runs: the version, the instruction set its core libraries were compiled for (``x86-64``,
    ``x86-64-v3``: an installed package carries both and the dynamic loader picks one by the CPU; ``native`` for a
    source build) and the paths of the core libraries loaded."""
    from ._version import __version__

    return {"version": __version__, "isa": _core.build_isa(), "core_libraries": _core.loaded_core_libraries()}


def load_plugin(path: str | os.PathLike) -> str:
    """Load one plugin library; returns its real path. A library is loaded once however often it is named.
    Raises ConfigError (a ValueError) naming the file when it is no granuflow plugin or was built against another
    version."""
    return _core.load_plugin(os.fspath(path))


def load_search_path(search_path: str | None = None) -> list[str]:
    """Load every plugin of a ':'-separated list of folders (their ``*.so`` files) and files; by default the value
    of ``GRANUFLOW_PLUGIN_PATH``."""
    value = os.environ.get(ENV_PATH, "") if search_path is None else search_path
    return _core.load_plugin_path(value) if value else []


def load_search_path_at_import() -> None:
    """GRANUFLOW_PLUGIN_PATH when the package is imported: a refused plugin does not make the import fail (the
    message is a PluginWarning, and the command line's one-line error with exit status 2)."""
    global env_error
    try:
        load_search_path()
    except _core.ConfigError as e:
        env_error = str(e)
        # The command line (`python -m granuflow`, the `granuflow` script) reports it itself, once.
        if os.path.basename(sys.argv[0]) not in ("-m", "granuflow"):
            warnings.warn(env_error, PluginWarning, stacklevel=3)


def loaded_plugins() -> list[str]:
    """Real paths of the plugins loaded in this process, in loading order."""
    return list(_core.loaded_plugins())


def origins() -> dict[str, dict[str, str]]:
    """Per family ("units", "aggregation", "growth", ...): the names plugins registered and the file of each."""
    return {family: dict(names) for family, names in _core.plugin_origins().items()}


def abi_tag() -> str:
    """The version and ABI tag a plugin must carry (GRANUFLOW_PLUGIN in granuflow/plugin.hpp writes it)."""
    return _core.plugin_abi_tag()


def cmake_prefix() -> str | None:
    """The prefix to give CMake (``-DCMAKE_PREFIX_PATH=...``) for ``find_package(granuflow)`` against this package
    when it was installed with pip (its libraries, headers and CMake files under granuflow/sdk); None in a build
    tree, whose installed form comes from ``cmake --install``."""
    sdk = os.path.join(os.path.dirname(os.path.realpath(__file__)), "sdk")
    return sdk if os.path.isfile(os.path.join(sdk, "lib", "cmake", "granuflow", "granuflowConfig.cmake")) else None
