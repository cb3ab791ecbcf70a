"""Experiment and stage files (YAML, CSV): schema, checks, reading and writing."""
from __future__ import annotations

import csv
import io
import math
import os
from dataclasses import dataclass, field
from typing import Any, Mapping, Sequence

import numpy as np

from .. import _calibration, _core
from ..flowsheet import Flowsheet, load
from ..outputs import observable_display, observable_groups
from ..quantity import difference_to_si, from_si, number, show, to_si
from ..textfile import MAX_DATA_BYTES, load_yaml, read_text, short
from .paper001 import TABLE1_LEVELS

ConfigError = _core.ConfigError
CalibrationError = _core.CalibrationError

_EXP_KEYS = ("experiments", "description", "scene", "sigma", "runs")
_RUN_KEYS = ("name", "kind", "use", "set", "t_end", "data", "sigma")
_STAGEFILE_KEYS = ("name", "description", "start", "options", "stages")
_STAGE_KEYS = ("name", "free", "observables")
_FREE_KEYS = ("transform", "lower", "upper", "logarithmic")


# ------------------------------------------------------------------------------------------------
# quantities
# ------------------------------------------------------------------------------------------------
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


def param_to_si(fs: Flowsheet, name: str, value: Any, where: str) -> float:
    """A parameter value (units allowed) in SI, within the declared bounds; ConfigError naming `where`."""
    spec = _param_spec(fs, name, where)
    v = to_si(value, spec["unit"], where)
    if not (math.isfinite(v) and spec["lower"] <= v <= spec["upper"]):
        raise ConfigError(f"{where} = {show(value)}: {v:g} {spec['unit']} is outside the declared bounds "
                          f"{spec['lower']:g} <= {name} <= {spec['upper']:g} {spec['unit']}".rstrip())
    return v


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


def sigma_entry(spec: Any, si_unit: str, where: str) -> tuple[float, float]:
    if not isinstance(spec, Mapping) or set(spec) - {"abs", "rel"} or len(spec) != 1:
        raise ConfigError(f"{where}: expected {{abs: value [unit]}} or {{rel: fraction}}, got {short(spec)}")
    if "abs" in spec:
        v = difference_to_si(spec["abs"], si_unit, where)
        if not (v > 0 and math.isfinite(v)):
            raise ConfigError(f"{where}.abs = {short(spec['abs'])}: violates 0 < abs < inf")
        return v, 0.0
    v = number(spec["rel"], f"{where}.rel")
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
    text = read_text(path, "CSV data file", MAX_DATA_BYTES)
    try:
        rows = list(enumerate(csv.reader(io.StringIO(text, newline="")), start=1))
    except csv.Error as e:  # e.g. a field longer than the csv module's limit
        raise ConfigError(f"{path}: not a CSV table ({short(str(e), 100)})") from None
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
        raise ConfigError(f"{where}: expected a mapping with keys {', '.join(allowed)}, got {short(doc)}")
    for k in doc:
        if k not in allowed:
            raise ConfigError(f"{where}: unknown key '{k}' (allowed: {', '.join(allowed)})")
    return doc


def _read_mapping(path: str, allowed: Sequence[str], kind: str) -> dict:
    """A YAML file (a `kind`, e.g. "stage file") whose top level is a mapping with only the `allowed` keys."""
    return _check_mapping(load_yaml(path, kind) or {}, allowed, path)


def load_experiments(path: str | os.PathLike, flowsheet: Flowsheet | None = None) -> ExperimentSet:
    """Read an experiment file (see the module docstring). Raises ConfigError naming the file and key."""
    path = os.fspath(path)
    base = os.path.dirname(os.path.abspath(path))
    doc = _read_mapping(path, _EXP_KEYS, "experiment file")
    scene = doc.get("scene", "")
    if not isinstance(scene, str):
        raise ConfigError(f"{path}: scene = {short(scene)}: expected the path of a scene file (relative to this file)")
    if scene and not os.path.isabs(scene):
        scene = os.path.normpath(os.path.join(base, scene))
    if scene and flowsheet is None and not os.path.isfile(scene):
        what = "a directory" if os.path.isdir(scene) else "no such file"
        raise ConfigError(f"{path}: scene = '{doc['scene']}': {what} ({scene}); expected a scene file")
    fs = flowsheet or (load(scene) if scene else None)
    if fs is None:
        raise ConfigError(f"{path}: give `scene:` or pass a flowsheet")
    defaults = doc.get("sigma") or {}
    if not isinstance(defaults, dict):
        raise ConfigError(f"{path}: sigma: expected a mapping observable -> {{abs: value [unit]}} or "
                          f"{{rel: fraction}}, got {short(defaults)}")
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
                raise ConfigError(f"{where}.{k}: expected a mapping, got {short(run[k])}")
        settings = {}
        for k, v in (run.get("set") or {}).items():
            settings[k] = param_to_si(fs, k, v, f"{where}.set.{k}")
        t_end = run.get("t_end")
        if t_end is not None:
            t_end_si = to_si(t_end, "s", f"{where}.t_end")
            if not (t_end_si > 0 and math.isfinite(t_end_si)):
                raise ConfigError(f"{where}.t_end = {show(t_end)}: violates 0 < t_end < inf (leave it out for the last "
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
                raise ConfigError(f"{where}.data.units: expected a mapping column -> unit name, got {short(units)}")
            units = dict(units)
            cols = {}
            for k, v in data.items():
                if k == "units":
                    continue
                if not isinstance(k, str):
                    raise ConfigError(f"{where}.data: column name {short(k)}: expected a state or output name "
                                      "(e.g. bed.d50) or t")
                if not isinstance(v, list) or not all(x is None or (isinstance(x, (int, float)) and
                                                                    not isinstance(x, bool)) for x in v):
                    raise ConfigError(f"{where}.data.{k}: expected a list of numbers (null: not measured), "
                                      f"got {short(v)}")
                cols[k] = [None if x is None else float(x) for x in v]

            def at(name: str, i: int) -> str:
                return f"{where}.data.{name}[{i}]"
            empty = "null"
        else:
            raise ConfigError(f"{where}.data: expected a CSV file name or a mapping of columns, got {short(data)}")
        if "t" not in cols:
            raise ConfigError(f"{where}.data: no time column 't' (e.g. 't [min]')")
        t_raw = cols.pop("t")
        t_unit = units.get("t", "")
        for k in units:
            if k != "t" and k not in cols:
                raise ConfigError(
                    f"{where}.data.units: '{k}' is not a data column (columns: {', '.join(['t', *cols])})")
        t = []
        for i, x in enumerate(t_raw):
            ts = math.nan if x is None else to_si(x, "s", f"{at('t', i)}", t_unit)
            if not (ts >= 0 and math.isfinite(ts)) or (t and not ts > t[-1]):
                raise ConfigError(f"{at('t', i)} = {show(x)} {t_unit}: times must be finite, >= 0 and "
                                  "increasing".rstrip())
            if t_end is not None and ts > t_end * (1 + 1e-12):
                raise ConfigError(f"{at('t', i)} = {show(x)} {t_unit}: after the run's end, "
                                  f"t_end = {show(run['t_end'])} (data must lie within 0 <= t <= t_end)")
            t.append(ts)
        t = np.array(t, dtype=float)

        def t_text(i: int) -> str:
            return f"t = {show(t_raw[i])} {t_unit}".rstrip()
        sig = {**defaults, **(run.get("sigma") or {})}
        obs = []
        for oname, values in cols.items():
            si_unit = _in_context(f"{where}.data.{oname}", fs.unit_of, oname)
            if len(values) != len(t):
                raise ConfigError(f"{where}.data.{oname}: {len(values)} values for {len(t)} times")
            v = []
            for i, x in enumerate(values):
                if x is None:
                    v.append(math.nan)
                    continue
                if not math.isfinite(x):
                    raise ConfigError(f"{at(oname, i)} = {show(x)} at {t_text(i)}: not a finite number ({empty}: not "
                                      "measured)")
                xs = to_si(x, si_unit, f"{where}.data.{oname}", units.get(oname, ""))
                if not math.isfinite(xs):
                    raise ConfigError(f"{at(oname, i)} = {x} at {t_text(i)}: {xs} {si_unit} is not finite")
                v.append(xs)
            v = np.array(v, dtype=float)
            # a measured distribution's points unit.Q3(size) share one sigma, given as unit.Q3
            skey = oname if oname in sig else oname.partition("(")[0] if oname.endswith(")") else oname
            if skey not in sig:
                raise ConfigError(f"{where}: no sigma for observable {oname} (give it under `sigma:`)")
            sa, sr = sigma_entry(sig[skey], si_unit, f"{where}: sigma.{skey}")
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
    fs = load(es.scene) if es.scene else None
    groups = observable_groups(fs.summary_map, fs.state_names + fs.output_names) if fs is not None else {}
    for e in es.experiments:
        times = sorted({float(x) for o in e.observations for x in o.t})
        cols = {"t": from_si(np.array(times), time_unit, "s")}
        units = {"t": time_unit}
        for o in e.observations:
            si_unit = fs.unit_of(o.name) if fs is not None else ""
            unit = (observable_display(o.name, groups) or "") if si_unit else ""
            col = np.full(len(times), math.nan)
            idx = [times.index(float(x)) for x in o.t]
            col[idx] = from_si(o.value, unit, si_unit) if unit else o.value
            cols[o.name] = col
            units[o.name] = unit
            sigma[o.name] = ({"abs": f"{o.sigma_abs:g} {si_unit}".strip()} if o.sigma_abs > 0
                             else {"rel": float(o.sigma_rel)})
        run: dict[str, Any] = {"name": e.name}
        if e.kind:
            run["kind"] = e.kind
        run["use"] = e.use
        run["set"] = {k: (f"{float(from_si(v, TABLE1_LEVELS[k][0], fs.spec(k)['unit'])):.6g} {TABLE1_LEVELS[k][0]}"
                          if k in TABLE1_LEVELS and fs is not None else float(v)) for k, v in e.settings.items()}
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
                           **{k: [None if not np.isfinite(x) else float(f"{x:.6g}") for x in v]
                              for k, v in cols.items()}}
        runs.append(run)
    doc = {"experiments": es.name, "description": es.description, "scene": scene, "sigma": sigma, "runs": runs}
    with open(path, "w") as f:
        f.write("# granuflow experiment file (format: granuflow.calibration). Values without a unit are SI; data "
                "columns carry their units.\n")
        yaml.safe_dump(doc, f, sort_keys=False, width=120)


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
        return [Stage("simultaneous", all_free(self.stages), [])]


def all_free(stages: Sequence[Stage]) -> list[FreeParameter]:
    """The free parameters of all stages, each once (as first declared)."""
    free: dict[str, FreeParameter] = {}
    for s in stages:
        for f in s.free:
            free.setdefault(f.name, f)
    return list(free.values())


def load_stages(path: str | os.PathLike, flowsheet: Flowsheet) -> StagePlan:
    """Read a stage file (see the module docstring)."""
    path = os.fspath(path)
    doc = _read_mapping(path, _STAGEFILE_KEYS, "stage file")
    start_doc = doc.get("start") or {}
    if not isinstance(start_doc, dict):
        raise ConfigError(f"{path}: start: expected a mapping parameter -> value [unit], got {short(start_doc)}")
    start = {k: param_to_si(flowsheet, k, v, f"{path}: start.{k}") for k, v in start_doc.items()}
    options = doc.get("options") or {}
    if not isinstance(options, dict):
        raise ConfigError(f"{path}: options: expected a mapping of CalibrationOptions fields, got {short(options)}")
    options = dict(options)
    _in_context(f"{path}: options", _calibration.check_calibration_options, options)
    stages: list[Stage] = []
    seen: dict[str, FreeParameter] = {}
    if not isinstance(doc.get("stages") or [], list):
        raise ConfigError(f"{path}: stages: expected a list of stages, got {short(doc['stages'])}")
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
            raise ConfigError(f"{where}.free = {short(free_spec)}: expected a mapping of parameters or 'inherit'")
        obs = st.get("observables", "all")
        if obs not in ("all", None) and not isinstance(obs, list):
            raise ConfigError(f"{where}.observables: expected a list of observables or 'all', got {short(obs)}")
        obs = [] if obs in ("all", None) else [str(o) for o in obs]
        for j, o in enumerate(obs):
            _in_context(f"{where}.observables[{j}]", flowsheet.unit_of, o)
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
                    raise ConfigError(f"{path}: start.{k} = {show(start_doc[k])}: {v:g} {spec['unit']} is outside the "
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
        raise ConfigError(f"{where}.transform = {short(transform)}: not one of none, log")
    bounds = {}
    for key in ("lower", "upper"):
        if spec.get(key) is None:
            bounds[key] = None
            continue
        v = to_si(spec[key], u, f"{where}.{key}")
        if math.isnan(v):
            raise ConfigError(f"{where}.{key} = {show(spec[key])}: not a number")
        bounds[key] = v
    lo = decl["lower"] if bounds["lower"] is None else bounds["lower"]
    hi = decl["upper"] if bounds["upper"] is None else bounds["upper"]
    if bounds["lower"] is not None and not lo >= decl["lower"]:
        raise ConfigError(
            f"{where}.lower = {show(spec['lower'])}: below the declared lower bound {decl['lower']:g} {u}")
    if bounds["upper"] is not None and not hi <= decl["upper"]:
        raise ConfigError(
            f"{where}.upper = {show(spec['upper'])}: above the declared upper bound {decl['upper']:g} {u}")
    if not hi > lo:
        key = "upper" if bounds["upper"] is not None else "lower"
        raise ConfigError(f"{where}.{key} = {show(spec.get(key, hi))}: violates upper > lower "
                          f"(lower {lo:g} {u}, upper {hi:g} {u})")
    if transform == "log" and not lo > 0:
        raise ConfigError(f"{where}.lower = {show(spec.get('lower', lo))}: transform log needs lower > 0 "
                          f"(lower {lo:g} {u})")
    logarithmic = spec.get("logarithmic")
    if logarithmic is not None and not isinstance(logarithmic, bool):
        raise ConfigError(f"{where}.logarithmic = {short(logarithmic)}: expected true or false")
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
