"""Plots of one run as files (PNG): the time series of a scene's `plots:` entries, the size distribution at several
times. Legends use readable names (not ``bed.d10``), axes carry units, and a curve the size grid clips says so."""
from __future__ import annotations

import numpy as np

from .. import outputs
from ..quantity import convert, from_si, pretty


def figure(figsize=(6.4, 4.0)):
    """A figure that only goes to a file: no pyplot (faster to import, never changes a notebook's backend)."""
    from matplotlib.figure import Figure

    fig = Figure(figsize=figsize)
    return fig, fig.add_subplot()


def _margins(fig) -> None:
    """Fixed margins instead of tight_layout(), which draws every text twice: a third of the time of
    `granuflow run` with plots. Legends sit inside the axes, so fixed margins fit every series plot."""
    fig.subplots_adjust(left=0.12, right=0.97, bottom=0.12, top=0.91)


def _phases(ax, result) -> None:
    """A recipe's events as dashed vertical lines, every second phase shaded and each named at the bottom."""
    events = getattr(result, "events", None)
    if not events:
        return
    for k, ph in enumerate(result.phases):
        a, b = ph["t_start_s"] / 60.0, ph["t_end_s"] / 60.0
        if k % 2 == 1:
            ax.axvspan(a, b, color="0.85", alpha=0.5, lw=0, zorder=0)
        if k > 0:
            ax.axvline(a, color="0.35", ls="--", lw=0.8)
        ax.text(0.5 * (a + b), 0.01, ph["name"], transform=ax.get_xaxis_transform(), ha="center", va="bottom",
                fontsize=7, color="0.3")


def supported_formats() -> list[str]:
    """File extensions matplotlib can write (png, pdf, svg, ...)."""
    from matplotlib.backend_bases import FigureCanvasBase

    return sorted(FigureCanvasBase.get_supported_filetypes())


def plot_series(result, spec: dict, path: str) -> str:
    """One figure: the series named in ``spec["y"]`` over time in minutes, converted to ``spec["unit"]``."""
    fig, ax = figure()
    units = set()
    for name in spec["y"]:
        si = result.unit(name)
        unit = spec.get("unit") or outputs.display_unit(name, si)
        units.add(unit)
        label = f"{outputs.readable(name)} [{pretty(unit)}]"
        top = clipped_top_um(result, name, si)
        if top is not None:
            label += f", clipped by the size grid (top class {top:.0f} µm)"
        line, = ax.plot(result.t / 60.0, convert(result[name], unit, si), label=label)
        err = _error(result, name)
        if err is not None:  # the estimated numerical error as a band around the curve
            lo, hi = (convert(result[name] + sign * np.abs(err), unit, si) for sign in (-1, 1))
            ax.fill_between(result.t / 60.0, lo, hi, color=line.get_color(), alpha=0.25, lw=0)
    _phases(ax, result)
    unit = units.pop() if len(units) == 1 else ""
    ylabel = spec.get("ylabel", "")
    ax.set_xlabel("time / min")
    ax.set_ylabel(f"{ylabel} / {pretty(unit)}" if unit and ylabel else ylabel or pretty(unit))
    ax.set_title(spec.get("title", ""))
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    _margins(fig)
    _error_footnote(fig, result, spec["y"], spec.get("unit"))
    fig.savefig(path, dpi=110)
    return path


def _error(result, name: str):
    """The estimated numerical error of a series over time, if the result carries an error estimate."""
    ee = getattr(result, "error_estimate", None)
    return None if ee is None else ee.error(name)


def _error_footnote(fig, result, names, unit=None) -> None:
    """A footnote under the axes: the estimated numerical error of each named series at the end of the run and how it
    was estimated (bands show it over time), when the result carries an error estimate."""
    ee = getattr(result, "error_estimate", None)
    if ee is None:
        return
    parts = []
    for name in names:
        err = ee.error(name)
        if err is None:
            continue
        si = result.unit(name)
        shown = unit or outputs.display_unit(name, si)
        e = float(convert(result[name][-1] + abs(err[-1]), shown, si) - convert(result[name][-1], shown, si))
        parts.append(f"{name} ±{e:.3g} {pretty(shown)}")
    how = (f"grid {ee.grid.split(' ', 1)[1]} classes" if ee.grid else "no size grid") + \
        f", rtol {ee.rtol[0]:g} vs {ee.rtol[1]:g}"
    fig.subplots_adjust(bottom=0.2)
    fig.text(0.01, 0.01, f"Estimated numerical error at the end (bands over time; {how}): " + ", ".join(parts),
             fontsize=6.5, wrap=True)


# Mass fraction in the top class above which a shown distribution counts as clipped by the grid.
CLIP_FRACTION = 1e-3


def clipped_top_um(result, name: str, si_unit: str):
    """The top pivot (µm) when ``name`` is a characteristic diameter dX of a unit whose top size class holds more
    than (100 - X) % of the mass at some output time (the grid then caps dX), else None."""
    unit = name.rpartition(".")[0]
    below = outputs.size_fraction(name)
    if below is None or si_unit != "m" or unit not in result.psd_units():
        return None
    dcols, mcols = outputs.psd_columns(result.output_roles, unit)
    m = result.outputs[:, mcols]
    total = m.sum(axis=1)
    frac = np.divide(m[:, -1], total, out=np.zeros_like(total), where=total > 0)
    return float(from_si(result.outputs[-1, dcols[-1]], "um", "m")) if frac.max() > 1.0 - below else None


def plot_psd(result, path: str, times_s=None, unit: str | None = None) -> str:
    """Mass density q3 over log-diameter at several times (PSD evolution). When mass sits in the top class at a shown
    time, the grid clips the distribution: the title and the legend say so (widen ``d_max`` of the size grid)."""
    if times_s is None:
        times_s = np.linspace(result.t[0], result.t[-1], 5)
    fig, ax = figure()
    clipped = []
    for t in times_s:
        _, d, _, frac = result.psd_arrays(t, unit)  # NumPy only: pandas would double the time of `granuflow run`
        # q3 over ln d from class mass fractions, with the geometric class widths of the pivots
        edges = np.sqrt(d[1:] * d[:-1])
        edges = np.concatenate([[d[0] ** 2 / edges[0]], edges, [d[-1] ** 2 / edges[-1]]])
        q3 = frac / np.diff(np.log(edges))
        top = float(frac[-1])
        note = ""
        if top > CLIP_FRACTION:
            clipped.append(t)
            note = f", {100 * top:.1f} % in the top class: clipped"
        ax.semilogx(d, q3, marker="o", ms=3, label=f"{t / 60:.0f} min{note}")
    ax.set_xlabel("particle diameter / µm")
    ax.set_ylabel("q3 (ln d) / -")
    ax.set_title("Particle size distribution" + (" (clipped by the size grid: mass in the top class)"
                                                 if clipped else ""), fontsize=10 if clipped else None)
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=8)
    _margins(fig)
    _error_footnote(fig, result, [n for n in (f"{unit or (result.psd_units() or [''])[0]}.d{x}" for x in (10, 50, 90))
                                  if n in result])
    fig.savefig(path, dpi=110)
    return path
