"""Parameter sweeps: a sweep file (YAML) over a scene, a generic parallel runner, main effects.

Sweep file (paths relative to the sweep file; values in each variable's edge unit)::

    sweep: stoeckl_gf25_table1
    description: paper 001 Table 1 design
    scene: stoeckl_gf25_batch.yaml
    variables:                              # column name -> scene parameter and the unit of its values
      V_air_m3h:    {param: inlet.V_dot, unit: m3/h, levels: [600, 700, 800]}
      T_in_degC:    {param: inlet.T,     unit: degC, levels: [40, 60, 80]}
      spray_g_min:  {param: nozzle.mdot, unit: g/min, levels: [60, 90, 120]}
    points:                                 # one run each; name and kind are labels
      - {name: C1, kind: corner, V_air_m3h: 600, T_in_degC: 40, spray_g_min: 60}
      - ...
    outputs: [d50_um, bed_moisture, bed_moisture_wet, T_gas_out_K, d10_um, d90_um]
    set: {bed.bed_mass: 15 kg}              # optional: fixed overrides for every point
    t_end: 60 min                           # optional: end time of every run

Outputs are summary keys of the scene (``d50_um``, ``bed_moisture``, ... as in summary.json) or qualified names of
states and reported outputs (``bed.T``: the value at the final time). A point value may also be a string with a
unit (``"80 degC"``); it is shown in the variable's unit.

Python::

    import granuflow as gf
    from granuflow import sweep
    sw = sweep.load_sweep("flowsheets/stoeckl_gf25_table1.yaml")
    df = sw.run(workers=2)                  # one row per point: variables (edge units), outputs, time, status
    sweep.main_effects(df)                  # over the cube corners: mean(high) - mean(low)
    sw.run(error_estimate=True)             # and d50_um_err ...: each point's estimated numerical error

    # the generic runner, for points built in code (values SI floats or strings with a unit):
    df = sweep.run_sweep(gf.load(scene), [{"nozzle.mdot": "60 g/min"}, {"nozzle.mdot": "120 g/min"}],
                         outputs=["d50_um"], workers=2)

Executors are pluggable: ``executor="threads"`` (default: a thread pool, each worker thread with its own
``Flowsheet.clone()``; the C++ solve releases the GIL), ``"serial"``, or any object with a
``map_unordered(evaluate, flowsheet, items)`` method (see :class:`ThreadExecutor`). A ``distributed.Client`` is
accepted as it is and runs the sweep on its Dask cluster (:class:`granuflow.sweep.dask.DaskExecutor`, which rebuilds
the flowsheet on each worker from the scene text and the parameter values). Plain runs are solved in the C++ core
many points per call, each reduced there to its row (:mod:`granuflow.sweep.batch`; every executor hands it its items
or chunks); ``run_sweep(..., batch=False)`` takes each point through ``Flowsheet.simulate`` and ``Result`` instead,
with the same rows.
"""
from .analysis import corner_points, main_effects
from .executors import EXECUTORS, SerialExecutor, ThreadExecutor, make_executor
from .file import Sweep, Variable, load_sweep, run_sweep_file
from .runner import (DEFAULT_OUTPUTS, STATUS_FAILED, STATUS_OK, check_outputs, error_column, final_errors,
                     final_values, run_sweep)

__all__ = ["corner_points", "main_effects", "EXECUTORS", "SerialExecutor", "ThreadExecutor", "make_executor", "Sweep",
           "Variable", "load_sweep", "run_sweep_file", "DEFAULT_OUTPUTS", "STATUS_FAILED", "STATUS_OK",
           "check_outputs", "error_column", "final_errors", "final_values", "run_sweep"]
