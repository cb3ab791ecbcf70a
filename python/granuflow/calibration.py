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
        free: {bed.ln_beta0: {lower: -25, upper: -10}, spray_zone.h_pen: {transform: log, lower: 10 um, upper: 5 mm}}
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
    rep.write("out/calibration") # report.json, CSV tables, parity PNGs
"""
from __future__ import annotations

import concurrent.futures as cf
import csv
import json
import math
import os
from dataclasses import dataclass, field
from typing import Any, Iterable, Mapping, Sequence

import numpy as np

from . import _core
from .flowsheet import Flowsheet, load
from .plots import _plt
from .sweep import _affine, _progress_bar, _split_quantity

ConfigError = _core.ConfigError
CalibrationError = _core.CalibrationError

# Paper 001, Table 5: standard deviations of the measurements (moisture and gas temperature absolute, SI).
D_VALUES = ("bed.d5", "bed.d10", "bed.d16", "bed.d25", "bed.d50", "bed.d75", "bed.d84", "bed.d90", "bed.d95")
TABLE5_SIGMA: dict[str, dict[str, float]] = {
    "bed.moisture": {"abs": 0.01},   # 1 wt%, kg/kg
    "gas.T": {"abs": 2.0},           # K
    **{d: {"rel": 0.07} for d in ("bed.d5", "bed.d10", "bed.d16", "bed.d25", "bed.d50")},
    "bed.d75": {"rel": 0.08}, "bed.d84": {"rel": 0.09}, "bed.d90": {"rel": 0.10}, "bed.d95": {"rel": 0.11},
}
# Paper 001, Table 1 levels (upper inlet temperature 80 degC as in Fig. 11, see docs/paper001_decisions.md).
TABLE1_LEVELS = {"inlet.V_dot": ("m3/h", (600.0, 700.0, 800.0)), "inlet.T": ("degC", (40.0, 60.0, 80.0)),
                 "nozzle.mdot": ("g/min", (60.0, 90.0, 120.0))}
# Display units of the observables in files, tables and plots.
DISPLAY_UNITS = {**{d: "um" for d in D_VALUES}, "bed.moisture": "wt%", "bed.moisture_wet": "wt%", "gas.T": "degC"}
GROUPS = {"size": D_VALUES, "moisture": ("bed.moisture", "bed.moisture_wet"), "T_gas_out": ("gas.T",)}

_EXP_KEYS = ("experiments", "description", "scene", "sigma", "runs")
_RUN_KEYS = ("name", "kind", "use", "set", "t_end", "data", "sigma")
_STAGEFILE_KEYS = ("name", "description", "start", "options", "stages")
_STAGE_KEYS = ("name", "free", "observables")
_FREE_KEYS = ("transform", "lower", "upper", "logarithmic")


# ------------------------------------------------------------------------------------------------
# quantities
# ------------------------------------------------------------------------------------------------
def _split(text: str, where: str = "") -> tuple[float, str]:
    try:
        return _split_quantity(str(text))
    except (ValueError, IndexError):
        raise ConfigError(f"{where + ' = ' if where else ''}'{text}': expected a number, optionally followed by a "
                          "unit") from None


def _number(value: Any, where: str) -> float:
    if isinstance(value, str):
        try:
            return float(value)
        except ValueError:
            pass
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise ConfigError(f"{where} = {value!r}: expected a number, optionally followed by a unit")
    return float(value)


def _to_si(value: Any, si_unit: str, where: str, unit: str = "") -> float:
    """A number in `unit` (or a string "value unit") converted to `si_unit`."""
    if isinstance(value, str):
        v, u = _split(value, where)
        return _core.to_si(v, u or unit, si_unit, where)
    return _core.to_si(_number(value, where), unit, si_unit, where)


def _show(x: Any) -> str:
    """A value as the user wrote it: numbers short (10, 0.5, inf), text quoted."""
    if isinstance(x, (int, float, np.integer, np.floating)) and not isinstance(x, bool):
        return f"{float(x):g}"
    return repr(x)


def _in_context(where: str, fn, *args):
    """fn(*args), a ConfigError from it prefixed with `where` (the file and key) unless it already names it."""
    try:
        return fn(*args)
    except ConfigError as e:
        msg = " ".join(str(e).split())
        raise ConfigError(msg if msg.startswith(where) else f"{where}: {msg}") from None


def _param_spec(fs: Flowsheet, name: str, where: str) -> dict:
    """The declared spec of parameter `name`; ConfigError naming `where` and the parameters otherwise."""
    if name not in fs.params:
        raise ConfigError(f"{where}: unknown parameter '{name}' of scene '{fs.name}' (allowed: {', '.join(fs.params)})")
    return fs.spec(name)


def _param_to_si(fs: Flowsheet, name: str, value: Any, where: str) -> float:
    """A parameter value (units allowed) in SI, within the declared bounds; ConfigError naming `where`."""
    spec = _param_spec(fs, name, where)
    v = _to_si(value, spec["unit"], where)
    if not (math.isfinite(v) and spec["lower"] <= v <= spec["upper"]):
        raise ConfigError(f"{where} = {_show(value)}: {v:g} {spec['unit']} is outside the declared bounds "
                          f"{spec['lower']:g} <= {name} <= {spec['upper']:g} {spec['unit']}".rstrip())
    return v


def _difference_to_si(value: Any, si_unit: str, where: str, unit: str = "") -> float:
    """A difference (a standard deviation): offsets such as degC -> K cancel."""
    if isinstance(value, str):
        v, u = _split(value, where)
        u = u or unit
    else:
        v, u = _number(value, where), unit
    return _core.to_si(v, u, si_unit, where) - _core.to_si(0.0, u, si_unit, where)


def _from_si(values: np.ndarray, unit: str, si_unit: str) -> np.ndarray:
    a, b = _affine(unit, si_unit, "unit")
    return (np.asarray(values, dtype=float) - a) / b


# ------------------------------------------------------------------------------------------------
# experiments
# ------------------------------------------------------------------------------------------------
@dataclass
class Observation:
    """One measured quantity of one run: times (s), values (SI; NaN = not measured) and sigma."""
    name: str
    t: np.ndarray
    value: np.ndarray
    sigma_abs: float = 0.0
    sigma_rel: float = 0.0

    def to_core(self) -> dict:
        return {"name": self.name, "t": [float(x) for x in self.t], "value": [float(x) for x in self.value],
                "sigma_abs": float(self.sigma_abs), "sigma_rel": float(self.sigma_rel)}


@dataclass
class Experiment:
    """A batch run: operating conditions and initial state (SI parameter values) and its observations."""
    name: str
    settings: dict[str, float] = field(default_factory=dict)
    observations: list[Observation] = field(default_factory=list)
    t_end: float | None = None
    kind: str = ""
    use: str = "calibration"

    def to_core(self) -> dict:
        return {"name": self.name, "settings": dict(self.settings), "t_end": self.t_end,
                "observations": [o.to_core() for o in self.observations]}

    def observation(self, name: str) -> Observation:
        for o in self.observations:
            if o.name == name:
                return o
        raise KeyError(f"experiment {self.name!r} has no observation {name!r}")


@dataclass
class ExperimentSet:
    name: str
    experiments: list[Experiment]
    scene: str = ""
    description: str = ""

    @property
    def calibration(self) -> list[Experiment]:
        return [e for e in self.experiments if e.use == "calibration"]

    @property
    def validation(self) -> list[Experiment]:
        return [e for e in self.experiments if e.use == "validation"]

    def flowsheet(self) -> Flowsheet:
        if not self.scene:
            raise ConfigError(f"experiment set {self.name!r} names no scene")
        return load(self.scene)

    def __len__(self) -> int:
        return len(self.experiments)


def _sigma_entry(spec: Any, si_unit: str, where: str) -> tuple[float, float]:
    if not isinstance(spec, Mapping) or set(spec) - {"abs", "rel"} or len(spec) != 1:
        raise ConfigError(f"{where}: expected {{abs: value [unit]}} or {{rel: fraction}}, got {spec!r}")
    if "abs" in spec:
        v = _difference_to_si(spec["abs"], si_unit, where)
        if not (v > 0 and math.isfinite(v)):
            raise ConfigError(f"{where}.abs = {spec['abs']!r}: violates 0 < abs < inf")
        return v, 0.0
    v = _number(spec["rel"], f"{where}.rel")
    if not (v > 0 and math.isfinite(v)):
        raise ConfigError(f"{where}.rel = {v}: violates rel > 0")
    return 0.0, v


def _parse_header(h: str) -> tuple[str, str]:
    h = h.strip()
    if h.endswith("]") and "[" in h:
        name, unit = h[:-1].split("[", 1)
        return name.strip(), unit.strip()
    return h, ""


def _read_csv(path: str) -> tuple[dict[str, list[float | None]], dict[str, str], list[int]]:
    """Columns (None: an empty field, not measured; inf and nan kept, the caller rejects them), units and the
    line number of every row."""
    with open(path, newline="") as f:
        rows = list(enumerate(csv.reader(f), start=1))
    rows = [(i, r) for i, r in rows if r and not r[0].lstrip().startswith("#")]
    if not rows:
        raise ConfigError(f"{path}: empty data file")
    header = [_parse_header(h) for h in rows[0][1]]
    names = [n for n, _ in header]
    if len(set(names)) != len(names):
        dup = next(n for n in names if names.count(n) > 1)
        raise ConfigError(f"{path}:{rows[0][0]}: column '{dup}' appears twice in the header")
    cols: dict[str, list[float | None]] = {n: [] for n in names}
    lines = []
    for i, r in rows[1:]:
        if len(r) != len(header):
            raise ConfigError(f"{path}:{i}: {len(r)} fields, the header has {len(header)}")
        for n, v in zip(names, r):
            v = v.strip()
            try:
                cols[n].append(None if v == "" else float(v))
            except ValueError:
                raise ConfigError(f"{path}:{i}: column {n}: '{v}' is not a number "
                                  "(leave the field empty: not measured)") from None
        lines.append(i)
    return cols, {n: u for n, u in header}, lines


def _check_mapping(doc: Any, allowed: Sequence[str], where: str) -> dict:
    """`doc` itself, checked to be a mapping with only the `allowed` keys."""
    if not isinstance(doc, dict):
        raise ConfigError(f"{where}: expected a mapping with keys {', '.join(allowed)}, got {doc!r}")
    for k in doc:
        if k not in allowed:
            raise ConfigError(f"{where}: unknown key '{k}' (allowed: {', '.join(allowed)})")
    return doc


def _read_mapping(path: str, allowed: Sequence[str]) -> dict:
    """A YAML file whose top level is a mapping with only the `allowed` keys."""
    import yaml

    with open(path) as f:
        try:
            doc = yaml.safe_load(f) or {}
        except yaml.YAMLError as e:
            raise ConfigError(f"{path}: not valid YAML ({' '.join(str(e).split())})") from None
    return _check_mapping(doc, allowed, path)


def load_experiments(path: str | os.PathLike, flowsheet: Flowsheet | None = None) -> ExperimentSet:
    """Read an experiment file (see the module docstring). Raises ConfigError naming the file and key."""
    path = os.fspath(path)
    base = os.path.dirname(os.path.abspath(path))
    doc = _read_mapping(path, _EXP_KEYS)
    scene = doc.get("scene", "")
    if scene and not os.path.isabs(scene):
        scene = os.path.normpath(os.path.join(base, scene))
    fs = flowsheet or (load(scene) if scene else None)
    if fs is None:
        raise ConfigError(f"{path}: give `scene:` or pass a flowsheet")
    sc = fs._scene
    defaults = doc.get("sigma") or {}
    if not isinstance(defaults, dict):
        raise ConfigError(f"{path}: sigma: expected a mapping observable -> {{abs: value [unit]}} or {{rel: fraction}}, "
                          f"got {defaults!r}")
    runs = doc.get("runs")
    if not isinstance(runs, list) or not runs:
        raise ConfigError(f"{path}: `runs` must be a non-empty list")
    exps = []
    names = set()
    for i, run in enumerate(runs):
        _check_mapping(run, _RUN_KEYS, f"{path}: runs[{i}]")
        name = str(run.get("name", f"run{i + 1}"))
        if name in names:
            raise ConfigError(f"{path}: runs[{i}]: duplicate run name '{name}'")
        names.add(name)
        where = f"{path}: run {name}"
        use = run.get("use", "calibration")
        if use not in ("calibration", "validation"):
            raise ConfigError(f"{where}.use = '{use}': not one of calibration, validation")
        for k in ("set", "sigma"):
            if not isinstance(run.get(k) or {}, dict):
                raise ConfigError(f"{where}.{k}: expected a mapping, got {run[k]!r}")
        settings = {}
        for k, v in (run.get("set") or {}).items():
            settings[k] = _param_to_si(fs, k, v, f"{where}.set.{k}")
        t_end = run.get("t_end")
        if t_end is not None:
            t_end_si = _to_si(t_end, "s", f"{where}.t_end")
            if not (t_end_si > 0 and math.isfinite(t_end_si)):
                raise ConfigError(f"{where}.t_end = {_show(t_end)}: violates 0 < t_end < inf (leave it out for the last "
                                  "sample time)")
            t_end = t_end_si
        data = run.get("data")
        if isinstance(data, str):
            csv_path = data if os.path.isabs(data) else os.path.join(base, data)
            cols, units, lines = _in_context(f"{where}.data", _read_csv, csv_path)

            def at(name: str, i: int) -> str:
                return f"{where}.data: {csv_path}:{lines[i]}: {name}"
            empty = "leave the field empty"
        elif isinstance(data, dict):
            units = data.get("units", {}) or {}
            if not isinstance(units, dict) or not all(isinstance(u, str) for u in units.values()):
                raise ConfigError(f"{where}.data.units: expected a mapping column -> unit name, got {units!r}")
            units = dict(units)
            cols = {}
            for k, v in data.items():
                if k == "units":
                    continue
                if not isinstance(v, list) or not all(x is None or (isinstance(x, (int, float)) and
                                                                    not isinstance(x, bool)) for x in v):
                    raise ConfigError(f"{where}.data.{k}: expected a list of numbers (null: not measured), got {v!r}")
                cols[k] = [None if x is None else float(x) for x in v]

            def at(name: str, i: int) -> str:
                return f"{where}.data.{name}[{i}]"
            empty = "null"
        else:
            raise ConfigError(f"{where}.data: expected a CSV file name or a mapping of columns, got {data!r}")
        if "t" not in cols:
            raise ConfigError(f"{where}.data: no time column 't' (e.g. 't [min]')")
        t_raw = cols.pop("t")
        t_unit = units.get("t", "")
        for k in units:
            if k != "t" and k not in cols:
                raise ConfigError(f"{where}.data.units: '{k}' is not a data column (columns: {', '.join(['t', *cols])})")
        t = []
        for i, x in enumerate(t_raw):
            ts = math.nan if x is None else _to_si(x, "s", f"{at('t', i)}", t_unit)
            if not (ts >= 0 and math.isfinite(ts)) or (t and not ts > t[-1]):
                raise ConfigError(f"{at('t', i)} = {_show(x)} {t_unit}: times must be finite, >= 0 and increasing".rstrip())
            if t_end is not None and ts > t_end * (1 + 1e-12):
                raise ConfigError(f"{at('t', i)} = {_show(x)} {t_unit}: after the run's end, t_end = {_show(run['t_end'])} "
                                  "(data must lie within 0 <= t <= t_end)")
            t.append(ts)
        t = np.array(t, dtype=float)

        def t_text(i: int) -> str:
            return f"t = {_show(t_raw[i])} {t_unit}".rstrip()
        sig = {**defaults, **(run.get("sigma") or {})}
        obs = []
        for oname, values in cols.items():
            si_unit = _in_context(f"{where}.data.{oname}", _core.observable_unit, sc, oname)
            if len(values) != len(t):
                raise ConfigError(f"{where}.data.{oname}: {len(values)} values for {len(t)} times")
            v = []
            for i, x in enumerate(values):
                if x is None:
                    v.append(math.nan)
                    continue
                if not math.isfinite(x):
                    raise ConfigError(f"{at(oname, i)} = {_show(x)} at {t_text(i)}: not a finite number ({empty}: not "
                                      "measured)")
                xs = _to_si(x, si_unit, f"{where}.data.{oname}", units.get(oname, ""))
                if not math.isfinite(xs):
                    raise ConfigError(f"{at(oname, i)} = {x} at {t_text(i)}: {xs} {si_unit} is not finite")
                v.append(xs)
            v = np.array(v, dtype=float)
            if oname not in sig:
                raise ConfigError(f"{where}: no sigma for observable {oname} (give it under `sigma:`)")
            sa, sr = _sigma_entry(sig[oname], si_unit, f"{where}: sigma.{oname}")
            keep = np.isfinite(v)
            obs.append(Observation(oname, t[keep], v[keep], sa, sr))
        if not any(len(o.t) for o in obs):
            raise ConfigError(f"{where}.data: no measured value (every value is {empty} or there are no rows); "
                              "give at least one number")
        exps.append(Experiment(name, settings, obs, t_end, str(run.get("kind", "")), use))
    return ExperimentSet(str(doc.get("experiments", os.path.splitext(os.path.basename(path))[0])), exps,
                         scene, str(doc.get("description", "")))


def save_experiments(es: ExperimentSet, path: str | os.PathLike, *, csv_dir: str | None = None,
                     time_unit: str = "min") -> None:
    """Write an experiment file; data go to one CSV per run in `csv_dir` (relative to the file), or inline."""
    import yaml

    path = os.fspath(path)
    base = os.path.dirname(os.path.abspath(path))
    scene = os.path.relpath(es.scene, base) if es.scene else ""
    sigma: dict[str, dict] = {}
    runs = []
    si_of = {"inlet.V_dot": "m3/s", "inlet.T": "K", "nozzle.mdot": "kg/s"}
    for e in es.experiments:
        times = sorted({float(x) for o in e.observations for x in o.t})
        cols = {"t": _from_si(np.array(times), time_unit, "s")}
        units = {"t": time_unit}
        for o in e.observations:
            si_unit = DISPLAY_SI.get(o.name, "")
            unit = DISPLAY_UNITS.get(o.name, "")
            col = np.full(len(times), math.nan)
            idx = [times.index(float(x)) for x in o.t]
            col[idx] = _from_si(o.value, unit, si_unit) if unit else o.value
            cols[o.name] = col
            units[o.name] = unit
            sigma[o.name] = ({"abs": f"{o.sigma_abs:g} {si_unit}".strip()} if o.sigma_abs > 0
                             else {"rel": float(o.sigma_rel)})
        run: dict[str, Any] = {"name": e.name}
        if e.kind:
            run["kind"] = e.kind
        run["use"] = e.use
        run["set"] = {k: (f"{float(_from_si(np.array([v]), TABLE1_LEVELS[k][0], si_of[k])[0]):.6g} {TABLE1_LEVELS[k][0]}"
                          if k in TABLE1_LEVELS else float(v)) for k, v in e.settings.items()}
        if e.t_end:
            run["t_end"] = f"{e.t_end:g} s"
        if csv_dir:
            os.makedirs(os.path.join(base, csv_dir), exist_ok=True)
            rel = os.path.join(csv_dir, f"{e.name}.csv")
            with open(os.path.join(base, rel), "w", newline="") as f:
                w = csv.writer(f)
                w.writerow([f"{k} [{units[k]}]" if units[k] else k for k in cols])
                for i in range(len(times)):
                    w.writerow([("" if not np.isfinite(cols[k][i]) else f"{cols[k][i]:.6g}") for k in cols])
            run["data"] = rel
        else:
            run["data"] = {"units": {k: u for k, u in units.items() if u},
                           **{k: [None if not np.isfinite(x) else float(f"{x:.6g}") for x in v] for k, v in cols.items()}}
        runs.append(run)
    doc = {"experiments": es.name, "description": es.description, "scene": scene, "sigma": sigma, "runs": runs}
    with open(path, "w") as f:
        f.write("# granuflow experiment file (format: granuflow/calibration.py). Values without a unit are SI; "
                "data columns carry their units.\n")
        yaml.safe_dump(doc, f, sort_keys=False, width=120)


DISPLAY_SI = {**{d: "m" for d in D_VALUES}, "bed.moisture": "kg/kg", "bed.moisture_wet": "kg/kg", "gas.T": "K"}


def table1_points() -> list[dict]:
    """The 15 runs of paper 001, Table 1: 8 cube corners (calibration), 6 face centres and the centre (validation).

    Each item: {"name", "kind", "use", "set": {param: "value unit"}}."""
    (vu, V), (tu, T), (mu, M) = (TABLE1_LEVELS[k] for k in ("inlet.V_dot", "inlet.T", "nozzle.mdot"))
    pts = []
    k = 0
    for m in (M[0], M[2]):
        for t in (T[0], T[2]):
            for v in (V[0], V[2]):
                k += 1
                pts.append((f"C{k}", "corner", v, t, m))
    faces = [(V[0], T[1], M[1]), (V[2], T[1], M[1]), (V[1], T[0], M[1]), (V[1], T[2], M[1]), (V[1], T[1], M[0]),
             (V[1], T[1], M[2])]
    pts += [(f"F{i + 1}", "face", *f) for i, f in enumerate(faces)]
    pts.append(("Z", "centre", V[1], T[1], M[1]))
    return [{"name": n, "kind": kind, "use": "calibration" if kind == "corner" else "validation",
             "set": {"inlet.V_dot": f"{v:g} {vu}", "inlet.T": f"{t:g} {tu}", "nozzle.mdot": f"{m:g} {mu}"}}
            for n, kind, v, t, m in pts]


def synthetic_experiments(flowsheet: Flowsheet, points: Sequence[Mapping], params: Mapping[str, float] | None = None,
                          *, times: Sequence[float] | None = None, observables: Sequence[str] | None = None,
                          sigma: Mapping[str, Mapping[str, float]] | None = None, seed: int | None = 0,
                          noise: bool = True, name: str = "synthetic", workers: int = 2) -> ExperimentSet:
    """Experiments simulated with the flowsheet at `points` (see :func:`table1_points`) and parameters `params`
    (SI), sampled at `times` (s; default every 5 min to 60 min), with Gaussian noise at `sigma` (default
    :data:`TABLE5_SIGMA`): data = model + sigma_abs * N(0,1), or model * (1 + sigma_rel * N(0,1))."""
    sigma = dict(sigma or TABLE5_SIGMA)
    observables = list(observables or (["gas.T", "bed.moisture"] + list(D_VALUES)))
    times = np.asarray(times if times is not None else np.arange(5, 61, 5) * 60.0, dtype=float)
    rng = np.random.default_rng(seed)
    exps = []
    for p in points:
        settings = {k: _to_si(v, flowsheet.spec(k)["unit"], f"point {p.get('name')}.{k}") for k, v in p["set"].items()}
        obs = []
        for o in observables:
            if o not in sigma:
                raise ConfigError(f"sigma: no entry for observable {o} (given: {', '.join(sigma)})")
            si_unit = DISPLAY_SI.get(o) or _core.observable_unit(flowsheet._scene, o)
            sa, sr = _sigma_entry(sigma[o], si_unit, f"sigma.{o}")
            obs.append(Observation(o, times.copy(), np.zeros(len(times)), sa, sr))
        exps.append(Experiment(str(p.get("name")), settings, obs, float(times[-1]), str(p.get("kind", "")),
                               str(p.get("use", "calibration"))))
    pred = _core.predict(flowsheet._scene, [e.to_core() for e in exps], dict(params or {}), {"num_threads": workers})
    by = {(q["experiment"], q["observable"]): np.asarray(q["model"]) for q in pred}
    for e in exps:  # noise drawn in a fixed order: experiment, observable, time
        for o in e.observations:
            m = by[(e.name, o.name)]
            z = rng.standard_normal(len(m)) if noise else np.zeros(len(m))
            o.value = m + o.sigma_abs * z if o.sigma_abs > 0 else m * (1 + o.sigma_rel * z)
    return ExperimentSet(name, exps, flowsheet.path, f"synthetic: {len(exps)} runs, seed {seed}")


# ------------------------------------------------------------------------------------------------
# stages
# ------------------------------------------------------------------------------------------------
@dataclass
class FreeParameter:
    name: str
    transform: str = "none"             # none | log
    lower: float | None = None          # SI; None: the declared bound
    upper: float | None = None
    logarithmic: bool | None = None     # the parameter is itself a logarithm (default: name starts with ln_)

    def to_core(self) -> dict:
        return {"name": self.name, "transform": self.transform, "lower": self.lower, "upper": self.upper,
                "logarithmic": self.logarithmic}


@dataclass
class Stage:
    name: str
    free: list[FreeParameter]
    observables: list[str] = field(default_factory=list)   # empty: all observations

    def to_core(self) -> dict:
        return {"name": self.name, "free": [f.to_core() for f in self.free], "observables": list(self.observables)}

    @property
    def params(self) -> list[str]:
        return [f.name for f in self.free]


@dataclass
class StagePlan:
    name: str
    stages: list[Stage]
    start: dict[str, float] = field(default_factory=dict)
    options: dict[str, Any] = field(default_factory=dict)
    description: str = ""

    def simultaneous(self) -> list[Stage]:
        """All free parameters at once against all observables (the comparison with the staged route)."""
        return [Stage("simultaneous", _all_free(self.stages), [])]


def _all_free(stages: Sequence[Stage]) -> list[FreeParameter]:
    """The free parameters of all stages, each once (as first declared)."""
    free: dict[str, FreeParameter] = {}
    for s in stages:
        for f in s.free:
            free.setdefault(f.name, f)
    return list(free.values())


def load_stages(path: str | os.PathLike, flowsheet: Flowsheet) -> StagePlan:
    """Read a stage file (see the module docstring)."""
    path = os.fspath(path)
    doc = _read_mapping(path, _STAGEFILE_KEYS)
    start_doc = doc.get("start") or {}
    if not isinstance(start_doc, dict):
        raise ConfigError(f"{path}: start: expected a mapping parameter -> value [unit], got {start_doc!r}")
    start = {k: _param_to_si(flowsheet, k, v, f"{path}: start.{k}") for k, v in start_doc.items()}
    options = doc.get("options") or {}
    if not isinstance(options, dict):
        raise ConfigError(f"{path}: options: expected a mapping of CalibrationOptions fields, got {options!r}")
    options = dict(options)
    _in_context(f"{path}: options", _core.check_calibration_options, options)
    stages: list[Stage] = []
    seen: dict[str, FreeParameter] = {}
    if not isinstance(doc.get("stages") or [], list):
        raise ConfigError(f"{path}: stages: expected a list of stages, got {doc['stages']!r}")
    for i, st in enumerate(doc.get("stages") or []):
        where = f"{path}: stages[{i}]"
        _check_mapping(st, _STAGE_KEYS, where)
        name = str(st.get("name", f"stage{i + 1}"))
        free_spec = st.get("free")
        free: list[FreeParameter] = []
        if free_spec == "inherit":
            free = list(seen.values())
            if not free:
                raise ConfigError(f"{where}.free = inherit: no stage before it has free parameters")
        elif isinstance(free_spec, dict):
            for p, spec in free_spec.items():
                fp = _free_parameter(flowsheet, p, spec, f"{where}.free.{p}")
                free.append(fp)
                seen[p] = fp
            if not free:
                raise ConfigError(f"{where}.free: empty; give at least one parameter "
                                  "(e.g. wall.k_wall: {transform: log, lower: 1, upper: 200}) or 'inherit'")
        else:
            raise ConfigError(f"{where}.free = {free_spec!r}: expected a mapping of parameters or 'inherit'")
        obs = st.get("observables", "all")
        if obs not in ("all", None) and not isinstance(obs, list):
            raise ConfigError(f"{where}.observables: expected a list of observables or 'all', got {obs!r}")
        obs = [] if obs in ("all", None) else [str(o) for o in obs]
        for j, o in enumerate(obs):
            _in_context(f"{where}.observables[{j}]", _core.observable_unit, flowsheet._scene, o)
        stages.append(Stage(name, free, obs))
    if not stages:
        raise ConfigError(f"{path}: no stages")
    for k, v in start.items():
        for i, stg in enumerate(stages):
            for f in stg.free:
                if f.name != k:
                    continue
                spec = flowsheet.spec(k)
                lo = spec["lower"] if f.lower is None else f.lower
                hi = spec["upper"] if f.upper is None else f.upper
                if not lo <= v <= hi:
                    raise ConfigError(f"{path}: start.{k} = {_show(start_doc[k])}: {v:g} {spec['unit']} is outside the "
                                      f"bounds {lo:g} <= {k} <= {hi:g} {spec['unit']} of stage '{stg.name}' "
                                      f"(stages[{i}].free.{k})")
    return StagePlan(str(doc.get("name", os.path.splitext(os.path.basename(path))[0])), stages, start, options,
                     str(doc.get("description", "")))


def _free_parameter(flowsheet: Flowsheet, p: str, spec: Any, where: str) -> FreeParameter:
    """One entry of a stage's ``free:`` mapping, checked: parameter, transform, bounds (SI), logarithmic."""
    spec = _check_mapping({} if spec is None else spec, _FREE_KEYS, where)
    decl = _param_spec(flowsheet, p, where)
    u = decl["unit"]
    transform = spec.get("transform", "none")
    if transform not in ("none", "log"):
        raise ConfigError(f"{where}.transform = {transform!r}: not one of none, log")
    bounds = {}
    for key in ("lower", "upper"):
        if spec.get(key) is None:
            bounds[key] = None
            continue
        v = _to_si(spec[key], u, f"{where}.{key}")
        if math.isnan(v):
            raise ConfigError(f"{where}.{key} = {_show(spec[key])}: not a number")
        bounds[key] = v
    lo = decl["lower"] if bounds["lower"] is None else bounds["lower"]
    hi = decl["upper"] if bounds["upper"] is None else bounds["upper"]
    if bounds["lower"] is not None and not lo >= decl["lower"]:
        raise ConfigError(f"{where}.lower = {_show(spec['lower'])}: below the declared lower bound {decl['lower']:g} {u}")
    if bounds["upper"] is not None and not hi <= decl["upper"]:
        raise ConfigError(f"{where}.upper = {_show(spec['upper'])}: above the declared upper bound {decl['upper']:g} {u}")
    if not hi > lo:
        key = "upper" if bounds["upper"] is not None else "lower"
        raise ConfigError(f"{where}.{key} = {_show(spec.get(key, hi))}: violates upper > lower "
                          f"(lower {lo:g} {u}, upper {hi:g} {u})")
    if transform == "log" and not lo > 0:
        raise ConfigError(f"{where}.lower = {_show(spec.get('lower', lo))}: transform log needs lower > 0 "
                          f"(lower {lo:g} {u})")
    logarithmic = spec.get("logarithmic")
    if logarithmic is not None and not isinstance(logarithmic, bool):
        raise ConfigError(f"{where}.logarithmic = {logarithmic!r}: expected true or false")
    return FreeParameter(p, transform, bounds["lower"], bounds["upper"], logarithmic)


def check_stage_data(plan: "StagePlan", experiments: Sequence[Experiment], stages_path: str = "",
                     experiments_path: str = "") -> None:
    """Every stage must see data: some experiment measures at least one of its observables (bad input otherwise)."""
    measured = {o.name for e in experiments for o in e.observations if len(o.t)}
    for i, st in enumerate(plan.stages):
        wanted = st.observables or sorted(measured)
        if not measured.intersection(wanted):
            where = f"{stages_path}: stages[{i}] '{st.name}'" if stages_path else f"stage '{st.name}'"
            src = f"calibration run of {experiments_path}" if experiments_path else "calibration experiment"
            raise ConfigError(f"{where}.observables = [{', '.join(st.observables) or 'all'}]: no {src} "
                              f"has data for them (measured: {', '.join(sorted(measured)) or 'nothing'})")


def paper001_stages() -> StagePlan:
    """The staged route of paper 001, Fig. 10, for the headline scene (the bounds of stages_paper001.yaml)."""
    hmt = [FreeParameter("wall.k_wall", "log", 1.0, 200.0), FreeParameter("droplets.k_evap", "log", 1e-5, 1.0),
           FreeParameter("bed.X_cr", "log", 0.01, 0.5)]
    size = [FreeParameter("bed.ln_beta0", "none", -25.0, -10.0), FreeParameter("spray_zone.h_pen", "log", 1e-5, 5e-3),
            FreeParameter("bed.k_break", "log", 1e-6, 1.0)]
    return StagePlan("paper001_fig10", [Stage("heat_and_mass_transfer", hmt, ["gas.T", "bed.moisture"]),
                                        Stage("size", size, list(D_VALUES)), Stage("all", hmt + size, [])])


# ------------------------------------------------------------------------------------------------
# results
# ------------------------------------------------------------------------------------------------
class CalibrationResult:
    """The outcome of :func:`calibrate`: numpy arrays and dicts; DataFrames on request (pandas imported lazily).

    Attributes: ``stages`` (list of dicts: estimates, covariance, correlation, history), ``parameters`` (final
    values, SI), ``simulations``, ``sensitivity_solves``, ``wall_time_s``, ``status``, ``message``.
    """

    def __init__(self, raw: dict, *, label: str = ""):
        self.raw = raw
        self.label = label
        self.stages = raw["stages"]
        self.parameters = dict(raw["parameters"])
        self.simulations = int(raw["simulations"])
        self.sensitivity_solves = int(raw["sensitivity_solves"])
        self.wall_time_s = float(raw["wall_time_s"])
        self.status = raw["status"]
        self.message = raw["message"]

    def brief(self) -> str:
        return self.raw["brief"]

    def full_report(self) -> str:
        return self.raw["full_report"]

    def __repr__(self) -> str:
        return f"<granuflow.CalibrationResult {self.brief()}>"

    @property
    def final(self) -> dict:
        return self.stages[-1]

    @property
    def cost(self) -> float:
        return float(self.final["cost"])

    @property
    def flagged(self) -> list[str]:
        """Parameters of the last stage the data cannot identify (not reported as recovered)."""
        return [e["name"] for e in self.final["estimates"] if not e["identifiable"]]

    def estimate(self, name: str) -> dict:
        for e in self.final["estimates"]:
            if e["name"] == name:
                return e
        raise KeyError(name)

    def estimates_frame(self, stage: int | str = -1):
        import pandas as pd

        st = self._stage(stage)
        df = pd.DataFrame(st["estimates"]).set_index("name")
        return df[["start", "value", "se", "rel_se", "transform", "lower", "upper", "at_bound", "identifiable", "flag"]]

    @property
    def estimates(self):
        """Final estimates: start, value, standard error (SI), relative SE, bounds, identifiability flag."""
        return self.estimates_frame(-1)

    @property
    def correlation(self):
        import pandas as pd

        st = self.final
        names = [e["name"] for e in st["estimates"]]
        return pd.DataFrame(np.asarray(st["correlation"]), index=names, columns=names)

    @property
    def history(self):
        """Stage by stage: cost, iterations, reweighting passes, simulations, sensitivity solves, time, parameters."""
        import pandas as pd

        rows = []
        for s in self.stages:
            row = {"stage": s["name"], "observables": " ".join(s["observables"]) or "all",
                   "initial_cost": s["initial_cost"], "cost": s["cost"], "chi2_reduced": s["chi2_reduced"],
                   "residuals": s["residuals"], "iterations": s["iterations"], "passes": s["passes"],
                   "simulations": s["simulations"], "sensitivity_solves": s["sensitivity_solves"],
                   "wall_time_s": s["wall_time_s"], "jacobian": s["jacobian_method"], "termination": s["termination"]}
            for e in s["estimates"]:
                row[e["name"]] = e["value"]
            rows.append(row)
        return pd.DataFrame(rows).set_index("stage")

    @property
    def profiles(self) -> list[dict]:
        return list(self.final["profiles"])

    def _stage(self, stage: int | str) -> dict:
        if isinstance(stage, str):
            for s in self.stages:
                if s["name"] == stage:
                    return s
            raise KeyError(stage)
        return self.stages[stage]

    def to_json(self) -> dict:
        def clean(x):
            if isinstance(x, dict):
                return {k: clean(v) for k, v in x.items()}
            if isinstance(x, (list, tuple)):
                return [clean(v) for v in x]
            if isinstance(x, np.ndarray):
                return clean(x.tolist())
            if isinstance(x, float) and not math.isfinite(x):
                return None
            return x

        return clean({k: v for k, v in self.raw.items() if k != "full_report"})


def _core_list(exps: Iterable[Experiment]) -> list[dict]:
    return [e.to_core() for e in exps]


def _options(options: Mapping[str, Any] | None) -> dict:
    return {"num_threads": min(2, os.cpu_count() or 1), **dict(options or {})}


def calibrate(flowsheet: Flowsheet, experiments: Sequence[Experiment], stages: Sequence[Stage] | StagePlan, *,
              start: Mapping[str, float] | None = None, options: Mapping[str, Any] | None = None,
              label: str = "") -> CalibrationResult:
    """Run the stages in order (each from the previous estimates) on the C++ core; the GIL is released.

    ``options``: CalibrationOptions fields (``num_threads`` default 2, ``sigma_basis``, ``jacobian``, ``rtol``,
    ``profile``, ...). Unknown keys raise ConfigError; a failed stage raises CalibrationError.
    """
    if isinstance(stages, StagePlan):
        start = {**stages.start, **dict(start or {})}
        options = {**stages.options, **dict(options or {})}
        stages = stages.stages
    raw = _core.calibrate(flowsheet._scene, _core_list(experiments), [s.to_core() for s in stages], _options(options),
                          {k: float(v) for k, v in dict(start or {}).items()})
    return CalibrationResult(raw, label=label)


def predict(flowsheet: Flowsheet, experiments: Sequence[Experiment], params: Mapping[str, float] | None = None, *,
            options: Mapping[str, Any] | None = None) -> list[dict]:
    """Model at the sampled times: list of {experiment, observable, t, data, model, sigma} (SI)."""
    return _core.predict(flowsheet._scene, _core_list(experiments), dict(params or {}), _options(options))


def _group_of(name: str) -> str:
    for g, members in GROUPS.items():
        if name in members:
            return g
    return name


def fit_statistics(predictions: Sequence[dict], groups: bool = True) -> list[dict]:
    """R² = 1 - SS_res/SS_tot and RMSE (SI) per observable, and per group (size = all d-values pooled)."""
    pooled: dict[str, list[tuple[np.ndarray, np.ndarray]]] = {}
    for p in predictions:
        keys = [p["observable"]] + ([_group_of(p["observable"])] if groups else [])
        for k in dict.fromkeys(keys):
            pooled.setdefault(k, []).append((np.asarray(p["data"]), np.asarray(p["model"])))
    out = []
    for k, parts in pooled.items():
        d = np.concatenate([a for a, _ in parts])
        m = np.concatenate([b for _, b in parts])
        ok = np.isfinite(d) & np.isfinite(m)
        d, m = d[ok], m[ok]
        ss_res = float(np.sum((d - m) ** 2))
        ss_tot = float(np.sum((d - d.mean()) ** 2)) if len(d) else math.nan
        out.append({"output": k, "n": int(len(d)), "r2": 1 - ss_res / ss_tot if ss_tot > 0 else math.nan,
                    "rmse": math.sqrt(ss_res / len(d)) if len(d) else math.nan,
                    "mean_abs_rel": float(np.mean(np.abs(m - d) / np.abs(d))) if len(d) else math.nan})
    return out


@dataclass
class CalibrationReport:
    """Estimates, correlation, history, flags and fit statistics (R², RMSE) on calibration and validation sets."""
    result: CalibrationResult
    predictions: dict[str, list[dict]]            # set name -> predictions
    fit_rows: list[dict]
    comparison: CalibrationResult | None = None   # e.g. the simultaneous fit from the same start
    truth: dict[str, float] | None = None

    @property
    def fit(self):
        import pandas as pd

        return pd.DataFrame(self.fit_rows).set_index(["set", "output"])

    def recovery(self):
        """Estimates against known true values (synthetic data): error in standard errors, verdict."""
        import pandas as pd

        if not self.truth:
            raise ValueError("no true parameters given")
        rows = []
        for e in self.result.final["estimates"]:
            if e["name"] not in self.truth:
                continue
            true = self.truth[e["name"]]
            z = (e["value"] - true) / e["se"] if e["se"] and math.isfinite(e["se"]) else math.nan
            verdict = ("flagged unidentifiable" if not e["identifiable"]
                       else "recovered" if abs(z) <= 2 else "NOT recovered")
            rows.append({"param": e["name"], "true": true, "estimate": e["value"], "se": e["se"],
                         "error_in_se": z, "verdict": verdict, "flag": e["flag"]})
        return pd.DataFrame(rows).set_index("param")

    def parity_plots(self, out_dir: str) -> list[str]:
        """One PNG per output group (size, moisture, outlet gas temperature): model against data."""
        plt = _plt()
        os.makedirs(out_dir, exist_ok=True)
        written = []
        for group, members in GROUPS.items():
            fig, ax = plt.subplots(figsize=(4.6, 4.4))
            lo, hi, any_pts = math.inf, -math.inf, False
            for (setname, preds), marker in zip(self.predictions.items(), ("o", "^", "s")):
                d, m = [], []
                for p in preds:
                    if p["observable"] in members:
                        unit = DISPLAY_UNITS.get(p["observable"], "")
                        si = DISPLAY_SI.get(p["observable"], "")
                        d.append(_from_si(p["data"], unit, si) if unit else np.asarray(p["data"]))
                        m.append(_from_si(p["model"], unit, si) if unit else np.asarray(p["model"]))
                if not d:
                    continue
                d, m = np.concatenate(d), np.concatenate(m)
                r2 = next((r["r2"] for r in self.fit_rows if r["set"] == setname and r["output"] == group), math.nan)
                ax.scatter(d, m, s=9, marker=marker, alpha=0.6, label=f"{setname} (R² {r2:.3f})")
                lo, hi, any_pts = min(lo, d.min(), m.min()), max(hi, d.max(), m.max()), True
            if not any_pts:
                plt.close(fig)
                continue
            ax.plot([lo, hi], [lo, hi], "k-", lw=0.8)
            unit = DISPLAY_UNITS.get(members[0], "")
            ax.set_xlabel(f"measured ({unit})")
            ax.set_ylabel(f"model ({unit})")
            ax.set_title({"size": "characteristic diameters d5..d95", "moisture": "bed moisture",
                          "T_gas_out": "outlet gas temperature"}[group])
            ax.legend(fontsize=8)
            fig.tight_layout()
            name = os.path.join(out_dir, f"parity_{group}.png")
            fig.savefig(name, dpi=110)
            plt.close(fig)
            written.append(name)
        return written

    def to_json(self) -> dict:
        out = {"result": self.result.to_json(), "fit": self.fit_rows,
               "comparison": None if self.comparison is None else self.comparison.to_json()}
        if self.truth:
            out["truth"] = dict(self.truth)
        return json.loads(json.dumps(out, default=float).replace("NaN", "null").replace("Infinity", "null"))

    def write(self, out_dir: str) -> list[str]:
        """report.json, report.txt, estimates.csv, correlation.csv, history.csv, fit.csv, predictions.csv, PNGs."""
        os.makedirs(out_dir, exist_ok=True)
        files = []

        def put(name, text):
            with open(os.path.join(out_dir, name), "w") as f:
                f.write(text)
            files.append(name)

        put("report.json", json.dumps(self.to_json(), indent=2))
        txt = self.result.full_report()
        if self.comparison is not None:
            txt += "\n\nComparison (" + (self.comparison.label or "other route") + "):\n" + self.comparison.full_report()
        put("report.txt", txt)
        self.result.estimates.to_csv(os.path.join(out_dir, "estimates.csv"))
        self.result.correlation.to_csv(os.path.join(out_dir, "correlation.csv"))
        self.result.history.to_csv(os.path.join(out_dir, "history.csv"))
        self.fit.to_csv(os.path.join(out_dir, "fit.csv"))
        files += ["estimates.csv", "correlation.csv", "history.csv", "fit.csv"]
        with open(os.path.join(out_dir, "predictions.csv"), "w", newline="") as f:
            w = csv.writer(f)
            w.writerow(["set", "experiment", "observable", "t_s", "data", "model", "sigma"])
            for setname, preds in self.predictions.items():
                for p in preds:
                    for i in range(len(p["t"])):
                        w.writerow([setname, p["experiment"], p["observable"], p["t"][i], p["data"][i], p["model"][i],
                                    p["sigma"][i]])
        files.append("predictions.csv")
        files += [os.path.basename(x) for x in self.parity_plots(out_dir)]
        return files


def report(flowsheet: Flowsheet, result: CalibrationResult, calibration: Sequence[Experiment],
           validation: Sequence[Experiment] = (), *, comparison: CalibrationResult | None = None,
           truth: Mapping[str, float] | None = None, options: Mapping[str, Any] | None = None) -> CalibrationReport:
    """Predictions at the final estimates on both sets, and R²/RMSE per output (and pooled per group)."""
    preds = {"calibration": predict(flowsheet, calibration, result.parameters, options=options)}
    if validation:
        preds["validation"] = predict(flowsheet, validation, result.parameters, options=options)
    rows = []
    for setname, p in preds.items():
        for r in fit_statistics(p):
            rows.append({"set": setname, **r})
    return CalibrationReport(result, preds, rows, comparison, dict(truth) if truth else None)


# ------------------------------------------------------------------------------------------------
# multi-start
# ------------------------------------------------------------------------------------------------
def stage_bounds(stages: Sequence[Stage] | StagePlan, flowsheet: Flowsheet | None = None) -> dict[str, tuple]:
    """Per free parameter (lower, upper) in SI that every stage freeing it accepts (the declared bounds of
    `flowsheet` where a stage gives none; ±inf without a flowsheet)."""
    if isinstance(stages, StagePlan):
        stages = stages.stages
    out: dict[str, tuple] = {}
    for s in stages:
        for f in s.free:
            spec = flowsheet.spec(f.name) if flowsheet is not None else {"lower": -math.inf, "upper": math.inf}
            lo = spec["lower"] if f.lower is None else f.lower
            hi = spec["upper"] if f.upper is None else f.upper
            plo, phi = out.get(f.name, (-math.inf, math.inf))
            out[f.name] = (max(lo, plo), min(hi, phi))
    return out


def random_starts(stages: Sequence[Stage] | StagePlan, n: int, *, center: Mapping[str, float], spread: float = 1.0,
                  seed: int | None = 0, flowsheet: Flowsheet | None = None) -> list[dict[str, float]]:
    """`n` start points: each free parameter drawn uniformly within ±`spread` of `center` (in ln units for
    log-transformed and logarithmic parameters, relative otherwise), clipped to the bounds of every stage that
    frees it (and to the declared bounds of `flowsheet`, when given)."""
    if isinstance(stages, StagePlan):
        stages = stages.stages
    bounds = stage_bounds(stages, flowsheet)
    rng = np.random.default_rng(seed)
    starts = []
    for _ in range(n):
        p = {}
        for f in _all_free(stages):
            name = f.name
            c = float(center[name])
            u = rng.uniform(-spread, spread)
            if f.transform == "log":
                v = c * math.exp(u)
            elif f.logarithmic or (f.logarithmic is None and name.split(".")[-1].startswith("ln_")):
                v = c + u
            else:
                v = c * (1 + u)
            lo, hi = bounds[name]
            p[name] = min(max(v, lo), hi)
        starts.append(p)
    return starts


def multi_start(flowsheet: Flowsheet, experiments: Sequence[Experiment], stages: Sequence[Stage] | StagePlan,
                starts: Sequence[Mapping[str, float]], *, options: Mapping[str, Any] | None = None,
                workers: int | None = None, progress: bool | None = None) -> list[CalibrationResult | Exception]:
    """Calibrate from every start in parallel threads (each calibration single-threaded; the C++ side releases
    the GIL), with a tqdm progress bar on stderr (default: when stderr is a terminal). Returns the results in
    the order of `starts`; a start whose calibration failed gives its exception. Best: min by ``.cost``."""
    plan_opts: dict = {}
    plan_start: dict = {}
    if isinstance(stages, StagePlan):
        plan_opts, plan_start, stages = stages.options, stages.start, stages.stages
    workers = workers or min(len(starts), os.cpu_count() or 1)
    opts = {**plan_opts, **dict(options or {}), "num_threads": 1}
    bar = _progress_bar(progress, len(starts), "calibration starts", unit="start")
    results: list[CalibrationResult | Exception | None] = [None] * len(starts)

    def one(i: int):
        return calibrate(flowsheet, experiments, stages, start={**plan_start, **dict(starts[i])}, options=opts,
                         label=f"start {i}")

    with cf.ThreadPoolExecutor(max_workers=workers, thread_name_prefix="granuflow-calib") as pool:
        futs = {pool.submit(one, i): i for i in range(len(starts))}
        for fut in cf.as_completed(futs):
            i = futs[fut]
            try:
                results[i] = fut.result()
            except (CalibrationError, _core.SolverError, ConfigError) as e:
                results[i] = e
            if bar is not None:
                bar.update(1)
    if bar is not None:
        bar.close()
    return results  # type: ignore[return-value]


def best(results: Sequence[CalibrationResult | Exception]) -> CalibrationResult:
    ok = [r for r in results if isinstance(r, CalibrationResult)]
    if not ok:
        raise CalibrationError(f"every start failed; first: {results[0] if results else 'no starts'}")
    return min(ok, key=lambda r: r.cost)
