"""granuflow: equation-oriented simulation of spray fluidized-bed processes.

Typical use::

    import granuflow as gf
    fs = gf.load("flowsheets/demo_tanks.yaml")
    fs.set("tank1.Q", "25 kW")
    res = fs.simulate()
    res.timeseries          # pandas DataFrame
    res.summary             # the fields of summary.json
"""
from ._core import CalibrationError, ConfigError, SolverError, unit_types
from .flowsheet import Flowsheet, load, load_text
from .kernels import aggregation_kernels, register_kernel
from .result import Result

__version__ = "0.1.0"
__all__ = ["load", "load_text", "Flowsheet", "Result", "ConfigError", "SolverError", "CalibrationError",
           "unit_types", "register_kernel", "aggregation_kernels", "__version__"]
