"""Fit statistics and the calibration report (files and parity plots)."""
from __future__ import annotations

import csv
import json
import math
import os
from dataclasses import dataclass, field
from typing import Any, Mapping, Sequence

import numpy as np

from .. import _calibration, accuracy
from ..flowsheet import Flowsheet
from ..outputs import group_of, observable_groups
from .files import Experiment
from .fit import ESTIMATE_COLUMNS, CalibrationResult, predict


def fit_statistics(predictions: Sequence[dict], groups: bool = True, *,
                   observable_groups: Mapping[str, Sequence[str]] | None = None) -> list[dict]:
    """R² = 1 - SS_res/SS_tot and RMSE (SI) per observable, and per group of ``observable_groups``
    (``outputs.observable_groups`` of the scene; size = all d-values pooled)."""
    by = observable_groups or {}
    pooled: dict[str, list[tuple[np.ndarray, np.ndarray]]] = {}
    for p in predictions:
        keys = [p["observable"]] + ([group_of(p["observable"], by)] if groups else [])
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


def _worst_model_error(predictions: Sequence[dict], output: str, groups: Mapping[str, Sequence[str]]) -> float:
    """The largest |model error| / sigma over the samples of ``output`` (an observable or a group)."""
    worst = math.nan
    for p in predictions:
        if output in (p["observable"], group_of(p["observable"], groups)) and "model_error" in p:
            e = np.abs(np.asarray(p["model_error"], dtype=float)) / np.asarray(p["sigma"], dtype=float)
            if e.size and np.isfinite(e).any():
                worst = float(np.nanmax(e)) if math.isnan(worst) else max(worst, float(np.nanmax(e)))
    return worst


@dataclass
class CalibrationReport:
    """Estimates, correlation, history, flags and fit statistics (R², RMSE) on calibration and validation sets."""
    result: CalibrationResult
    predictions: dict[str, list[dict]]            # set name -> predictions
    fit_rows: list[dict]
    comparison: CalibrationResult | None = None   # e.g. the simultaneous fit from the same start
    truth: dict[str, float] | None = None
    units: dict[str, str] = field(default_factory=dict)  # SI unit of every observable
    param_units: dict[str, str] = field(default_factory=dict)  # SI unit of every free parameter
    groups: dict[str, tuple] = field(default_factory=dict)  # observable groups of the scene (outputs.observable_groups)

    @property
    def fit(self):
        import pandas as pd

        return pd.DataFrame(self.fit_rows).set_index(["set", "output"])

    def fit_text(self) -> str:
        """The fit table as text (what ``granuflow calibrate`` prints): one row per set and output, numbers to four
        significant digits, the set named on its first row. Without pandas, whose import alone took 0.3-0.45 s, a
        fifth of the shipped calibration's wall time."""
        return fit_table_text(self.fit_rows)

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
        from ..plots.calibration import parity_plots

        return parity_plots(self.predictions, self.fit_rows, out_dir, units=self.units, groups=self.groups)

    def to_json(self) -> dict:
        out = {"result": self.result.to_json(), "warnings": list(self.result.warnings), "fit": self.fit_rows,
               "comparison": None if self.comparison is None else self.comparison.to_json()}
        if self.truth:
            out["truth"] = dict(self.truth)
        return json.loads(json.dumps(out, default=float).replace("NaN", "null").replace("Infinity", "null"))

    def write(self, out_dir: str, *, plots: bool = True) -> list[str]:
        """report.json, report.txt, estimates.csv, correlation.csv, history.csv, fit.csv, predictions.csv and, with
        ``plots``, the parity PNGs (drawing them costs about as much CPU as a sixth of the calibration)."""
        os.makedirs(out_dir, exist_ok=True)
        files = []

        def put(name, text):
            with open(os.path.join(out_dir, name), "w") as f:
                f.write(text)
            files.append(name)

        put("report.json", json.dumps(self.to_json(), indent=2))
        txt = self.result.full_report()
        extra = [w for w in self.result.warnings if w not in self.result.raw.get("warnings", [])]
        if extra:  # what multi_start() added
            txt += "".join(f"warning: {w}\n" for w in extra)
        if self.comparison is not None:
            txt += "\n\nComparison (" + (self.comparison.label or "other route") + "):\n" + \
                                    self.comparison.full_report()
        put("report.txt", txt)
        final = self.result.final
        names = [e["name"] for e in final["estimates"]]
        tables = {  # value, se and bounds of an estimate in its unit
            "estimates.csv": (("name",), [{"name": e["name"], "unit": self.param_units.get(e["name"], ""),
                                           **{c: e[c] for c in ESTIMATE_COLUMNS}} for e in final["estimates"]]),
            "correlation.csv": (("",), [{"": a, **dict(zip(names, row))}
                                        for a, row in zip(names, np.asarray(final["correlation"]).tolist())]),
            "history.csv": (("stage",), self.result.history_rows()),
            "fit.csv": (("set", "output"), self.fit_rows)}
        for name, (index, rows) in tables.items():
            write_table(os.path.join(out_dir, name), index, rows)
        files += list(tables)
        with open(os.path.join(out_dir, "predictions.csv"), "w", newline="") as f:
            w = csv.writer(f)
            errors = any("model_error" in p for ps in self.predictions.values() for p in ps)
            w.writerow(["set", "experiment", "observable", "t_s", "data", "model", "sigma"]
                       + (["model_error"] if errors else []))
            for setname, preds in self.predictions.items():
                for p in preds:
                    for i in range(len(p["t"])):
                        w.writerow([setname, p["experiment"], p["observable"], p["t"][i], p["data"][i], p["model"][i],
                                    p["sigma"][i]] + ([p["model_error"][i]] if errors else []))
        files.append("predictions.csv")
        if plots:
            files += [os.path.basename(x) for x in self.parity_plots(out_dir)]
        return files


def fit_table_text(rows: Sequence[Mapping[str, Any]], index: Sequence[str] = ("set", "output")) -> str:
    """``rows`` as an aligned text table: the ``index`` columns left-aligned (a value repeated from the row above
    left blank, as for a grouped index), the others right-aligned in order of first appearance; floats to four
    significant digits, a missing value or NaN as NaN."""
    cols = list(dict.fromkeys(k for r in rows for k in r if k not in index))

    def text(v):
        if v is None or (isinstance(v, float) and math.isnan(v)):
            return "NaN"
        return f"{v:.4g}" if isinstance(v, float) else str(v)

    body, last = [], [None] * len(index)
    for r in rows:
        keys = [str(r.get(k, "")) for k in index]
        shown = ["" if all(keys[j] == last[j] for j in range(i + 1)) else keys[i] for i in range(len(index))]
        last = keys
        body.append(shown + [text(r.get(c)) for c in cols])
    header = list(index) + cols
    widths = [max(len(h), *(len(b[i]) for b in body)) if body else len(h) for i, h in enumerate(header)]
    ni = len(index)

    def line(cells):
        left = [c.ljust(w) for c, w in zip(cells[:ni], widths[:ni])]
        right = [c.rjust(w) for c, w in zip(cells[ni:], widths[ni:])]
        return "  ".join(left + right).rstrip()

    return "\n".join([line(header)] + [line(b) for b in body])


def _cell(v):
    return "" if v is None or (isinstance(v, float) and math.isnan(v)) else v


def write_table(path: str, index: Sequence[str], rows: Sequence[Mapping[str, Any]]) -> None:
    """``rows`` as CSV, the ``index`` columns first and the others in order of first appearance (a missing or NaN
    cell empty, a float in its shortest exact text): the file pandas' ``DataFrame(rows).set_index(index).to_csv``
    writes, without importing pandas (a third of a second of a calibration's serial part)."""
    cols = list(dict.fromkeys(k for r in rows for k in r if k not in index))
    with open(path, "w", newline="") as f:
        w = csv.writer(f, lineterminator="\n")
        w.writerow([*index, *cols])
        for r in rows:
            w.writerow([_cell(r.get(k)) for k in (*index, *cols)])


def model_errors(flowsheet: Flowsheet, experiments: Sequence[Experiment], params: Mapping[str, float],
                 predictions: Sequence[dict], options: Mapping[str, Any] | None = None) -> None:
    """The estimated numerical error of each predicted sample (granuflow.accuracy): the predictions again at a 100
    times tighter tolerance and on size grids refined twice and four times; adds ``"model_error"`` (SI, signed:
    model minus the converged model) to every prediction in ``predictions`` (those of ``experiments``)."""
    rtol, atol = _calibration.calibration_tolerances(dict(options or {}))
    tight = {**dict(options or {}), "rtol": max(rtol / accuracy.TOLERANCE_FACTOR, accuracy.MIN_RTOL),
             "atol": atol / accuracy.TOLERANCE_FACTOR}
    runs = [predict(flowsheet, experiments, params, options=tight)]
    if flowsheet.grid() is not None:
        runs += [predict(flowsheet.refined(f), experiments, params, options=tight) for f in accuracy.REFINEMENTS]
    key = {(p["experiment"], p["observable"]): k for k, p in enumerate(predictions)}
    by = [{(p["experiment"], p["observable"]): p for p in run} for run in runs]
    for (e, o), k in key.items():
        base = np.asarray(predictions[k]["model"], dtype=float)
        t = np.asarray(by[0][(e, o)]["model"], dtype=float)
        err = base - t
        if len(by) == 3:
            err = err + accuracy.richardson_series(t, np.asarray(by[1][(e, o)]["model"], dtype=float),
                                                   np.asarray(by[2][(e, o)]["model"], dtype=float), np.abs(err))
        predictions[k]["model_error"] = err.tolist()


def report(flowsheet: Flowsheet, result: CalibrationResult, calibration: Sequence[Experiment],
           validation: Sequence[Experiment] = (), *, comparison: CalibrationResult | None = None,
           truth: Mapping[str, float] | None = None, options: Mapping[str, Any] | None = None,
           error_estimate: bool = False) -> CalibrationReport:
    """Predictions at the final estimates on both sets, and R²/RMSE per output (and pooled per group). With
    ``error_estimate`` every prediction also carries the estimated numerical error of the model (``model_error``,
    :func:`model_errors`), and the fit table the largest |model error| / sigma per output: a model error well below
    the measurement's sigma does not move the estimates."""
    preds = {"calibration": predict(flowsheet, calibration, result.parameters, options=options)}
    if validation:
        preds["validation"] = predict(flowsheet, validation, result.parameters, options=options)
    if error_estimate:
        for name, exps in (("calibration", calibration), ("validation", validation)):
            if name in preds:
                model_errors(flowsheet, exps, result.parameters, preds[name], options)
    groups = observable_groups(flowsheet.summary_map, flowsheet.state_names + flowsheet.output_names)
    rows = []
    for setname, p in preds.items():
        for r in fit_statistics(p, observable_groups=groups):
            if error_estimate:
                r["max_model_error_over_sigma"] = _worst_model_error(p, r["output"], groups)
            rows.append({"set": setname, **r})
    units = {p["observable"]: flowsheet.unit_of(p["observable"]) for ps in preds.values() for p in ps}
    for r in rows:  # RMSE is in the SI unit of the observable (of the group's members for pooled rows)
        members = groups.get(r["output"], (r["output"],))
        r["unit"] = next((units[m] for m in members if m in units), "")
    param_units = {e["name"]: flowsheet.spec(e["name"])["unit"] for e in result.final["estimates"]}
    return CalibrationReport(result, preds, rows, comparison, dict(truth) if truth else None, units, param_units,
                             groups)
