"""Population-balance kernels written in Python, for prototyping.

A registered aggregation kernel is selected in a ``pbm_batch`` unit by its name, exactly like a compiled one::

    import numpy as np
    import granuflow as gf

    def brownian(d, v):                        # d: pivot diameters (m), v: pivot volumes (m3), both (n,)
        return 1e-3 * np.add.outer(d, d) * np.add.outer(1 / d, 1 / d)

    gf.register_kernel("brownian_py", brownian, description="Brownian (continuum) kernel, 1e-3 1/s scale")
    fs = gf.load_text('''
    scene: proto
    t_end: 10 s
    units:
      pbm: {type: pbm_batch, settings: {aggregation: brownian_py, aggregation_scheme: cell_average}}
    ''')

A kernel may declare parameters with an SI unit, bounds and a source; the unit that uses it then has them with the
prefix ``agg_`` (``pbm.agg_beta0``), so a scene sets them with units, ``describe`` lists them, and sweeps, contour
maps and calibrations vary them like the compiled kernels' parameters::

    def brownian(d, v, beta0):
        return beta0 * np.add.outer(d, d) * np.add.outer(1 / d, 1 / d)

    gf.register_kernel("brownian_py", brownian, params=[
        {"name": "beta0", "unit": "1/s", "default": 1e-3, "lower": 0, "upper": 1,
         "description": "rate coefficient", "source": "fitted"}])

Prototype kernels are slower than compiled ones and have fewer features: the GIL is taken for every
evaluation, and the kernel reads only the pivot sizes (it is state-independent, so pbm_batch evaluates it once per
run and never per residual). Sensitivities to its parameters (calibration, ``--error-estimate`` gradients) are
central finite differences of relative step 1e-6, two more calls of the function per parameter and Jacobian
(kernels/aggregation/callback.cpp), not automatic differentiation: accurate to about 1e-6 relative for a smooth
function. Port a kernel that works to C++ (kernels/aggregation/, one file pair and one line in
kernels/registry.cpp, or a plugin: docs/install_and_plugins.md) for production runs.
"""
from __future__ import annotations

import math
import re
from collections.abc import Callable, Sequence

from . import _core

__all__ = ["register_kernel", "aggregation_kernels", "python_kernels"]

KernelFunction = Callable[["numpy.ndarray", "numpy.ndarray"], "numpy.ndarray"]  # NumPy only when a kernel runs


_DECLARED: dict[str, list[dict]] = {}  # the parameters each Python kernel was registered with
PARAM_KEYS = ("name", "unit", "default", "lower", "upper", "description", "source")


def _param_specs(name: str, params: Sequence[dict]) -> list[dict]:
    """The declared parameters checked as a compiled kernel's are: every key, an SI unit granuflow knows, finite
    bounds around the default, distinct names."""
    where = f"register_kernel({name!r})"
    specs, seen = [], set()
    si = set(_core.known_si_units())
    for k, p in enumerate(params):
        at = f"{where}: params[{k}]"
        if not isinstance(p, dict):
            raise _core.ConfigError(f"{at}: expected a dict with keys {', '.join(PARAM_KEYS)}, got {type(p).__name__}")
        missing = [key for key in PARAM_KEYS if key not in p]
        unknown = [key for key in p if key not in PARAM_KEYS]
        if missing or unknown:
            raise _core.ConfigError(f"{at}: " + (f"missing {', '.join(missing)}" if missing else
                                                 f"unknown key {', '.join(map(str, unknown))}")
                                    + f" (keys: {', '.join(PARAM_KEYS)})")
        pname = p["name"]
        if not isinstance(pname, str) or not re.fullmatch(r"[A-Za-z_][A-Za-z0-9_]*", pname) or pname in seen:
            raise _core.ConfigError(f"{at}: name {pname!r}: expected a distinct Python identifier")
        seen.add(pname)
        if p["unit"] not in si:
            raise _core.ConfigError(f"{at} ({pname}): unit {p['unit']!r} is not an SI unit granuflow knows "
                                    f"(allowed: {', '.join(sorted(si))})")
        try:
            lo, hi, default = float(p["lower"]), float(p["upper"]), float(p["default"])
        except (TypeError, ValueError):
            raise _core.ConfigError(f"{at} ({pname}): default, lower and upper must be numbers") from None
        if not all(math.isfinite(x) for x in (lo, hi, default)) or not lo <= default <= hi:
            raise _core.ConfigError(f"{at} ({pname}): default {default} must lie in [lower, upper] = [{lo}, {hi}], "
                                    "all finite")
        specs.append({"name": pname, "unit": p["unit"], "default": default, "lower": lo, "upper": hi,
                      "description": str(p["description"]), "source": str(p["source"])})
    return specs


def register_kernel(name: str, fn: KernelFunction, *, params: Sequence[dict] = (), description: str = "",
                    replace: bool = False) -> None:
    """Register a Python aggregation kernel under ``name`` in the process-wide kernel registry.

    Parameters
    ----------
    name
        The name a scene uses (``settings: {aggregation: NAME}`` of a ``pbm_batch`` unit). No spaces; not
        ``none``; must not be a built-in kernel (:func:`aggregation_kernels` lists them).
    fn
        ``fn(diameters_m, volumes_m3, **params) -> beta``: the pivot diameters (m) and volumes (m3) of the grid,
        both read-only float arrays of shape ``(n,)``, and the declared parameters by name in SI; returns the
        ``(n, n)`` matrix of rate coefficients beta_ij in 1/s per pair of particles (absolute numbers, as the
        compiled kernels). It must be finite, non-negative and symmetric (to 1e-10 relative).
    params
        The kernel's parameters, each a dict with ``name`` (an identifier), ``unit`` (an SI unit granuflow knows,
        e.g. ``"1/s"``, ``"m3"``, ``"Pa s"``), ``default``, ``lower``, ``upper`` (inclusive bounds in that unit),
        ``description`` and ``source`` (where the value comes from). A unit using the kernel declares them as
        ``agg_NAME``.
    description
        One line shown by :func:`aggregation_kernels`.
    replace
        Swap the function of a kernel registered from Python before (e.g. when a notebook cell runs again).
        Flowsheets already built keep the function they were built with. Built-in kernels are never replaced.

    Raises
    ------
    TypeError
        ``fn`` is not callable.
    ValueError (granuflow.ConfigError)
        The name is taken (built in, or registered before without ``replace=True``) or malformed. When a
        flowsheet using the kernel is simulated: ``fn`` returned a matrix of the wrong shape, a negative,
        non-finite or asymmetric entry, or raised; the message names the kernel, the entry and the rule.

    Notes
    -----
    Slower than a compiled kernel: the GIL is taken for every evaluation, which happens once per run (the kernel
    is state-independent). Jacobians treat beta as constant, which is exact here.
    """
    if not isinstance(name, str):
        raise TypeError(f"register_kernel: name must be a str, got {type(name).__name__}")
    if not callable(fn):
        raise TypeError(f"register_kernel({name!r}): fn must be callable fn(diameters_m, volumes_m3) -> (n, n) "
                        f"array, got {type(fn).__name__}")
    specs = _param_specs(name, params)
    if replace and name in _DECLARED and _DECLARED[name] != specs:
        raise _core.ConfigError(f"register_kernel({name!r}, replace=True): the parameters differ from the ones it was "
                                "registered with; replace swaps the function only (register a new name)")
    _core.register_aggregation_kernel(name, fn, params=specs, description=description, replace=replace)
    _DECLARED.setdefault(name, specs)


def aggregation_kernels() -> dict[str, str]:
    """All registered aggregation kernels (built in and from Python): name -> description."""
    return dict(_core.aggregation_kernels())


def python_kernels() -> list[str]:
    """Names of the aggregation kernels registered from Python in this process."""
    return list(_core.python_kernels())
