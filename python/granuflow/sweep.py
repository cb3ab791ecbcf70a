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

    # the generic runner, for points built in code (values SI floats or strings with a unit):
    df = sweep.run_sweep(gf.load(scene), [{"nozzle.mdot": "60 g/min"}, {"nozzle.mdot": "120 g/min"}],
                         outputs=["d50_um"], workers=2)

Executors are pluggable: ``executor="threads"`` (default: a thread pool, each worker thread with its own
``Flowsheet.clone()``; the C++ solve releases the GIL), ``"serial"``, or any object with a
``map_unordered(evaluate, flowsheet, items)`` method (see :class:`ThreadExecutor`). A ``distributed.Client`` is
accepted as it is and runs the sweep on its Dask cluster (:class:`granuflow.executors.DaskExecutor`, which rebuilds
the flowsheet on each worker from the scene text and the parameter values).
"""
from __future__ import annotations

import concurrent.futures as cf
import math
import os
import sys
import threading
import time
from dataclasses import dataclass, field
from typing import Any, Callable, Iterable, Iterator, Mapping, Sequence

from . import _core
from .flowsheet import Flowsheet, load
from .result import _STANDARD_KEYS

ConfigError = _core.ConfigError
SolverError = _core.SolverError

DEFAULT_OUTPUTS = ("d50_um", "bed_moisture", "bed_moisture_wet", "T_gas_out_K", "d10_um", "d90_um")
STATUS_OK = "ok"
STATUS_FAILED = "failed"
_TOP_KEYS = ("sweep", "description", "scene", "variables", "points", "outputs", "set", "t_end", "notes")
_VAR_KEYS = ("param", "unit", "levels", "description")
_POINT_LABELS = ("name", "kind")


# ------------------------------------------------------------------------------------------------
# executors
# ------------------------------------------------------------------------------------------------
class SerialExecutor:
    """Runs the points one after another on one clone of the flowsheet (reference and debugging)."""

    name = "serial"

    def map_unordered(self, evaluate: Callable[[Flowsheet, Any], dict], flowsheet: Flowsheet,
                      items: Sequence[Any]) -> Iterator[dict]:
        fs = flowsheet.clone()
        for item in items:
            yield evaluate(fs, item)


class ThreadExecutor:
    """A thread pool; every worker thread owns one ``Flowsheet.clone()`` (flowsheets are not thread-safe,
    clones are independent). The C++ solve releases the GIL, so the solves run in parallel.

    The executor protocol: ``map_unordered(evaluate, flowsheet, items)`` yields ``evaluate(fs, item)`` for every
    item, in any order, where ``fs`` is a flowsheet equal to ``flowsheet`` that no other running task uses.
    ``evaluate`` never raises for a failed point (it returns a row with status "failed") unless the caller asked
    for errors to propagate.
    """

    name = "threads"

    def __init__(self, workers: int | None = None):
        self.workers = workers

    def map_unordered(self, evaluate, flowsheet, items):
        workers = max(1, min(self.workers or os.cpu_count() or 1, len(items) or 1))
        local = threading.local()
        lock = threading.Lock()

        def task(item):
            fs = getattr(local, "fs", None)
            if fs is None:
                with lock:  # clone() reads the template; serialize it
                    fs = local.fs = flowsheet.clone()
            return evaluate(fs, item)

        with cf.ThreadPoolExecutor(max_workers=workers, thread_name_prefix="granuflow-sweep") as pool:
            futures = [pool.submit(task, item) for item in items]
            try:
                for fut in cf.as_completed(futures):
                    yield fut.result()
            except BaseException:
                for f in futures:
                    f.cancel()
                raise


EXECUTORS: dict[str, Callable[..., Any]] = {"threads": ThreadExecutor, "serial": lambda workers=None: SerialExecutor()}


def make_executor(executor: str | Any = "threads", workers: int | None = None):
    """An executor by name (``"threads"``, ``"serial"``, or one added to ``EXECUTORS``), a ``distributed.Client``
    (wrapped in :class:`granuflow.executors.DaskExecutor`) or the object itself."""
    if isinstance(executor, str):
        try:
            return EXECUTORS[executor](workers=workers)
        except KeyError:
            raise ConfigError(f"executor = '{executor}': unknown (allowed: {', '.join(sorted(EXECUTORS))})") from None
    # --- a dask.distributed Client runs the same sweep on its cluster (granuflow/executors.py) ---
    from .executors import DaskExecutor, is_dask_client

    if is_dask_client(executor):
        return DaskExecutor(executor)
    # ---
    if not hasattr(executor, "map_unordered"):
        raise ConfigError(f"executor = {executor!r}: expected a name ({', '.join(sorted(EXECUTORS))}) "
                          "or an object with map_unordered(evaluate, flowsheet, items)")
    return executor


def flowsheet_spec(flowsheet: Flowsheet) -> dict:
    """What a remote worker needs to rebuild ``flowsheet``: scene path, end time and every parameter value (SI).
    (Time-varying inputs set with ``set_input`` are not included.)"""
    return {"scene": flowsheet.path, "t_end": flowsheet.t_end,
            "params": {p: flowsheet.get(p) for p in flowsheet.params}}


# ------------------------------------------------------------------------------------------------
# the generic runner
# ------------------------------------------------------------------------------------------------
def _check_outputs(flowsheet: Flowsheet, outputs: Sequence[str], where: str = "outputs") -> list[str]:
    summary_keys = list(_STANDARD_KEYS) + [k for k in flowsheet._scene.summary_map if k not in _STANDARD_KEYS]
    names = set(flowsheet.state_names) | set(flowsheet.output_names)
    out = []
    for o in outputs:
        if not isinstance(o, str) or (o not in summary_keys and o not in names):
            raise ConfigError(f"{where}: '{o}' is neither a summary key of scene '{flowsheet.name}' "
                              f"(allowed: {', '.join(summary_keys)}) nor a state or output name (e.g. bed.T)")
        out.append(o)
    return out


def _final_values(res, outputs: Sequence[str]) -> dict[str, float]:
    """``outputs`` of a result at its final time: summary keys, else states and reported outputs; NaN where the
    summary has no value (null in summary.json)."""
    summary = res.summary
    out = {}
    for o in outputs:
        v = summary[o] if o in summary else float(res[o][-1])
        out[o] = math.nan if v is None else float(v)
    return out


def _progress_bar(progress: bool | None, total: int, desc: str, unit: str = "run"):
    if progress is None:
        progress = sys.stderr.isatty()
    if not progress:
        return None
    try:
        from tqdm import tqdm
    except ImportError:  # tqdm is optional (Debian python3-tqdm)
        return None
    return tqdm(total=total, desc=desc, unit=unit, file=sys.stderr, leave=False)


def _collect(exe, evaluate: Callable[[Flowsheet, Any], dict], flowsheet: Flowsheet, items: Sequence[Any],
             progress: bool | None, desc: str) -> list[dict]:
    """The rows of ``exe.map_unordered(evaluate, flowsheet, items)`` in the order of ``items``, with a progress bar
    counting the failed ones. Items are ``(i, ...)`` and every row carries ``"_i": i`` and ``"status"``."""
    bar = _progress_bar(progress, len(items), desc)
    rows = []
    n_failed = 0
    try:
        for row in exe.map_unordered(evaluate, flowsheet, items):
            rows.append(row)
            n_failed += row["status"] != STATUS_OK
            if bar is not None:
                bar.update(1)
                if n_failed:
                    bar.set_postfix(failed=n_failed)
    finally:
        if bar is not None:
            bar.refresh()  # tqdm throttles redraws: show the final count before the bar goes
            bar.close()
    rows.sort(key=lambda r: r["_i"])
    return rows


def run_sweep(flowsheet: Flowsheet, points: Sequence[Mapping[str, float | str]],
              outputs: Sequence[str] = DEFAULT_OUTPUTS, *, names: Sequence[str] | None = None,
              workers: int | None = None, progress: bool | None = None, executor: str | Any = "threads",
              t_end: float | None = None, raise_errors: bool = False, simulate: Mapping[str, Any] | None = None,
              desc: str = "sweep"):
    """Simulate ``flowsheet`` once per point and collect ``outputs``.

    ``points``: one mapping per run, ``{"unit.param": value}`` with SI floats or strings with a unit; parameters
    not named keep the flowsheet's value. ``outputs``: summary keys (``d50_um``, ...) or state/output names (final
    value). Returns a pandas DataFrame, one row per point in the order given: ``point`` (``names[i]`` or ``i``),
    one column per parameter (its SI value), the outputs, ``wall_time_s`` (this point, including setup),
    ``solve_time_s`` (the integrator alone), ``status`` ("ok" or "failed") and ``message``.

    A point whose solve fails (``SolverError``) or whose values are rejected (``ConfigError``) is recorded with
    status "failed" and the message; with ``raise_errors=True`` the first failure is raised instead.
    ``progress``: tqdm bar on stderr (default: only when stderr is a terminal). ``simulate``: keyword arguments
    of ``Flowsheet.simulate`` (``rtol``, ``atol``, ...).
    """
    import numpy as np
    import pandas as pd

    points = [dict(p) for p in points]
    if names is None:
        names = list(range(len(points)))
    if len(names) != len(points):
        raise ConfigError(f"names: {len(names)} names for {len(points)} points")
    outputs = _check_outputs(flowsheet, list(outputs))
    params = list(dict.fromkeys(k for p in points for k in p))
    known = set(flowsheet.params)
    for k in params:
        if k not in known:
            raise ConfigError(f"unknown parameter '{k}' (parameters: {', '.join(flowsheet.params)})")
    sim_kwargs = dict(simulate or {})
    if t_end is not None:
        sim_kwargs["t_end"] = float(t_end)
    base = {k: flowsheet.get(k) for k in params}

    def evaluate(fs: Flowsheet, item) -> dict:
        i, point = item
        t0 = time.perf_counter()
        row: dict[str, Any] = {"_i": i}
        try:
            fs.update(base)  # a worker's clone may carry the previous point's values
            fs.update(point)
            for k in params:
                row[k] = fs.get(k)
            res = fs.simulate(**sim_kwargs)
            row.update(_final_values(res, outputs))
            row["solve_time_s"] = res.wall_time_s
            row["status"], row["message"] = STATUS_OK, ""
        except (SolverError, ConfigError) as e:
            if raise_errors:
                raise
            row["status"], row["message"] = STATUS_FAILED, " ".join(str(e).split())
        row["wall_time_s"] = time.perf_counter() - t0
        return row

    rows = _collect(make_executor(executor, workers), evaluate, flowsheet, list(enumerate(points)), progress, desc)
    cols = ["point"] + params + outputs + ["wall_time_s", "solve_time_s", "status", "message"]
    data = []
    for r in rows:
        d = {c: r.get(c, np.nan) for c in cols}
        d["point"] = names[r["_i"]]
        if r["status"] != STATUS_OK:  # parameter values as requested, where they could be read
            for k in params:
                if isinstance(d[k], float) and math.isnan(d[k]):
                    d[k] = _si_or_nan(flowsheet, k, points[r["_i"]].get(k, base[k]))
        data.append(d)
    return pd.DataFrame(data, columns=cols)


def _si_or_nan(flowsheet: Flowsheet, param: str, value) -> float:
    if isinstance(value, (int, float)):
        return float(value)
    try:
        num, unit = _split_quantity(str(value))
        return _core.to_si(num, unit, flowsheet.spec(param)["unit"], param)
    except (ConfigError, ValueError):
        return math.nan


def _affine(unit: str, si_unit: str, where: str) -> tuple[float, float]:
    """(a, b) with SI value = a + b * value in ``unit``: edge units are affine in SI (degC)."""
    a = _core.to_si(0.0, unit, si_unit, where)
    return a, _core.to_si(1.0, unit, si_unit, where) - a


def _split_quantity(text: str) -> tuple[float, str]:
    parts = text.strip().split(None, 1)
    return float(parts[0]), (parts[1].strip() if len(parts) > 1 else "")


# ------------------------------------------------------------------------------------------------
# sweep files
# ------------------------------------------------------------------------------------------------
@dataclass
class Variable:
    name: str          # column name in the results
    param: str         # scene parameter, "unit.param"
    unit: str          # edge unit of the values ("" = SI)
    levels: list[float] = field(default_factory=list)  # optional, informative (low, centre, high)
    description: str = ""

    def to_si(self, value: float, si_unit: str) -> float:
        return _core.to_si(float(value), self.unit, si_unit, self.param)

    def quantity(self, value: float) -> str:
        return f"{value!r} {self.unit}".strip()


@dataclass
class Sweep:
    """A loaded sweep file. ``run()`` returns the results as a DataFrame."""

    path: str
    name: str
    description: str
    scene: str                       # absolute path of the scene file
    variables: list[Variable]
    points: list[dict]               # {"name", "kind", <variable>: value in the variable's unit}
    outputs: list[str]
    set: dict = field(default_factory=dict)
    t_end: float | None = None       # s

    # -- building blocks -------------------------------------------------------------------------
    def flowsheet(self, overrides: Mapping[str, float | str] | None = None) -> Flowsheet:
        """The scene with the sweep file's ``set`` and then ``overrides`` applied."""
        fs = load(self.scene)
        for k, v in self.set.items():
            _set_or_raise(fs, k, v, f"{self.path}: set.{k}")
        for k, v in (overrides or {}).items():
            if any(var.param == k for var in self.variables):
                raise ConfigError(f"--set {k}={v}: {k} is a variable of sweep '{self.name}' "
                                  f"(its values come from the points)")
            _set_or_raise(fs, k, v, f"--set {k}")
        if self.t_end is not None:
            fs.set_t_end(self.t_end)
        return fs

    def param_points(self) -> list[dict]:
        """The points as ``{"unit.param": "value unit"}`` for :func:`run_sweep`."""
        return [{v.param: v.quantity(p[v.name]) for v in self.variables} for p in self.points]

    @property
    def point_names(self) -> list[str]:
        return [p["name"] for p in self.points]

    # -- running ---------------------------------------------------------------------------------
    def run(self, *, workers: int | None = None, progress: bool | None = None, executor: str | Any = "threads",
            overrides: Mapping[str, float | str] | None = None, raise_errors: bool = False,
            flowsheet: Flowsheet | None = None, simulate: Mapping[str, Any] | None = None):
        """Run every point. Returns a DataFrame: ``point``, ``kind``, one column per variable (in its edge unit),
        the outputs, ``wall_time_s``, ``solve_time_s``, ``status``, ``message``. ``df.attrs`` holds the sweep name,
        the variables (parameter, unit, levels) and the outputs, which :func:`main_effects` uses."""
        fs = flowsheet if flowsheet is not None else self.flowsheet(overrides)
        raw = run_sweep(fs, self.param_points(), self.outputs, names=self.point_names, workers=workers,
                        progress=progress, executor=executor, raise_errors=raise_errors, simulate=simulate,
                        desc=self.name)
        df = raw[["point"]].copy()
        df["kind"] = [p.get("kind", "") for p in self.points]
        for v in self.variables:
            df[v.name] = [float(p[v.name]) for p in self.points]
        for c in self.outputs + ["wall_time_s", "solve_time_s", "status", "message"]:
            df[c] = raw[c].to_numpy()
        df.attrs.update(self.metadata())
        return df

    def metadata(self) -> dict:
        return {"sweep": self.name, "description": self.description, "scene": self.scene,
                "variables": {v.name: {"param": v.param, "unit": v.unit, "levels": list(v.levels)}
                              for v in self.variables},
                "outputs": list(self.outputs), "set": dict(self.set), "t_end_s": self.t_end}


def _set_or_raise(fs: Flowsheet, name: str, value, where: str, shown=None) -> None:
    try:
        fs.set(name, value)
    except (ConfigError, TypeError) as e:
        shown = value if shown is None else shown
        raise ConfigError(f"{where} = {shown!r}: {' '.join(str(e).split())}") from None


def _is_number(x) -> bool:
    return isinstance(x, (int, float)) and not isinstance(x, bool) and math.isfinite(x)


def load_sweep(path: str | os.PathLike) -> Sweep:
    """Read and check a sweep file. Raises ConfigError naming the file, the key, the value and what is allowed;
    every point is checked against the parameter bounds before anything runs."""
    import yaml

    path = os.fspath(path)
    try:
        with open(path) as f:
            text = f.read()
    except OSError as e:
        raise ConfigError(f"{path}: cannot read the sweep file ({e.strerror})") from None
    try:
        doc = yaml.safe_load(text)
    except yaml.YAMLError as e:
        raise ConfigError(f"{path}: not valid YAML ({' '.join(str(e).split())})") from None
    if not isinstance(doc, dict):
        raise ConfigError(f"{path}: expected a mapping with keys {', '.join(_TOP_KEYS)}")

    def err(key: str, msg: str) -> ConfigError:
        return ConfigError(f"{path}: {key}: {msg}")

    for k in doc:
        if k not in _TOP_KEYS:
            raise err(str(k), f"unknown key (allowed: {', '.join(_TOP_KEYS)})")
    for k in ("scene", "variables", "points"):
        if k not in doc:
            raise err(k, "missing required key")
    if not isinstance(doc["scene"], str):
        raise err("scene", f"expected a path (relative to the sweep file), got {doc['scene']!r}")
    scene = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(path)), doc["scene"]))
    if not os.path.isfile(scene):
        raise err("scene", f"'{doc['scene']}': no such file ({scene})")
    fs = load(scene)
    name = str(doc.get("sweep") or os.path.splitext(os.path.basename(path))[0])

    # variables
    vdoc = doc["variables"]
    if not isinstance(vdoc, dict) or not vdoc:
        raise err("variables", "expected a mapping name -> {param: unit.param, unit: U, levels: [...]}")
    variables = []
    for vname, spec in vdoc.items():
        key = f"variables.{vname}"
        if not isinstance(vname, str) or vname in _POINT_LABELS:
            raise err(key, f"invalid variable name (not {', '.join(_POINT_LABELS)})")
        if not isinstance(spec, dict):
            raise err(key, "expected a mapping {param: unit.param, unit: U, levels: [...]}")
        for k in spec:
            if k not in _VAR_KEYS:
                raise err(f"{key}.{k}", f"unknown key (allowed: {', '.join(_VAR_KEYS)})")
        if "param" not in spec:
            raise err(f"{key}.param", "missing required key")
        param = spec["param"]
        if param not in fs.params:
            raise err(f"{key}.param", f"unknown parameter '{param}' of scene '{fs.name}' "
                                      f"(allowed: {', '.join(fs.params)})")
        si_unit = fs.spec(param)["unit"]
        unit = spec.get("unit", "")
        if not isinstance(unit, str):
            raise err(f"{key}.unit", f"expected a unit string, got {unit!r}")
        try:
            _core.to_si(1.0, unit, si_unit, param)
        except ConfigError as e:
            raise err(f"{key}.unit", f"'{unit}' does not fit {param} (SI unit {si_unit}): "
                                     f"{' '.join(str(e).split())}") from None
        levels = spec.get("levels", [])
        if not isinstance(levels, list) or not all(_is_number(x) for x in levels):
            raise err(f"{key}.levels", f"expected a list of numbers in {unit or si_unit}, got {levels!r}")
        variables.append(Variable(vname, param, unit, [float(x) for x in levels], str(spec.get("description", ""))))
    if len({v.param for v in variables}) != len(variables):
        raise err("variables", "two variables set the same parameter")

    # outputs
    outputs = doc.get("outputs", list(DEFAULT_OUTPUTS))
    if not isinstance(outputs, list) or not outputs:
        raise err("outputs", f"expected a list of summary keys, got {outputs!r}")
    outputs = _check_outputs(fs, outputs, where=f"{path}: outputs")

    # fixed settings and end time
    fixed = doc.get("set") or {}
    if not isinstance(fixed, dict):
        raise err("set", f"expected a mapping unit.param -> value, got {fixed!r}")
    for k, v in fixed.items():
        if k not in fs.params:
            raise err(f"set.{k}", f"unknown parameter (allowed: {', '.join(fs.params)})")
        if any(var.param == k for var in variables):
            raise err(f"set.{k}", "is also a sweep variable")
        if not (_is_number(v) or isinstance(v, str)):
            raise err(f"set.{k}", f"expected a number or a string with a unit, got {v!r}")
        _set_or_raise(fs, k, v, f"{path}: set.{k}")
    t_end = None
    if "t_end" in doc:
        t_end = _parse_time(doc["t_end"], f"{path}: t_end")

    # points
    pdoc = doc["points"]
    if not isinstance(pdoc, list) or not pdoc:
        raise err("points", "expected a non-empty list of {name: ..., <variable>: value, ...}")
    points, seen = [], set()
    allowed = list(_POINT_LABELS) + [v.name for v in variables]
    for i, p in enumerate(pdoc):
        if not isinstance(p, dict):
            raise err(f"points[{i}]", f"expected a mapping with keys {', '.join(allowed)}, got {p!r}")
        pname = str(p.get("name", f"P{i + 1}"))
        key = f"points[{i}] ({pname})"
        if pname in seen:
            raise err(key, f"duplicate point name '{pname}'")
        seen.add(pname)
        for k in p:
            if k not in allowed:
                raise err(f"{key}.{k}", f"unknown key (allowed: {', '.join(allowed)})")
        point = {"name": pname, "kind": str(p.get("kind", ""))}
        for v in variables:
            if v.name not in p:
                raise err(f"{key}.{v.name}", f"missing (every point gives every variable: "
                                             f"{', '.join(x.name for x in variables)})")
            value = p[v.name]
            point[v.name] = _edge_value(fs, v, value, f"{path}: {key}.{v.name}")
            _set_or_raise(fs, v.param, value if isinstance(value, str) else v.quantity(point[v.name]),
                          f"{path}: {key}.{v.name}", shown=value)
        points.append(point)
    return Sweep(path=path, name=name, description=str(doc.get("description", "")), scene=scene,
                 variables=variables, points=points, outputs=outputs, set=dict(fixed), t_end=t_end)


def _quantity(value, where: str, expected: str) -> tuple[float, str] | None:
    """(number, unit) of a string such as "60 degC"; None for a plain number. ConfigError names `expected`."""
    if _is_number(value):
        return None
    if isinstance(value, str):
        try:
            return _split_quantity(value)
        except (ValueError, IndexError):
            pass
    raise ConfigError(f"{where} = {value!r}: expected {expected}")


def _edge_value(fs: Flowsheet, v: Variable, value, where: str) -> float:
    """A point value in the variable's edge unit (numbers are taken as given; strings may carry a unit)."""
    si_unit = fs.spec(v.param)["unit"]
    q = _quantity(value, where, f"a number in {v.unit or si_unit} or a number with a unit")
    if q is None:
        return float(value)
    try:
        si = _core.to_si(q[0], q[1], si_unit, v.param)
    except ConfigError as e:
        raise ConfigError(f"{where} = {value!r}: {' '.join(str(e).split())}") from None
    a, b = _affine(v.unit, si_unit, v.param)
    return (si - a) / b


def _parse_time(value, where: str) -> float:
    q = _quantity(value, where, "seconds or a number with a time unit (e.g. '60 min')")
    return float(value) if q is None else _core.to_si(q[0], q[1], "s", where)


def run_sweep_file(path: str | os.PathLike, **kwargs):
    """``load_sweep(path).run(**kwargs)``."""
    return load_sweep(path).run(**kwargs)


# ------------------------------------------------------------------------------------------------
# analysis
# ------------------------------------------------------------------------------------------------
def corner_points(df, variables: Iterable[str] | None = None):
    """Boolean mask of the rows at a cube corner: every variable at its lowest or highest value in ``df``."""
    import numpy as np

    variables = list(variables if variables is not None else df.attrs.get("variables", {}))
    mask = np.ones(len(df), dtype=bool)
    for v in variables:
        col = df[v].to_numpy(dtype=float)
        lo, hi = np.nanmin(col), np.nanmax(col)
        mask &= np.isclose(col, lo) | np.isclose(col, hi)
    return mask


def main_effects(df, variables: Iterable[str] | None = None, outputs: Iterable[str] | None = None):
    """Main effect of each variable on each output over the cube corners of a two-level (or 3-level) design:
    mean of the output where the variable is at its high level minus the mean where it is at its low level.

    Only successful points count; a level with no successful corner gives NaN. Returns a DataFrame indexed by
    variable with one column per output; ``attrs["levels"]`` holds (low, high) per variable and
    ``attrs["n_corners"]`` the corners used.
    """
    import numpy as np
    import pandas as pd

    variables = list(variables if variables is not None else df.attrs.get("variables", {}))
    outputs = list(outputs if outputs is not None else df.attrs.get("outputs", []))
    if not variables or not outputs:
        raise ValueError("main_effects: name the variables and outputs (or pass a DataFrame from Sweep.run)")
    corners = df[corner_points(df, variables)]
    ok = corners[corners["status"] == STATUS_OK] if "status" in corners else corners
    rows, levels = {}, {}
    for v in variables:
        col = df[v].to_numpy(dtype=float)
        lo, hi = float(np.nanmin(col)), float(np.nanmax(col))
        levels[v] = (lo, hi)
        at_hi = np.isclose(ok[v].to_numpy(dtype=float), hi)
        at_lo = np.isclose(ok[v].to_numpy(dtype=float), lo)
        rows[v] = {o: (ok.loc[at_hi, o].astype(float).mean() - ok.loc[at_lo, o].astype(float).mean())
                   if at_hi.any() and at_lo.any() else math.nan for o in outputs}
    eff = pd.DataFrame.from_dict(rows, orient="index", columns=outputs)
    eff.index.name = "variable"
    eff.attrs["levels"] = levels
    eff.attrs["n_corners"] = int(len(ok))
    return eff
