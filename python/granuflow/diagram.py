"""Flowsheet diagrams drawn by Graphviz (Debian's ``graphviz``): units as nodes labelled with their type, streams as
edges labelled with their kind, recycles drawn apart so a loop is seen at a glance, and a controller's measured and
driven quantities as dashed signal lines.

    fs = granuflow.load("flowsheets/continuous_layering_sieve_mill.yaml")
    fs.diagram()                      # inline SVG in a notebook
    fs.diagram().save("loop.svg")     # or .png / .pdf
    granuflow draw SCENE --out loop.svg

The graph is the scene's own: its ``units`` and ``connections``, with each port's stream kind from the unit
registry (``granuflow units NAME``). A connection that closes a cycle (it runs from a unit back to one that the
depth-first walk from the feeds is still inside; probes, which carry information, not material, are left out of the
walk) is drawn against the flow; when it carries solids it is what a process engineer calls a recycle, and is
labelled so.
"""
from __future__ import annotations

import html
import os
import shutil
import subprocess

from . import _core

ConfigError = _core.ConfigError

# Stream kinds by colour, so a gas path and a solids path are told apart without reading labels.
_KIND_COLOURS = {"gas": "#1f77b4", "liquid": "#17becf", "solids": "#8c564b", "heat": "#d62728", "vapour": "#7f7f7f",
                 "wetting": "#2ca02c", "holdup": "#9467bd"}
# Settings of a controller that name another unit's quantity (pi_controller: measure, drive), drawn as signal lines.
_SIGNAL_SETTINGS = ("measure", "drive")
_SIGNAL_COLOUR = "#e377c2"
_FORMATS = {".svg": "svg", ".png": "png", ".pdf": "pdf", ".dot": "dot"}


def _scene_graph(fs) -> tuple[dict, list, dict]:
    """``({unit: (type, ports)}, [(src, src_port, dst, dst_port), ...], {(controller, measure|drive): "unit.name"})``
    from the flowsheet's scene text."""
    import yaml

    from .reference import unit_reference
    from .textfile import yaml_loader

    doc = yaml.load(fs.text, Loader=yaml_loader(yaml)) or {}
    units, signals = {}, {}
    for name, spec in (doc.get("units") or {}).items():
        spec = spec or {}
        settings = {k: v for k, v in (spec.get("settings") or {}).items() if not isinstance(v, (dict, list))}
        try:
            ports = {p["name"]: p for p in unit_reference(spec.get("type", ""), settings)["ports"]}
        except (ConfigError, ValueError):
            ports = {}
        units[str(name)] = (str(spec.get("type", "?")), ports)
        signals.update({(str(name), k): str(v) for k, v in settings.items() if k in _SIGNAL_SETTINGS})
    edges = []
    for text in doc.get("connections") or []:
        src, _, dst = str(text).partition("->")
        (su, _, sp), (du, _, dp) = src.strip().partition("."), dst.strip().partition(".")
        edges.append((su, sp, du, dp))
    return units, edges, signals


def _port(units: dict, unit: str, port: str) -> dict:
    return units.get(unit, ("", {}))[1].get(port) or {}


def _back_edges(units: dict, edges: list) -> set[int]:
    """Indices of the material edges that close a cycle (back edges of a depth-first walk started at the units
    without inlets, then at any unit not yet reached, in scene order)."""
    out: dict[str, list[int]] = {u: [] for u in units}
    has_in = set()
    for i, (su, sp, du, dp) in enumerate(edges):
        if "probe" in (_port(units, su, sp).get("direction"), _port(units, du, dp).get("direction")):
            continue
        out.setdefault(su, []).append(i)
        has_in.add(du)
    state: dict[str, int] = {}  # 1 on the walk's path, 2 finished
    back: set[int] = set()

    def walk(u: str) -> None:
        state[u] = 1
        for i in out.get(u, []):
            v = edges[i][2]
            if state.get(v) == 1:
                back.add(i)
            elif v not in state:
                walk(v)
        state[u] = 2

    for u in [u for u in out if u not in has_in] + list(out):
        if u not in state:
            walk(u)
    return back


def dot_source(fs) -> str:
    """The Graphviz text of the flowsheet."""
    units, edges, signals = _scene_graph(fs)
    back = _back_edges(units, edges)
    q = html.escape
    lines = [f'digraph "{q(fs.name)}" {{', '  rankdir=LR; bgcolor="white"; fontname="Helvetica";',
             f'  label=<<b>{q(fs.name)}</b>>; labelloc=t;',
             '  node [shape=box, style="rounded,filled", fillcolor="#f4f4f4", fontname="Helvetica", fontsize=11];',
             '  edge [fontname="Helvetica", fontsize=9];']
    for name, (typ, _) in units.items():
        lines.append(f'  "{q(name)}" [label=<<b>{q(name)}</b><br/><font point-size="9">{q(typ)}</font>>];')
    for i, (su, sp, du, dp) in enumerate(edges):
        port = _port(units, su, sp) or _port(units, du, dp)
        kind = port.get("kind", "")
        probe = "probe" in (_port(units, su, sp).get("direction"), _port(units, du, dp).get("direction"))
        attrs = [f'label="{q(kind)}{" (probe)" if probe else ""}"', f'color="{_KIND_COLOURS.get(kind, "black")}"',
                 f'tooltip="{q(su)}.{q(sp)} -> {q(du)}.{q(dp)}"']
        if probe:
            attrs.append("style=dotted")
        if i in back:
            attrs.append("constraint=false")
            if kind == "solids":
                attrs += ['style="dashed,bold"', 'xlabel="recycle"', 'fontcolor="#d62728"']
        lines.append(f'  "{q(su)}" -> "{q(du)}" [{", ".join(attrs)}];')
    # Controllers' signals (docs/controllers.md): what a controller measures and the parameter it drives. They are
    # information, not streams: dashed, and left out of the layout's ranks.
    for (unit, key), target in sorted(signals.items()):
        other = target.partition(".")[0]
        if other not in units:
            continue
        src, dst = (other, unit) if key == "measure" else (unit, other)
        lines.append(f'  "{q(src)}" -> "{q(dst)}" [label="{q(key)} {q(target)}", color="{_SIGNAL_COLOUR}", '
                     f'fontcolor="{_SIGNAL_COLOUR}", style=dashed, constraint=false];')
    lines.append("}")
    return "\n".join(lines) + "\n"


def _dot_program() -> str:
    exe = shutil.which("dot")
    if not exe:
        raise RuntimeError("drawing a flowsheet needs Graphviz's 'dot' (Debian package graphviz: "
                           "sudo apt-get install graphviz)")
    return exe


def render(source: str, fmt: str = "svg") -> bytes:
    """``source`` drawn by Graphviz in ``fmt`` (svg, png, pdf)."""
    done = subprocess.run([_dot_program(), f"-T{fmt}"], input=source.encode(), capture_output=True, timeout=60)
    if done.returncode != 0:
        raise RuntimeError(f"Graphviz failed: {done.stderr.decode(errors='replace').strip()}")
    return done.stdout


class Diagram:
    """A flowsheet's diagram: shown inline in a notebook, saved as SVG, PNG, PDF or DOT."""

    def __init__(self, fs):
        self.name = fs.name
        self.dot = dot_source(fs)
        self._svg: str | None = None

    @property
    def svg(self) -> str:
        if self._svg is None:
            self._svg = render(self.dot, "svg").decode()
        return self._svg

    def _repr_svg_(self) -> str:
        return self.svg

    def save(self, path: str | os.PathLike) -> str:
        """Write the diagram; the format follows the extension (.svg, .png, .pdf, .dot)."""
        path = os.fspath(path)
        ext = os.path.splitext(path)[1].lower()
        if ext not in _FORMATS:
            raise ValueError(f"diagram file {path}: extension '{ext}' not supported (allowed: "
                             f"{', '.join(_FORMATS)})")
        data = self.dot.encode() if ext == ".dot" else (self.svg.encode() if ext == ".svg"
                                                        else render(self.dot, _FORMATS[ext]))
        with open(path, "wb") as f:
            f.write(data)
        return path
