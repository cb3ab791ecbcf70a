"""One self-contained HTML page for a finished output folder: ``granuflow report OUT`` writes ``OUT/report.html``.

It works for every command that writes a folder (run, steady, sweep, contour, calibrate) and holds, in this order:
the flowsheet diagram, the results with their units (and error estimates where they were computed), the balances
and the warnings, the plots, and the scene with the command that produced the folder (``provenance.json``). The
page loads nothing: plots are embedded as data URIs, the diagram as inline SVG, the style sheet is inline and there
is no script, so it opens offline and can be mailed or archived as one file.
"""
from __future__ import annotations

import base64
import csv
import glob
import html
import json
import os

from . import _core

ConfigError = _core.ConfigError

# What identifies each kind of folder, in the order they are tried.
_KINDS = (("calibration", "estimates.csv"), ("contour", "contour.json"), ("sweep", "sweep.json"),
          ("steady", "steady.json"), ("run", "summary.json"))
_TABLE_ROWS = 60  # a sweep or contour table shows this many rows; the CSV beside the page has them all

_STYLE = """
body{font-family:Helvetica,Arial,sans-serif;margin:0;color:#222;background:#fff}
header{background:#1f4e79;color:#fff;padding:14px 24px}
header h1{margin:0;font-size:22px} header p{margin:4px 0 0;font-size:13px;color:#dbe6f1}
main{padding:8px 24px 40px;max-width:1200px}
h2{border-bottom:2px solid #1f4e79;padding-bottom:3px;font-size:17px;margin-top:28px}
table{border-collapse:collapse;font-size:13px;margin:6px 0}
td,th{border:1px solid #ccc;padding:3px 8px;text-align:left;vertical-align:top}
th{background:#eef3f8} td.num{text-align:right;font-family:monospace}
.warn{background:#fff4e0;border-left:4px solid #e69500;padding:6px 10px;margin:4px 0;font-size:13px}
.ok{background:#e8f5e9;border-left:4px solid #2e7d32;padding:6px 10px;margin:4px 0;font-size:13px}
pre{background:#f6f6f6;padding:10px;font-size:12px;overflow-x:auto;white-space:pre-wrap}
figure{margin:10px 0;display:inline-block;max-width:100%} figure img{max-width:100%;border:1px solid #ddd}
figcaption{font-size:12px;color:#555} .diagram svg{max-width:100%;height:auto}
"""


def _kind(out: str) -> str:
    for kind, marker in _KINDS:
        if os.path.isfile(os.path.join(out, marker)):
            return kind
    raise ConfigError(f"{out}: not an output folder of granuflow (no summary.json, steady.json, sweep.json, "
                      "contour.json or estimates.csv)")


def _read_json(path: str) -> dict:
    try:
        with open(path, encoding="utf-8") as f:
            return json.load(f)
    except (OSError, ValueError) as e:
        raise ConfigError(f"{path}: cannot be read as JSON ({e})") from None


def _fmt(v) -> str:
    if isinstance(v, float):
        return f"{v:.6g}"
    if v is None:
        return "null"
    return str(v)


def _table(rows, header=None) -> str:
    out = ["<table>"]
    if header:
        out.append("<tr>" + "".join(f"<th>{html.escape(str(h))}</th>" for h in header) + "</tr>")
    for r in rows:
        out.append("<tr>" + "".join(
            f'<td class="num">{html.escape(_fmt(c))}</td>' if isinstance(c, (int, float)) and not isinstance(c, bool)
            else f"<td>{html.escape(_fmt(c))}</td>" for c in r) + "</tr>")
    out.append("</table>")
    return "\n".join(out)


def _csv_table(path: str) -> str:
    with open(path, encoding="utf-8") as f:
        rows = list(csv.reader(f))
    if not rows:
        return "<p>(empty)</p>"
    more = len(rows) - 1 - _TABLE_ROWS
    note = f"<p>{more} more rows in {html.escape(os.path.basename(path))}</p>" if more > 0 else ""
    return _table(rows[1:1 + _TABLE_ROWS], rows[0]) + note


def _scalars(d: dict, units: dict, errors: dict) -> list[list]:
    """Rows of (key, value, unit, estimated error) for the scalar entries of a summary."""
    rows = []
    for k, v in d.items():
        if isinstance(v, (dict, list)) or k in ("scene", "units"):
            continue
        e = errors.get(k)
        if isinstance(e, dict):
            e = e.get("relative")
        rows.append([k, v, units.get(k, ""), "" if e is None else f"{e:+.2%}"])
    return rows


def _results(kind: str, out: str) -> tuple[str, dict]:
    """The results section's HTML and the document it came from."""
    if kind == "run":
        doc = _read_json(os.path.join(out, "summary.json"))
        # --error-estimate's relative errors where computed, else the plain run's grid check (first order)
        errors = dict(((doc.get("grid_check") or {}).get("errors") or {}))
        errors.update(((doc.get("error_estimate") or {}).get("outputs") or {}))
        header = ["result", "value", "unit", "estimated relative error"]
        return _table(_scalars(doc, doc.get("units", {}) or {}, errors), header), doc
    if kind == "steady":
        doc = _read_json(os.path.join(out, "steady.json"))
        return _table(_scalars(doc, doc.get("units", {}) or {}, {}), ["result", "value", "unit", ""]), doc
    if kind == "sweep":
        doc = _read_json(os.path.join(out, "sweep.json"))
        return _csv_table(os.path.join(out, "sweep.csv")), doc
    if kind == "contour":
        doc = _read_json(os.path.join(out, "contour.json"))
        meta = [[k, v] for k, v in doc.items() if not isinstance(v, (dict, list))]
        return _table(meta, ["contour map", "value"]) + _csv_table(os.path.join(out, "contour.csv")), doc
    doc = _read_json(os.path.join(out, "report.json")) if os.path.isfile(os.path.join(out, "report.json")) else {}
    text = ""
    if os.path.isfile(os.path.join(out, "report.txt")):
        with open(os.path.join(out, "report.txt"), encoding="utf-8") as f:
            text = f"<pre>{html.escape(f.read())}</pre>"
    return _csv_table(os.path.join(out, "estimates.csv")) + text, doc


def _checks(doc: dict) -> str:
    """Balances, warnings and the reasons a result is null."""
    parts = []
    bal = doc.get("balance") or doc.get("balances")
    if isinstance(bal, dict) and bal:
        parts.append(_table([[k, v] for k, v in bal.items() if not isinstance(v, (dict, list))],
                            ["balance (relative closure)", "value"]))
    warnings = list(doc.get("warnings") or [])
    for k, why in (doc.get("null_reasons") or {}).items():
        warnings.append(f"{k} is null: {why}")
    gc = doc.get("grid_check")
    if isinstance(gc, dict) and gc.get("warning"):
        warnings.append(str(gc["warning"]))
    parts += [f'<div class="warn">{html.escape(str(w))}</div>' for w in warnings]
    if not warnings:
        parts.append('<div class="ok">no warnings</div>')
    return "\n".join(parts)


def _plots(out: str) -> str:
    figs = []
    for path in sorted(glob.glob(os.path.join(out, "*.png"))):
        with open(path, "rb") as f:
            data = base64.b64encode(f.read()).decode()
        name = html.escape(os.path.basename(path))
        figs.append(f'<figure><img alt="{name}" src="data:image/png;base64,{data}"><figcaption>{name}'
                    "</figcaption></figure>")
    return "\n".join(figs) or "<p>(no plots in this folder)</p>"


def _scene_path(prov: dict) -> str | None:
    """The scene the folder's results come from: the scene argument, or the one a sweep or experiment file names."""
    inputs = prov.get("inputs", {})
    if "scene" in inputs:
        return inputs["scene"]["path"]
    for key in ("sweepfile", "experiments"):
        if key in inputs and "text" in inputs[key]:
            import yaml

            from .textfile import yaml_loader
            try:
                scene = (yaml.load(inputs[key]["text"], Loader=yaml_loader(yaml)) or {}).get("scene")
            except yaml.YAMLError:
                return None
            if isinstance(scene, str):
                return os.path.normpath(os.path.join(os.path.dirname(inputs[key]["path"]), scene))
    return None


def _diagram(scene: str | None) -> str:
    if not scene or not os.path.isfile(scene):
        return "<p>(the scene file is not at hand: no diagram)</p>"
    from .diagram import Diagram
    from .flowsheet import load
    try:
        svg = Diagram(load(scene)).svg
    except (ConfigError, RuntimeError) as e:
        return f"<p>(no diagram: {html.escape(str(e))})</p>"
    return f'<div class="diagram">{svg[svg.index("<svg"):]}</div>'


def _provenance(prov: dict) -> str:
    if not prov:
        return "<p>(no provenance.json: the folder was not written by the command line)</p>"
    parts = [f"<p>command (in {html.escape(prov.get('cwd', '?'))}):</p>",
             f"<pre>{html.escape(prov.get('command', '?'))}</pre>",
             f"<p>granuflow {html.escape(str(prov.get('version', '?')))}, finished "
             f"{html.escape(str(prov.get('finished', '?')))}</p>"]
    for key, entry in prov.get("inputs", {}).items():
        parts.append(f"<h3>{html.escape(key)}: {html.escape(entry['path'])}</h3>")
        parts.append(f"<pre>{html.escape(entry.get('text', '(not copied)'))}</pre>")
    return "\n".join(parts)


def write_report(out: str | os.PathLike) -> str:
    """Write ``OUT/report.html`` for a finished output folder and return its path."""
    from . import __version__

    out = os.fspath(out)
    if not os.path.isdir(out):
        raise ConfigError(f"{out}: no such output folder")
    kind = _kind(out)
    prov_path = os.path.join(out, "provenance.json")
    prov = _read_json(prov_path) if os.path.isfile(prov_path) else {}
    results, doc = _results(kind, out)
    scene = _scene_path(prov)
    title = f"{kind}: {doc.get('scene') or os.path.basename(os.path.abspath(out))}"
    page = f"""<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8"><title>granuflow {html.escape(title)}</title>
<style>{_STYLE}</style></head><body>
<header><h1>granuflow {html.escape(title)}</h1><p>{html.escape(os.path.abspath(out))} · report by granuflow
{html.escape(__version__)}</p></header>
<main>
<h2 id="flowsheet">Flowsheet</h2>
{_diagram(scene)}
<h2 id="results">Results</h2>
{results}
<h2 id="checks">Balances and warnings</h2>
{_checks(doc)}
<h2 id="plots">Plots</h2>
{_plots(out)}
<h2 id="provenance">Scene and command</h2>
{_provenance(prov)}
</main></body></html>
"""
    path = os.path.join(out, "report.html")
    with open(path, "w", encoding="utf-8") as f:
        f.write(page)
    return path
