"""Simulation results: NumPy arrays for callers; pandas only when asked for (timeseries).

The core hands a run's arrays over as plain buffers (``_core.ResultArray``). NumPy wraps them without a copy on a
caller's first use of ``res.t``, ``res.y`` ...; the summary, warnings, balance check and timeseries.csv read them
through the core's reductions (``_core.end_fractions``, ``column_max``, ``columns_equal``, ``csv_table``, shared with
the sweep batch), so a plain ``granuflow run`` never imports NumPy (issue 32: its import took longer than the run)."""
from __future__ import annotations

import math
import os

from . import _core, outputs
from .quantity import affine, from_si, from_si_value, is_number, label
from .textfile import short

TYPE_CHECKING = False  # typing's own flag without importing typing (a plain run imports neither it nor NumPy)
if TYPE_CHECKING:
    import numpy as np

# The arrays of a run (see Result): NumPy's from their first use.
ARRAYS = ("t", "y", "yp", "outputs", "sens", "output_sens")

ConfigError = _core.ConfigError


class GridWarning(UserWarning):
    """A result whose size grid clips the distribution (:attr:`Result.warnings`)."""


class BalanceWarning(UserWarning):
    """A result whose water, solids or energy balance closes worse than its solver tolerance explains
    (:attr:`Result.warnings`; the limits: :func:`granuflow.outputs.balance_limits`)."""


class BalanceError(_core.SolverError):
    """A run or steady state whose balance does not close (closure above ``outputs.BALANCE_FAIL``): a unit loses or
    creates mass or energy. ``balance`` names the closure, ``value`` is it; ``result`` holds the run's
    :class:`Result` (or ``report``, a steady state's report) so that its files can still be written; ``t`` is the
    time of the check."""

    def __init__(self, message: str, balance: str, value: float, t: float, result=None, report=None):
        super().__init__(message)
        self.balance, self.value, self.t = balance, value, t
        self.unit, self.worst_residual = None, None
        self.result, self.report = result, report


class Layout:
    """What the results of one flowsheet share: state and output names, output roles, units and the name index.
    Built from a raw result that carries the names; a flowsheet keeps one and passes it to every later result."""

    def __init__(self, raw: dict, units: dict | None = None):
        self.state_names = tuple(raw["state_names"])
        self.output_names = tuple(raw["output_names"])
        self.output_roles = tuple(tuple(r) for r in raw["output_roles"])
        self.units = dict(units or {})
        self.index = {n: ("y", i) for i, n in enumerate(self.state_names)}
        self.index.update({n: ("o", i) for i, n in enumerate(self.output_names)})


class Result:
    """The outcome of one simulation.

    Attributes: ``t`` (s), ``y`` [time, state], ``state_names``, ``outputs`` [time, output],
    ``output_names``, ``sens`` [time, param, state], ``sens_params``, ``stats`` (solver statistics),
    ``wall_time_s``, ``units`` (SI unit of every state and output). Arrays are SI; files and tables made for
    people (:meth:`table`, :meth:`to_csv`, :attr:`summary`) show sizes in µm and say so.
    """

    def __init__(self, raw: dict, scene_name: str = "", summary_map: dict | None = None,
                 units: dict | None = None, layout: Layout | None = None):
        layout = layout or Layout(raw, units)
        self._raw = {k: raw.get(k) for k in ARRAYS}  # res.t, res.y ...: NumPy arrays from a caller's first use
        self.state_names = list(layout.state_names)
        self.output_names = list(layout.output_names)
        self.output_roles = list(layout.output_roles)  # (role, quantity, class, unit) per output
        self.sens_params = list(raw["sens_params"])
        self.stats = dict(raw["stats"])
        # State events that fired ({name, phase, t}), in time order; the checkpoint files the run wrote.
        self.events = [dict(e) for e in raw.get("events", [])]
        self.checkpoint_files = list(raw.get("checkpoint_files", []))
        self.wall_time_s = raw["wall_time_s"]
        self.rtol = raw.get("rtol")
        self.atol = raw.get("atol")
        self.error_estimate = None  # granuflow.accuracy.ErrorEstimate with simulate(error_estimate=True)
        self.material = None  # Flowsheet.material: the solid's catalogue entry and what it did not give
        self.accuracy = None        # granuflow.accuracy.target.Accuracy with simulate(accuracy=...)
        self.grid_check = None      # granuflow.accuracy.grid_check.GridCheck of a plain run
        self.extra_warnings: list[str] = []
        self.t_end = raw["t_end"] if "t_end" in raw else self._t_at(-1)
        self.scene_name = scene_name
        self.summary_map = dict(summary_map or {})
        self.units = dict(layout.units)
        self._index = layout.index  # shared between the results of one flowsheet, never changed

    def __getattr__(self, name: str):
        # Only for an array not yet asked for: the core's buffer becomes a NumPy array (no copy), kept from then on.
        raw = self.__dict__.get("_raw")
        if raw is None or name not in ARRAYS:
            raise AttributeError(f"'Result' object has no attribute '{name}'")
        v = raw[name]
        if v is not None:
            import numpy as np

            v = np.asarray(v)
        self.__dict__[name] = v
        return v

    def __getstate__(self) -> dict:
        """For pickle (a process pool's results, a cache on disk): the core's buffers as NumPy arrays of their own.
        ``flowsheet``, the live scene that made the result, does not travel: it is None after unpickling."""
        import numpy as np

        state = dict(self.__dict__)
        if "flowsheet" in state:
            state["flowsheet"] = None
        raw = state.pop("_raw", None) or {}
        for name, v in raw.items():
            if name not in state:
                state[name] = None if v is None else np.array(v)
        return state

    def __setstate__(self, state: dict) -> None:
        self.__dict__.update(state)

    def _buf(self, name: str):
        """The array ``name`` as a float64 buffer without importing NumPy: the core's own until a caller asks for (or
        sets) the attribute, then that; anything that is not a float64 buffer goes through NumPy."""
        v = self.__dict__.get(name)
        if v is None and self.__dict__.get("_raw") is not None:
            v = self._raw[name]
        try:
            if memoryview(v).format == "d":
                return v
        except TypeError:
            pass
        import numpy as np

        return np.ascontiguousarray(v, dtype=float)

    def _t_at(self, k: int) -> float:
        """The output time at index k (s)."""
        return float(memoryview(self._buf("t"))[k])

    def _t_list(self) -> list[float]:
        """The output times (s) as floats."""
        return memoryview(self._buf("t")).tolist()

    def _final(self, name: str) -> float:
        """The value of a state or output at the last output time."""
        kind, i = self._index[name]
        return float(memoryview(self._buf("y" if kind == "y" else "outputs"))[-1, i])

    def __getitem__(self, name: str) -> np.ndarray:
        """Time series of a state or reported output by its qualified name."""
        try:
            kind, i = self._index[name]
        except KeyError:
            raise KeyError(f"{name!r} is neither a state nor an output "
                           f"(e.g. {', '.join(list(self._index)[:8])}, ...)") from None
        return self.y[:, i] if kind == "y" else self.outputs[:, i]

    def __contains__(self, name: str) -> bool:
        return name in self._index

    def sensitivity(self, state: str, param: str) -> np.ndarray:
        """d state / d param over time (requires ``simulate(sensitivities=[param])``)."""
        if param not in self.sens_params:
            raise ValueError(f"sensitivity: '{param}' was not a sensitivity parameter of this run "
                             f"(simulated with sensitivities={self.sens_params}); pass it to simulate(sensitivities=)")
        if state not in self.state_names:
            raise ValueError(f"sensitivity: '{state}' is not a state (e.g. {', '.join(self.state_names[:8])}, ...)")
        return self.sens[:, self.sens_params.index(param), self.state_names.index(state)]

    def unit(self, name: str) -> str:
        """SI unit of a state or output ("" if unknown)."""
        return self.units.get(name, "")

    @property
    def timeseries(self):
        """All states and outputs as a DataFrame indexed by time in s, in SI; ``df.attrs["units"]`` maps every column
        (and the index ``t_s``) to its unit."""
        import numpy as np
        import pandas as pd

        data = np.hstack([self.y, self.outputs]) if self.outputs.size else self.y
        names = self.state_names + self.output_names
        df = pd.DataFrame(data, columns=names)
        df.index = pd.Index(self.t, name="t_s")
        df.attrs["units"] = {"t_s": "s", **{n: self.unit(n) for n in names}}
        return df

    def repeated_outputs(self) -> list[str]:
        """Outputs that repeat a state of the same unit over the whole run (a balance term that is the unit's own
        accumulator, a class mass reported again for the size distribution): files list such a quantity once."""
        y, o = self._buf("y"), self._buf("outputs")
        if not memoryview(y).nbytes or not memoryview(o).nbytes:
            return []
        # Linear in the size of the result: each output is looked up by its unit and last value among the states,
        # and compared in full only with the few states it meets there (as numpy.array_equal: -0.0 and 0.0 are one
        # value, a column with NaN never repeats).
        by_last: dict[tuple[str, float], list[int]] = {}
        for i, (n, v) in enumerate(zip(self.state_names, _core.row(y, -1))):
            by_last.setdefault((n.rpartition(".")[0], v), []).append(i)
        out = []
        for j, (n, v) in enumerate(zip(self.output_names, _core.row(o, -1))):
            for i in by_last.get((n.rpartition(".")[0], v), ()):
                if _core.columns_equal(y, i, o, j):
                    out.append(n)
                    break
        return out

    def _display_plan(self) -> tuple[list[str], list[tuple[int, int]], list[float], list[float]]:
        """(headers, columns, shifts, scales) of every state and output as files show them: sizes in µm, the rest
        SI; outputs that repeat a state are left out. A column is (0, state) or (1, output); its value as shown is
        (value - shift) / scale (quantity.from_si)."""
        skip = set(self.repeated_outputs())
        headers, a, b, cols = [], [], [], []
        factors: dict[tuple[str, str], tuple[float, float]] = {}
        units, display_unit = self.units, outputs.display_unit  # once per column of a 2-D scene's 6600: kept local
        for block, names in enumerate((self.state_names, self.output_names)):
            for j, n in enumerate(names):
                if n in skip:
                    continue
                si = units.get(n, "")
                shown = display_unit(n, si)
                headers.append(label(n, shown))
                f = factors.get((shown, si))
                if f is None:
                    f = factors[shown, si] = affine(shown, si) if shown and shown != si else (0.0, 1.0)
                a.append(f[0])
                b.append(f[1])
                cols.append((block, j))
        return headers, cols, a, b

    def _display_columns(self) -> tuple[list[str], np.ndarray]:
        """(headers, values [time, column]) of :meth:`_display_plan` as one NumPy block: one conversion of the whole
        block, not one per column."""
        import numpy as np

        headers, cols, a, b = self._display_plan()
        block = np.hstack([self.y, self.outputs]) if self.outputs.size else np.asarray(self.y, dtype=float)
        flat = [j if k == 0 else len(self.state_names) + j for k, j in cols]
        # from_si per column: (value - a) / b; a = 0, b = 1 leaves a value as it is (also -0.0 and NaN)
        return headers, (block[:, flat] - np.array(a)) / np.array(b)

    def _file_columns(self) -> tuple[list[str], np.ndarray]:
        """(headers, values) of :meth:`table` and :meth:`to_csv`: time in s and min, then :meth:`_display_columns`."""
        import numpy as np

        headers, values = self._display_columns()
        t = np.asarray(self.t, dtype=float)
        return ["t [s]", "t [min]"] + headers, np.column_stack([t, t / 60.0, values])

    def table(self):
        """The time series as people read them: headers with units (``bed.d50 [um]``), sizes in µm, time in s and
        min, each quantity once (:meth:`repeated_outputs` are left out); a DataFrame (what :meth:`to_csv` writes)."""
        import pandas as pd

        headers, data = self._file_columns()
        return pd.DataFrame({h: data[:, k] for k, h in enumerate(headers)})

    def to_csv(self, path: str) -> str:
        """Write :meth:`table` as CSV (neither pandas nor NumPy needed: the command line writes it on every run). Each
        value as ``%.10g``, as NumPy's savetxt writes it, converted and formatted by the core."""
        headers, cols, a, b = self._display_plan()
        text = _core.csv_table(self._buf("t"), [self._buf("y"), self._buf("outputs")], cols, a, b)
        with open(path, "w") as f:
            f.write(",".join('"' + h + '"' if "," in h else h for h in ["t [s]", "t [min]"] + headers) + "\n")
            f.write(text)
        return path

    # -- particle size distribution -------------------------------------------------------------
    def psd_units(self) -> list[str]:
        return outputs.psd_units(self.output_roles)

    def psd_arrays(self, t: float, unit: str | None = None) -> tuple[float, np.ndarray, np.ndarray, np.ndarray]:
        """(output time in s, pivot diameters in µm, class masses in kg, mass fractions) at the output time nearest
        to ``t``, as NumPy arrays (what :meth:`psd` tabulates)."""
        units = self.psd_units()
        if not units:
            raise ValueError("this result has no particle size distribution (no unit reports psd_d_i / psd_m_i)")
        unit = unit or units[0]
        if unit not in units:
            raise ValueError(f"psd: unit '{unit}' reports no size distribution (units with one: {', '.join(units)})")
        if not is_number(t):
            raise ConfigError(f"psd: t = {short(t)}: expected a time in s within the run, {self.t[0]:g} to "
                              f"{self.t[-1]:g} s")
        span = self.t[-1] - self.t[0]
        if not self.t[0] - 1e-9 * span <= t <= self.t[-1] + 1e-9 * span:
            raise ConfigError(f"psd: t = {t:g} s: outside the run, {self.t[0]:g} to {self.t[-1]:g} s")
        import numpy as np

        k = int(np.argmin(np.abs(self.t - t)))
        dcols, mcols = outputs.psd_columns(self.output_roles, unit)
        w = self.outputs[k, mcols]
        frac = w / w.sum() if w.sum() > 0 else w
        return float(self.t[k]), from_si(self.outputs[k, dcols], "um", "m"), w, frac

    def psd(self, t: float, unit: str | None = None):
        """Mass-based size distribution at the output time nearest to ``t``.

        Returns a DataFrame with pivot diameter (µm), class mass (kg), mass fraction and cumulative Q3.
        """
        import numpy as np
        import pandas as pd

        t_k, d, w, frac = self.psd_arrays(t, unit)
        df = pd.DataFrame({"d_um": d, "mass_kg": w, "mass_fraction": frac, "Q3": np.cumsum(frac)}).rename_axis("class")
        df.attrs["units"] = {"d_um": "um", "mass_kg": "kg", "mass_fraction": "-", "Q3": "-"}
        df.attrs["t_s"] = t_k
        return df

    # -- the ends of the size grid ----------------------------------------------------------------
    def grid_ends(self) -> dict[str, dict]:
        """The mass fraction at the ends of each size grid: per unit with a size distribution its bottom and top
        class (``"bed.bottom_class"``, ``"bed.top_class"``; the top class holds what grew beyond the grid), and
        every output a unit declares as a grid-end fraction (role ``grid_end``) of a unit without one. Each:
        ``{"initial", "final", "max"}`` over the output times, and ``"d_um"``, the pivot of that class."""
        if getattr(self, "_grid_ends", None) is not None:  # a result never changes; warnings and summary ask again
            return {k: dict(v) for k, v in self._grid_ends.items()}
        out: dict[str, dict] = {}
        units = self.psd_units()
        o = self._buf("outputs")
        mv = memoryview(o)
        for unit in units:
            dcols, mcols = outputs.psd_columns(self.output_roles, unit)
            fractions = _core.end_fractions(o, mcols, [0, -1])  # of the bottom and the top class at every time
            for (end, k), (first, last, peak) in zip((("bottom_class", 0), ("top_class", -1)), fractions):
                out[f"{unit}.{end}"] = {"initial": first, "final": last, "max": peak,
                                        "d_um": from_si_value(mv[0, dcols[k]], "um", "m")}
        for j, name in outputs.grid_end_columns(self.output_roles, self.output_names):
            if self.output_roles[j][3] not in units:
                out[name] = {"initial": float(mv[0, j]), "final": float(mv[-1, j]), "max": _core.column_max(o, j),
                             "d_um": None}
        self._grid_ends = {k: dict(v) for k, v in out.items()}
        return out

    @property
    def warnings(self) -> list[str]:
        """What a user must know before trusting the numbers (summary.json ``warnings``): an end class of a size
        grid holding more than ``outputs.GRID_END_WARNING`` of the mass, at the start (the initial distribution
        lies outside the grid) or at any later output time (the grid clips the product), with its cause when the
        grid check tells it; a characteristic diameter that lies in an end class; the grid check's estimated grid
        error above its threshold; an accuracy target not reached; a balance closure above its limit
        (:func:`granuflow.outputs.balance_findings`)."""
        ends = self.grid_ends()
        gc = self.grid_check
        causes = {k: gc.end_cause(k) for k in ends} if gc is not None else None
        out = outputs.grid_end_warnings(ends, causes=causes)
        out += [b["note"] for b in self.end_class_percentiles(ends).values()]
        if gc is not None:
            out += gc.warnings()
        return out + list(self.extra_warnings) + self.balance_findings()[0]

    def end_class_percentiles(self, ends: dict | None = None) -> dict[str, dict]:
        """Summary keys of characteristic diameters (d90 ...) whose percentile lies in an end class at the end of
        the run: ``{key: {"bound": "lower"|"upper", "value": pivot in the key's unit, "note": ...}}``. Such a value
        is the grid's end, not the product's (summary.json reports null and ``<key>_lower_bound``)."""
        ends = self.grid_ends() if ends is None else ends
        out = {}
        for key, src in self.summary_map.items():
            frac = outputs.size_fraction(src)
            unit = src.rpartition(".")[0]
            if frac is None:
                continue
            top, bottom = ends.get(f"{unit}.top_class"), ends.get(f"{unit}.bottom_class")
            name = src.rpartition(".")[2]
            for end, which, inside in (("top", "lower", top and top["final"] > 1.0 - frac + 1e-12),
                                       ("bottom", "upper", bottom and bottom["final"] > frac + 1e-12)):
                if inside:
                    e = top if end == "top" else bottom
                    d_um = float(f"{e['d_um']:.12g}")  # the pivot, without the roundoff of m -> um
                    value = d_um if outputs.summary_in_um(key) else d_um * 1e-6
                    word = "at least" if end == "top" else "at most"
                    out[key] = {"bound": which, "value": value,
                                "note": f"{unit}: {name} lies in the {end} size class ({100 * e['final']:.3g} % of "
                                        f"the mass there): {word} the grid's end, {d_um:.4g} um; summary {key} is "
                                        f"null, {key}_{which}_bound = {value:.4g}"}
                    break
        return out

    def summary_values(self) -> dict:
        """The summary keys' values at the end of the run as the core computes them (units as in summary.json)."""
        if getattr(self, "_summary_values", None) is not None:
            return dict(self._summary_values)
        out = {}
        for key, src in self.summary_map.items():
            si = self.unit(src)
            out[key] = _finite(from_si_value(self._final(src), outputs.summary_unit(key, si), si))
        self._summary_values = out  # a result never changes
        return dict(out)

    def balance_findings(self) -> tuple[list[str], list[str]]:
        """(warnings, failures) of the balance guard on :meth:`balance_closure` at this run's tolerance."""
        return outputs.balance_findings(self.balance_closure(), self.rtol)

    def check_balance(self) -> None:
        """Raise :class:`BalanceError` when a balance closure is far above its limit (a unit loses or creates mass
        or energy); :meth:`granuflow.Flowsheet.simulate` calls it on every result."""
        fails = self.balance_findings()[1]
        if fails:
            name, value = _worst(self.balance_closure())
            raise BalanceError(f"{self.scene_name}: {fails[0]}", name, value, self._t_at(-1), result=self)

    # -- summary --------------------------------------------------------------------------------
    def balance_closure(self) -> dict:
        """Relative closure error per conserved quantity at the final time:
        |hold(t) - hold(0) - (in - out)| / max(|hold(0)|, |hold(t)|, |in|, |out|); None if not tracked."""
        if getattr(self, "_balance", None) is not None:  # a result never changes
            return dict(self._balance)
        acc: dict = {}
        mv = memoryview(self._buf("outputs"))
        for j, q, kind in outputs.balance_terms(self.output_roles):
            acc.setdefault(q, {"in": 0.0, "out": 0.0, "hold0": 0.0, "hold": 0.0})
            if kind == "hold":
                acc[q]["hold0"] += mv[0, j]
                acc[q]["hold"] += mv[-1, j]
            else:
                acc[q][kind] += mv[-1, j] - mv[0, j]
        out = {}
        for q in outputs.BALANCE_QUANTITIES:
            if q not in acc:
                out[f"{q}_rel"] = None
                continue
            a = acc[q]
            scale = max(abs(a["hold0"]), abs(a["hold"]), abs(a["in"]), abs(a["out"]), 1e-300)
            out[f"{q}_rel"] = _finite(abs(a["hold"] - a["hold0"] - (a["in"] - a["out"])) / scale)
        for q in sorted(k for k in acc if k.startswith("solids:")):  # each named solid of a composed particle system
            a = acc[q]
            scale = max(abs(a["hold0"]), abs(a["hold"]), abs(a["in"]), abs(a["out"]), 1e-300)
            out[f"{q}_rel"] = _finite(abs(a["hold"] - a["hold0"] - (a["in"] - a["out"])) / scale)
        self._balance = dict(out)
        return out

    @property
    def phases(self) -> list[dict]:
        """The recipe's phases: the first (``start``) from the start, then one from each event (its ``phase``) to the
        next event or the end of the run."""
        starts = [("start", self._t_at(0))] + [(e["phase"], float(e["t"])) for e in self.events]
        ends = [t for _, t in starts[1:]] + [self._t_at(-1)]
        # an event that stops the run begins no phase
        return [{"name": n, "t_start_s": a, "t_end_s": b} for k, ((n, a), b) in enumerate(zip(starts, ends))
                if b > a or k == 0]

    @property
    def summary(self) -> dict:
        """The fields of summary.json (docs/design.md contract); null where the scene has no such quantity."""
        s = {"scene": self.scene_name, "t_end_s": self._t_at(-1)}
        for key in outputs.STANDARD_SUMMARY_KEYS:
            s[key] = None
        units, reasons = {}, {}
        for key, v in self.summary_values().items():
            s[key] = v
            units[key] = outputs.summary_unit(key, self.unit(self.summary_map[key]))
            if v is None:
                reasons[key] = outputs.null_reason(self.summary_map[key], self.unit(self.summary_map[key]))
        ends = self.grid_ends()
        for key, b in self.end_class_percentiles(ends).items():  # the grid's end, not a result
            s[key] = None
            s[f"{key}_{b['bound']}_bound"] = b["value"]
            units[f"{key}_{b['bound']}_bound"] = units[key]
            reasons[key] = b["note"]
        s["null_reasons"] = reasons  # why a value the scene declares is null (an empty stream has no size)
        s["balance"] = self.balance_closure()
        if self.material is not None:
            s["material"] = self.material
        # Where a model left the paper's literal equations (floors, caps, regularizations): the largest count of
        # classes or instances affected at any output time, per unit (docs/paper001_decisions.md asks for this).
        o = self._buf("outputs")
        s["regularizations"] = {n: _finite(_core.column_max(o, j))
                                for j, n in outputs.regularization_columns(self.output_roles, self.output_names)}
        if self.error_estimate is not None:
            s["error_estimate"] = self.error_estimate.to_json()
        if self.accuracy is not None:
            s["accuracy"] = self.accuracy.to_json()
        if self.grid_check is not None:
            s["grid_check"] = self.grid_check.to_json()
        s["grid_end"] = {k: {x: _finite(v) for x, v in e.items()} for k, e in ends.items()}
        if self.events:  # a recipe: when each event fired and the phases between them
            s["events"] = [{"name": e["name"], "phase": e["phase"], "t_s": e["t"]} for e in self.events]
            s["phases"] = self.phases
        if self.checkpoint_files:
            s["checkpoint_files"] = [os.path.basename(f) for f in self.checkpoint_files]
        s["warnings"] = self.warnings
        s["wall_time_s"] = self.wall_time_s
        st = self.stats
        s["solver"] = {"states": st["states"], "steps": st["steps"], "residuals": st["residuals"],
                       "jacobians": st["jacobians"], "linear_solver": st["linear_solver"],
                       "reinits": st["reinits"], "rtol": self.rtol}
        for k in ("method", "method_reason"):  # which integrator ran, and why (solver.method: auto)
            if st.get(k):
                s["solver"][k] = st[k]
        s["units"] = {"t_end_s": "s", **outputs.STANDARD_SUMMARY_UNITS, **units,
                      "balance": "-", "regularizations": "classes or instances", "null_reasons": "",
                      "grid_end": "mass fraction (d_um: um)", "wall_time_s": "s"}
        return s

    def __repr__(self) -> str:
        return (f"<granuflow.Result {self.scene_name!r}: {len(self._t_list())} times to {self._t_at(-1):g} s, "
                f"{len(self.state_names)} states, {self.stats['steps']} steps, {self.wall_time_s * 1e3:.1f} ms>")


def _worst(balance) -> tuple[str, float]:
    """The largest closure of a balance map: (name, value)."""
    return max(outputs.balance_closures(balance).items(), key=lambda kv: kv[1])


def _finite(v):
    return float(v) if v is not None and math.isfinite(v) else None
