"""Plots of contour maps, feasible windows and probabilistic design spaces."""
from __future__ import annotations

from typing import Sequence

import numpy as np

from .. import outputs
from ..quantity import convert, pretty


def _display(output: str, values):
    """(axis label with unit, values in the unit shown) of a summary key or state/output at the final time."""
    name, unit, shown = outputs.summary_display(output)
    v = convert(values, shown, unit) if shown else np.asarray(values, dtype=float)
    return (f"{name} / {pretty(shown)}" if shown else name), v


def _display_bound(c) -> str:
    name, unit, shown = outputs.summary_display(c.output)
    b = float(convert(c.bound, shown, unit)) if shown else c.bound
    op = {">=": "≥", "<=": "≤"}.get(c.op, c.op)
    return f"{name} {op} {b:g} {pretty(shown)}".strip()


def _axes(ax, path, figsize=(6.4, 4.8)):
    """The axes to draw on: ``ax``; else a new figure, without pyplot when it only goes to a file (so that saving
    PNGs never changes the backend of a notebook), with pyplot otherwise (shown inline)."""
    if ax is not None:
        return ax.figure, ax, False
    if path:
        from matplotlib.figure import Figure

        fig = Figure(figsize=figsize)
        return fig, fig.add_subplot(), True
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=figsize)
    return fig, ax, True


def _finish(fig, ax, path, own: bool):
    if own:
        fig.tight_layout()
    if path:
        fig.savefig(path, dpi=110)
        return path
    return ax


def _draw_window(ax, window, *, color="k", hatch="//", label="feasible window"):
    from matplotlib.patches import Polygon

    first = True
    for ring in window.outline:
        ax.add_patch(Polygon(ring, closed=True, fill=False, hatch=hatch, edgecolor=color, linewidth=1.6,
                             label=label if first else None))
        first = False


def plot_contour(grid, output: str, path: str | None = None, *, ax=None, levels: int | Sequence = 12,
                 window=None, title: str | None = None, cmap: str = "viridis",
                 mark_points: bool = False):
    """Filled contours of ``output`` over the grid with labelled contour lines (display units: µm, wt%, °C), the
    feasible ``window`` hatched and outlined if given. Saves a PNG at ``path`` (returns it), else draws on ``ax``
    (returns it)."""
    fig, ax, own = _axes(ax, path)
    label, z = _display(output, grid[output])
    if min(z.shape) < 2:  # one point on an axis (allowed): a profile along the other, no contours
        return _profile(fig, ax, path, own, grid, output, label, z, title, window)
    zm = np.ma.masked_invalid(z)
    cf = ax.contourf(grid.x.values, grid.y.values, zm, levels=levels, cmap=cmap)
    cs = ax.contour(grid.x.values, grid.y.values, zm, levels=cf.levels, colors="k", linewidths=0.6)
    ax.clabel(cs, cs.levels[::2], fmt="%.3g", fontsize=7)
    fig.colorbar(cf, ax=ax, label=label)
    if window is not None:
        _draw_window(ax, window)
        ax.legend(loc="upper left", fontsize=8, framealpha=0.8)
    if mark_points:
        X, Y = np.meshgrid(grid.x.values, grid.y.values)
        ax.plot(X[~grid.ok], Y[~grid.ok], "rx", ms=5, label="failed")
    ax.set_xlabel(grid.x.label)
    ax.set_ylabel(grid.y.label)
    _category_ticks(ax, grid.x, grid.y)
    ax.set_title(title if title is not None else f"{label.split(' / ')[0]} {grid.when}")
    return _finish(fig, ax, path, own)


def _category_ticks(ax, x, y) -> None:
    """A categorical setting's axis (bed.aggregation=kapur,sum) shows the names at their positions."""
    if x is not None and x.labels:
        ax.set_xticks(x.values, x.labels)
    if y is not None and y.labels:
        ax.set_yticks(y.values, y.labels)


def _profile(fig, ax, path, own, grid, output, label, z, title, window):
    """``output`` along the axis with more than one point, the other held at its single value (a map with one
    point on an axis); the feasible points marked when a window is given."""
    along, held = (grid.x, grid.y) if z.shape[1] >= z.shape[0] else (grid.y, grid.x)
    v = z.ravel()
    ax.plot(along.values, v, "o-", ms=4, label=label.split(" / ")[0])
    if window is not None and window.mask.any():
        ok = window.mask.ravel()
        ax.plot(along.values[ok], v[ok], "o", color="tab:red", ms=6, label="feasible")
        ax.legend(loc="best", fontsize=8)
    ax.set_xlabel(along.label)
    _category_ticks(ax, along, None)
    ax.set_ylabel(label)
    ax.grid(alpha=0.3)
    note = f"{held.param} = {held.values[0]:g} {held.unit}".strip()
    ax.set_title(title if title is not None else f"{label.split(' / ')[0]} {grid.when} ({note})",
                 fontsize=10)
    return _finish(fig, ax, path, own)


def plot_feasible_window(window, path: str | None = None, *, grid=None,
                         background: str | None = None, ax=None, title: str | None = None):
    """Fig. 20 style: each constraint's boundary line (labelled), the feasible window hatched, the grid points
    inside it marked red; optionally filled contours of ``background`` (an output of ``grid``) underneath."""
    fig, ax, own = _axes(ax, path)
    if grid is not None and background is not None and min(grid[background].shape) >= 2:
        label, z = _display(background, grid[background])
        cf = ax.contourf(grid.x.values, grid.y.values, np.ma.masked_invalid(z), levels=12, cmap="Greys", alpha=0.6)
        fig.colorbar(cf, ax=ax, label=label)
    colors = ["tab:blue", "tab:orange", "tab:green", "tab:purple", "tab:brown"]
    for k, c in enumerate(window.constraints):
        for n, seg in enumerate(window.boundaries[str(c)]):
            ax.plot(seg[:, 0], seg[:, 1], color=colors[k % len(colors)], lw=2,
                    label=_display_bound(c) if n == 0 else None)
    _draw_window(ax, window, color="tab:red")
    X, Y = np.meshgrid(window.x.values, window.y.values)
    ax.plot(X[window.mask], Y[window.mask], "o", color="tab:red", ms=3, label="feasible grid points")
    ax.plot(X[~window.mask], Y[~window.mask], "o", color="0.6", ms=2, label="infeasible grid points")
    for axis, set_lim in ((window.x, ax.set_xlim), (window.y, ax.set_ylim)):
        if axis.hi > axis.lo:  # a single point on an axis: matplotlib picks a range around it
            set_lim(axis.lo, axis.hi)
    ax.set_xlabel(window.x.label)
    ax.set_ylabel(window.y.label)
    ax.set_title(title if title is not None else "Design space: " + ", ".join(_display_bound(c)
                                                                              for c in window.constraints))
    ax.legend(loc="best", fontsize=7, framealpha=0.85)
    return _finish(fig, ax, path, own)


def plot_probability(pmap, path: str | None = None, *, ax=None, title: str | None = None,
                     levels: Sequence[float] = (0.5, 0.9)):
    """P(all constraints met) as filled contours with the ``levels`` (0.5, 0.9) drawn and labelled, and the nominal
    feasible window (mean parameters) dashed."""
    fig, ax, own = _axes(ax, path)
    cf = ax.contourf(pmap.x.values, pmap.y.values, pmap.probability, levels=np.linspace(0, 1, 11), cmap="RdYlGn",
                     vmin=0, vmax=1)
    fig.colorbar(cf, ax=ax, label="P(constraints met)")
    cs = ax.contour(pmap.x.values, pmap.y.values, pmap.probability, levels=list(levels), colors="k",
                    linewidths=[1.2, 2.0][:len(levels)] or 1.2)
    ax.clabel(cs, fmt=lambda v: f"P = {v:g}", fontsize=8)
    win = pmap.nominal_window
    for n, ring in enumerate(win.outline):
        ax.plot(np.r_[ring[:, 0], ring[:1, 0]], np.r_[ring[:, 1], ring[:1, 1]], "b--", lw=1.2,
                label="nominal window" if n == 0 else None)
    if win.outline:
        ax.legend(loc="upper left", fontsize=8, framealpha=0.8)
    ax.set_xlabel(pmap.x.label)
    ax.set_ylabel(pmap.y.label)
    ax.set_title(title if title is not None else
                 f"Probabilistic design space ({pmap.method}, {len(pmap.params)} uncertain parameters)")
    return _finish(fig, ax, path, own)
