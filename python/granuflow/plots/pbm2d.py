"""The 2-D population of a ``pbm_2d`` unit (solid volume x liquid volume, paper 002) from a run: the numbers per bin
at an output time, their marginals, and plots as files: heat maps over the two coordinates at chosen times and the
solid and liquid-content marginals. Coordinates come from the unit's own outputs (``solid_pivot_<i>``,
``liquid_pivot_<j>``, m3), so the plots need nothing but the result."""
from __future__ import annotations

import math
import re

import numpy as np


def units_2d(result) -> list[str]:
    """Units of a result that hold a 2-D population (they report ``solid_pivot_0``)."""
    return [n[: -len(".solid_pivot_0")] for n in result.output_names if n.endswith(".solid_pivot_0")]


def _unit(result, unit: str | None) -> str:
    found = units_2d(result)
    if not found:
        raise ValueError("this result holds no 2-D population (no unit of type pbm_2d)")
    if unit is None:
        return found[0]
    if unit not in found:
        raise ValueError(f"unit {unit!r} holds no 2-D population (2-D units: {', '.join(found)})")
    return unit


def grid(result, unit: str | None = None) -> tuple[np.ndarray, np.ndarray]:
    """(solid pivot volumes s_i, liquid pivot volumes l_j), m3, of the unit's bins."""
    unit = _unit(result, unit)
    s, ll = [], []
    for i, name in enumerate(result.output_names):
        if name.startswith(unit + ".solid_pivot_"):
            s.append(result.outputs[0, i])
        elif name.startswith(unit + ".liquid_pivot_"):
            ll.append(result.outputs[0, i])
    return np.array(s), np.array(ll)


def distribution(result, t: float, unit: str | None = None) -> tuple[float, np.ndarray, np.ndarray, np.ndarray]:
    """(output time nearest ``t`` in s, s_i in m3, l_j in m3, N[i, j]) of the unit's population."""
    unit = _unit(result, unit)
    s, ll = grid(result, unit)
    k = int(np.argmin(np.abs(result.t - t)))
    N = np.zeros((len(s), len(ll)))
    pat = re.compile(re.escape(unit) + r"\.N_(\d+)_(\d+)$")
    for c, name in enumerate(result.state_names):
        m = pat.match(name)
        if m:
            N[int(m.group(1)), int(m.group(2))] = result.y[k, c]
    return float(result.t[k]), s, ll, N


def diameter(v):
    """Volume-equivalent sphere diameter, m."""
    return np.cbrt(6.0 * np.asarray(v) / math.pi)


def _edges(x: np.ndarray, log: bool) -> np.ndarray:
    """Cell edges around pivots for drawing (geometric or arithmetic means, extended at the ends)."""
    if log:
        m = np.sqrt(x[1:] * x[:-1])
        return np.concatenate([[x[0] ** 2 / m[0]], m, [x[-1] ** 2 / m[-1]]])
    m = 0.5 * (x[1:] + x[:-1])
    return np.concatenate([[x[0] - (m[0] - x[0])], m, [x[-1] + (x[-1] - m[-1])]])


def plot_heatmaps(result, path: str, times_s=None, unit: str | None = None, lc_min: float | None = None,
                  liquid_unit_m3: float | None = None) -> str:
    """One panel per time: number of particles per bin over solid-volume diameter (mm, log) and liquid volume
    (in multiples of ``liquid_unit_m3``, e.g. a droplet volume; default m3 x 1e9 = mm3), colour on a log scale. With
    ``lc_min`` the line LC = l / (s + l) = lc_min of Eq. (13) is drawn: bins above it are wet."""
    from matplotlib.colors import LogNorm
    from matplotlib.figure import Figure
    from matplotlib.ticker import NullFormatter, ScalarFormatter

    unit = _unit(result, unit)
    if times_s is None:
        times_s = [result.t[0], result.t[len(result.t) // 2], result.t[-1]]
    scale, label = (liquid_unit_m3, "liquid volume / droplet volumes") if liquid_unit_m3 else (1e-9, "liquid / mm3")
    fig = Figure(figsize=(3.3 * len(times_s) + 1.0, 3.4))
    axes = fig.subplots(1, len(times_s), squeeze=False, sharey=True)[0]
    data = [distribution(result, t, unit) for t in times_s]
    vmax = max(float(N.max()) for *_, N in data)
    vmin = max(vmax * 1e-8, 1e-3)
    for ax, (t, s, ll, N) in zip(axes, data):
        d = diameter(s) * 1e3
        mesh = ax.pcolormesh(_edges(d, True), _edges(ll / scale, False), np.where(N.T > vmin, N.T, np.nan),
                             norm=LogNorm(vmin=vmin, vmax=vmax), shading="flat", cmap="viridis")
        if lc_min is not None:
            ax.plot(d, s * lc_min / (1 - lc_min) / scale, "r--", lw=1, label=f"LC = {lc_min:g}")
            ax.legend(fontsize=7, loc="upper left")
        ax.set_xscale("log")
        ax.xaxis.set_major_formatter(ScalarFormatter())
        ax.xaxis.set_minor_formatter(NullFormatter())
        ax.set_xticks([x for x in (1, 2, 3, 4, 5, 6, 8, 10, 20) if d[0] / 1.2 <= x <= d[-1] * 1.2] or [d[0]])
        ax.set_ylim(0, (ll[-1] + 0.5 * (ll[1] - ll[0])) / scale)
        ax.set_title(f"t = {t:g} s", fontsize=10)
        ax.set_xlabel("solid diameter / mm")
    axes[0].set_ylabel(label)
    fig.subplots_adjust(left=0.06, right=0.9, bottom=0.15, top=0.9, wspace=0.08)
    fig.colorbar(mesh, cax=fig.add_axes([0.915, 0.15, 0.012, 0.75]), label="particles per bin")
    fig.savefig(path, dpi=110)
    return path


def marginals(result, t: float, unit: str | None = None, lc_bins: int = 20):
    """At the output time nearest ``t``: (time, solid diameter d_i in m, particles per solid class, liquid-content
    bin edges, particles per liquid-content bin). The liquid-content distribution bins each bin's LC = l / (s + l).
    Both are numbers of particles (multiply the first by s_i for the solid volume per class)."""
    t, s, ll, N = distribution(result, t, unit)
    solid = N.sum(axis=1)
    lc = ll[None, :] / (s[:, None] + ll[None, :])
    edges = np.linspace(0.0, 1.0, lc_bins + 1)
    counts, _ = np.histogram(lc.ravel(), bins=edges, weights=N.ravel())
    return t, diameter(s), solid, edges, counts


def plot_marginals(result, path: str, times_s=None, unit: str | None = None) -> str:
    """Two panels at several times: the solid marginal as the fraction of the solid volume per solid class over the
    solid-volume diameter (where the aggregates are), and the number fraction over the liquid content l / (s + l)."""
    from matplotlib.figure import Figure
    from matplotlib.ticker import NullFormatter, ScalarFormatter

    unit = _unit(result, unit)
    if times_s is None:
        times_s = [result.t[0], result.t[len(result.t) // 2], result.t[-1]]
    fig = Figure(figsize=(9.0, 3.6))
    a1, a2 = fig.subplots(1, 2)
    for t in times_s:
        tt, d, solid, edges, counts = marginals(result, t, unit)
        vol = solid * d ** 3
        a1.semilogx(d * 1e3, vol / vol.sum(), marker="o", ms=3, label=f"t = {tt:g} s")
        a2.step(edges[:-1], counts / counts.sum(), where="post", label=f"t = {tt:g} s")
    a1.xaxis.set_major_formatter(ScalarFormatter())
    a1.xaxis.set_minor_formatter(NullFormatter())
    a1.set_xlabel("solid diameter / mm")
    a1.set_ylabel("solid volume fraction per class")
    a1.set_title("solid marginal", fontsize=10)
    a2.set_xlabel("liquid content l / (s + l)")
    a2.set_ylabel("number fraction per 0.05")
    a2.set_title("liquid-content distribution", fontsize=10)
    for a in (a1, a2):
        a.grid(alpha=0.3)
        a.legend(fontsize=8)
    fig.subplots_adjust(left=0.08, right=0.98, bottom=0.14, top=0.91, wspace=0.3)
    fig.savefig(path, dpi=110)
    return path
