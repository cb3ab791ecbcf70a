"""Plots as files (PNG) from results: time series per scene plot spec, PSD evolution."""
from __future__ import annotations

import numpy as np

# Display units of the series plots, each with its SI unit and (factor, offset): display = SI * factor + offset.
_UNIT_CONVERT = {
    "degC": ("K", 1.0, -273.15), "K": ("K", 1.0, 0.0), "um": ("m", 1e6, 0.0), "mm": ("m", 1e3, 0.0),
    "m": ("m", 1.0, 0.0), "kg/s": ("kg/s", 1.0, 0.0), "g/min": ("kg/s", 6e4, 0.0), "wt%": ("kg/kg", 100.0, 0.0),
    "kg/kg": ("kg/kg", 1.0, 0.0), "kg": ("kg", 1.0, 0.0), "g": ("kg", 1e3, 0.0), "W": ("W", 1.0, 0.0),
    "-": ("-", 1.0, 0.0),
}


def _plt():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def supported_formats() -> list[str]:
    """File extensions matplotlib can write (png, pdf, svg, ...)."""
    plt = _plt()
    fig = plt.figure()
    try:
        return sorted(fig.canvas.get_supported_filetypes())
    finally:
        plt.close(fig)


def display_units(si_unit: str | None = None) -> list[str]:
    """The display units of series plots (those for `si_unit` when given)."""
    return [u for u, (si, _, _) in _UNIT_CONVERT.items() if si_unit is None or si == si_unit]


def conversion(unit: str, si_unit: str | None = None) -> tuple[float, float]:
    """(factor, offset) with display = SI * factor + offset; ValueError for an unknown unit or one of another
    dimension than `si_unit` (when given)."""
    if unit in ("", None) or (si_unit is not None and unit == si_unit):
        return 1.0, 0.0
    if unit not in _UNIT_CONVERT:
        raise ValueError(f"unknown unit '{unit}' (allowed: {', '.join(display_units())})")
    si, f, o = _UNIT_CONVERT[unit]
    if si_unit is not None and si != si_unit:
        raise ValueError(f"unit '{unit}' is for {si}, but the series is in {si_unit or '-'} "
                         f"(allowed: {', '.join(display_units(si_unit)) or si_unit or '-'})")
    return f, o


def convert(values, unit: str, si_unit: str | None = None):
    """SI values in the display `unit` (ValueError for an unknown unit or one of another dimension)."""
    f, o = conversion(unit, si_unit)
    return np.asarray(values) * f + o


def plot_series(result, spec: dict, path: str) -> str:
    """One figure: the series named in ``spec["y"]`` over time in minutes, converted to ``spec["unit"]``."""
    plt = _plt()
    unit = spec.get("unit", "")
    fig, ax = plt.subplots(figsize=(6.4, 4.0))
    for name in spec["y"]:
        ax.plot(result.t / 60.0, convert(result[name], unit), label=name)
    ax.set_xlabel("time / min")
    ax.set_ylabel(f"{spec.get('ylabel', '')} / {unit}" if unit else spec.get("ylabel", ""))
    ax.set_title(spec.get("title", ""))
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def plot_psd(result, path: str, times_s=None, unit: str | None = None) -> str:
    """Mass density q3 over log-diameter at several times (PSD evolution)."""
    plt = _plt()
    if times_s is None:
        times_s = np.linspace(result.t[0], result.t[-1], 5)
    fig, ax = plt.subplots(figsize=(6.4, 4.0))
    for t in times_s:
        df = result.psd(t, unit)
        d = df["d_um"].to_numpy()
        # q3 over ln d from class mass fractions, with the geometric class widths of the pivots
        edges = np.sqrt(d[1:] * d[:-1])
        edges = np.concatenate([[d[0] ** 2 / edges[0]], edges, [d[-1] ** 2 / edges[-1]]])
        q3 = df["mass_fraction"].to_numpy() / np.diff(np.log(edges))
        ax.semilogx(d, q3, marker="o", ms=3, label=f"{t / 60:.0f} min")
    ax.set_xlabel("particle diameter / µm")
    ax.set_ylabel("q3 (ln d) / -")
    ax.set_title("Particle size distribution")
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path
