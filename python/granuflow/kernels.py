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

Prototype kernels are slower than compiled ones and have fewer features: the GIL is taken for every
evaluation, the kernel reads only the pivot sizes (it is state-independent, so pbm_batch evaluates it once per
run and never per residual), it has no parameters of its own, and parameter sensitivities through it are zero.
Port a kernel that works to C++ (kernels/aggregation/, one file pair and one line in kernels/registry.cpp) for
production runs.
"""
from __future__ import annotations

from typing import Callable

import numpy as np

from . import _core

__all__ = ["register_kernel", "aggregation_kernels", "python_kernels"]

KernelFunction = Callable[[np.ndarray, np.ndarray], np.ndarray]


def register_kernel(name: str, fn: KernelFunction, *, description: str = "", replace: bool = False) -> None:
    """Register a Python aggregation kernel under ``name`` in the process-wide kernel registry.

    Parameters
    ----------
    name
        The name a scene uses (``settings: {aggregation: NAME}`` of a ``pbm_batch`` unit). No spaces; not
        ``none``; must not be a built-in kernel (:func:`aggregation_kernels` lists them).
    fn
        ``fn(diameters_m, volumes_m3) -> beta``: the pivot diameters (m) and volumes (m3) of the grid, both
        read-only float arrays of shape ``(n,)``; returns the ``(n, n)`` matrix of rate coefficients beta_ij
        in 1/s per pair of particles (absolute numbers, as the compiled kernels). It must be finite,
        non-negative and symmetric (to 1e-10 relative).
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
    _core.register_aggregation_kernel(name, fn, description=description, replace=replace)


def aggregation_kernels() -> dict[str, str]:
    """All registered aggregation kernels (built in and from Python): name -> description."""
    return dict(_core.aggregation_kernels())


def python_kernels() -> list[str]:
    """Names of the aggregation kernels registered from Python in this process."""
    return list(_core.python_kernels())
