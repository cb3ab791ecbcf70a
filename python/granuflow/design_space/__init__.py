"""Design space: contour maps of summary outputs over two operating variables, the feasible window of constraints on
outputs, constrained optimization with NLopt, and a probabilistic design space (paper 001, section 4.3, Figs. 17-20).

Operating variables are given as ``(param, unit, lo, hi, n)`` (contour axes), ``(param, unit, lo, hi)``
(optimization variables) or the same as a string ``"inlet.T:degC:40:80:15"``; values are in the given edge unit,
the simulations run in SI. Outputs are summary keys (``d50_um``, ``bed_moisture_wet``, ... as in summary.json) or
state/output names (final value). Constraints are ``{"d50_um": (">=", 400), "bed_moisture_wet": ("<", 0.04)}`` or
strings ``"d50_um>=400"``, bounds in the unit of the output.

Python::

    import granuflow as gf
    from granuflow import design_space as ds

    fs = gf.load("flowsheets/stoeckl_gf25_batch.yaml")
    grid = ds.contour_map(fs, x=("inlet.T", "degC", 40, 80, 15), y=("nozzle.mdot", "g/min", 60, 120, 15),
                          outputs=["d50_um", "bed_moisture_wet"], workers=2)
    grid["d50_um"]                       # (ny, nx) array; grid.x.values, grid.y.values in degC and g/min
    win = ds.feasible_window(grid, {"d50_um": (">=", 400), "bed_moisture_wet": ("<", 0.04)})
    win.mask, win.outline                # boolean map; closed polygons (degC, g/min) of the window
    ds.plot_contour(grid, "d50_um", "d50.png", window=win)

    opt = ds.optimize(fs, objective="nozzle.mdot", maximize=True,
                      variables=[("nozzle.mdot", "g/min", 60, 120), ("inlet.T", "degC", 40, 80)],
                      constraints=["d50_um>=400", "bed_moisture_wet<0.04"], algorithm="LN_COBYLA")
    opt.x, opt.constraints, opt.n_simulations, opt.nlopt_result

    pmap = ds.probabilistic_design_space(fs, x=..., y=..., constraints=..., params=["bed.agg_ln_beta0", "bed.X_cr"],
                                         covariance=[[0.15**2, 0], [0, 0.005**2]], method="linear")
    pmap.probability                     # P(all constraints met), (ny, nx)

Every function that simulates takes ``workers``, ``executor`` (``"threads"``, ``"serial"``, a
``distributed.Client`` or an executor object, see :mod:`granuflow.sweep`) and ``progress``, and runs through
:func:`granuflow.sweep.run_sweep` or its executors. Only the final state matters here, so runs use ``n_out=2``
(outputs are interpolated: the values are identical to a default run).
"""
from ..plots.design_space import plot_contour, plot_feasible_window, plot_probability
from .axes import MAX_AXIS_POINTS, T_END, Axis, Constraint, make_axis, parse_constraints
from .contour import ContourGrid, FeasibleWindow, contour_map, feasible_window
from .optimize import OptimizationResult, nlopt_algorithms, optimize
from .probabilistic import ProbabilityMap, probabilistic_design_space

__all__ = ["plot_contour", "plot_feasible_window", "plot_probability", "MAX_AXIS_POINTS", "T_END", "Axis", "Constraint",
           "make_axis", "parse_constraints", "ContourGrid", "FeasibleWindow", "contour_map", "feasible_window",
           "OptimizationResult", "nlopt_algorithms", "optimize", "ProbabilityMap", "probabilistic_design_space"]
