"""granuflow: equation-oriented simulation of spray fluidized-bed processes.

Typical use::

    import granuflow as gf
    fs = gf.load("flowsheets/demo_tanks.yaml")
    fs.set("tank1.Q", "25 kW")
    res = fs.simulate()
    res.timeseries          # pandas DataFrame (SI; units in .attrs["units"])
    res.summary             # the fields of summary.json
    gf.unit_reference("fluid_bed")   # ports, settings, parameters, outputs of a unit type

Layers (no module imports one above it; tests/python/test_package_layers.py checks it):
``_core`` (C++) < ``textfile`` < ``quantity``, ``outputs``, ``progress`` < ``result``, ``flowsheet``, ``kernels``,
``reference`` < ``plots`` < ``sweep`` < ``design_space``, ``calibration`` < ``bench`` < ``cli``.
"""
from ._core import CalibrationError, ConfigError, SolverError
from .flowsheet import Flowsheet, load, load_text
from .kernels import aggregation_kernels, register_kernel
from .reference import kernel_reference, unit_reference, unit_types
from .result import BalanceError, BalanceWarning, GridWarning, Result
from ._version import __version__  # generated from the project version in CMakeLists.txt
from .plugins import PluginWarning, build_info, load_plugin, load_search_path, load_search_path_at_import

load_search_path_at_import()  # GRANUFLOW_PLUGIN_PATH: a user's units and kernels, before anything lists or builds them

__all__ = ["load", "load_text", "Flowsheet", "Result", "GridWarning", "BalanceWarning", "ConfigError", "SolverError",
           "BalanceError", "CalibrationError", "unit_types", "unit_reference", "kernel_reference", "register_kernel",
           "aggregation_kernels", "load_plugin", "load_search_path", "PluginWarning", "build_info", "__version__"]
