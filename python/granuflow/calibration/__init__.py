"""Calibration against batch experiments: experiment and stage files, synthetic data, staged calibration (Ceres,
C++ core), reports with parity plots, multi-start on threads.

Paper 001 (Fig. 10) calibrates in stages: heat and mass transfer first (against outlet gas temperature and bed
moisture), then size (against the characteristic diameters), then all parameters together, with the relative
standard deviations of Table 5 as loss weights. The residual of a sample is (model - data) / sigma with
sigma = sigma_abs, or sigma = sigma_rel * |model| (``sigma_basis="model"``, default: iteratively reweighted, unbiased
for noise proportional to the true value) or sigma_rel * |data| (``"data"``: biased low by about 2 sigma_rel^2).
Jacobians come from IDAS forward sensitivities (one solve per experiment and Jacobian), or from central
differences of plain simulations with ``options={"jacobian": "central_differences"}`` (the report says which).

Experiment file (YAML; paths relative to it; values in the units given, SI if none)::

    experiments: synthetic_gf25_table1
    description: ...
    scene: ../stoeckl_gf25_batch.yaml
    sigma:                                    # per observable: {abs: value [unit]} or {rel: fraction}
      gas.T: {abs: 2 K}
      bed.moisture: {abs: 0.01}               # kg/kg dry (1 wt%, Table 5)
      bed.d50: {rel: 0.07}
    runs:
      - name: C1
        kind: corner                          # label
        use: calibration                      # calibration | validation
        set: {inlet.V_dot: 600 m3/h, inlet.T: 40 degC, nozzle.mdot: 60 g/min}   # operating point, initial state
        t_end: 60 min                         # optional: default the last sample
        data: synthetic_gf25_table1/C1.csv    # CSV, header "t [min],bed.d50 [um],gas.T [degC],..."
      - name: F1
        use: validation
        set: {...}
        data:                                 # or inline columns with their units
          units: {t: min, bed.d50: um, gas.T: degC}
          t: [5, 10, 15]
          bed.d50: [230, 270, 300]
          gas.T: [36.2, 35.0, 34.6]
        sigma: {bed.d50: {rel: 0.05}}         # optional per-run override

Stage file (YAML)::

    name: paper001_fig10
    start: {wall.k_wall: 20, bed.X_cr: 0.1}   # optional start values (units allowed), else the scene's
    options: {sigma_basis: model}            # CalibrationOptions fields (C++), e.g. rtol, max_iterations
    stages:
      - name: heat_and_mass_transfer
        free:
          wall.k_wall: {transform: log, lower: 1, upper: 200}
          droplets.k_evap: {transform: log, lower: 1e-5, upper: 1}
        observables: [gas.T, bed.moisture]
      - name: size
        free: {bed.agg_ln_beta0: {lower: -25, upper: -10},
               spray_zone.h_pen: {transform: log, lower: 10 um, upper: 5 mm}}
        observables: [bed.d10, bed.d50, bed.d90]
      - name: all
        free: inherit                         # every parameter of the stages before, same bounds
        observables: all

Python::

    from granuflow import calibration as cal
    exps = cal.load_experiments("flowsheets/calibration/synthetic_gf25_table1.yaml")
    fs = exps.flowsheet()
    plan = cal.load_stages("flowsheets/calibration/stages_paper001.yaml", fs)
    res = cal.calibrate(fs, exps.calibration, plan.stages, start=plan.start, options=plan.options)
    rep = cal.report(fs, res, exps.calibration, exps.validation)
    rep.fit                      # R², RMSE per output and set;  res.estimates, res.correlation, res.history
    rep.write("out/calibration") # report.json, CSV tables, parity PNGs (plots=False: no PNGs)
"""
from .files import (CalibrationError, ConfigError, Experiment, ExperimentSet, FreeParameter, Observation, Stage,
                    StagePlan, check_stage_data, load_experiments, load_stages, save_experiments)
from .fit import (CalibrationResult, best, calibrate, compare_starts, multi_start, predict, random_starts,
                  stage_bounds)
from .psd_data import q3_observations
from .paper001 import D_VALUES, OBSERVABLE_DISPLAY, OBSERVABLE_GROUPS, TABLE1_LEVELS, TABLE5_SIGMA
from .report import CalibrationReport, fit_statistics, model_errors, report
from .synthetic import paper001_stages, synthetic_experiments, table1_points

__all__ = ["D_VALUES", "OBSERVABLE_DISPLAY", "OBSERVABLE_GROUPS", "CalibrationError", "ConfigError", "Experiment",
           "ExperimentSet", "FreeParameter", "Observation", "Stage", "StagePlan", "check_stage_data",
           "load_experiments", "load_stages", "save_experiments", "CalibrationResult", "best", "calibrate",
           "compare_starts", "multi_start", "predict", "random_starts", "stage_bounds", "TABLE1_LEVELS", "TABLE5_SIGMA",
           "CalibrationReport", "fit_statistics", "model_errors", "report", "paper001_stages", "synthetic_experiments",
           "table1_points", "q3_observations"]
