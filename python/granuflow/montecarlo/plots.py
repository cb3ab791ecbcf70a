"""Plots of a Monte Carlo result: d/d0 over time with its confidence band, and the mass distribution over
agglomerate sizes at a few output times (matplotlib imported only here)."""
from __future__ import annotations

import numpy as np

from ..quantity import from_si
from . import MonteCarloResult


def plot_growth(res: MonteCarloResult, path: str | None = None, ax=None, label: str | None = None):
    """d_mean/d0 and d50/d0 with their 95 % bands over the replicas."""
    import matplotlib

    if ax is None:
        matplotlib.use("Agg") if path else None
        import matplotlib.pyplot as plt

        fig, ax = plt.subplots(figsize=(6.4, 4.4))
    else:
        fig = None
    for name, style in (("d_mean_over_d0", "-"), ("d50_over_d0", "--")):
        lo, hi = res.ci(name)
        line, = ax.plot(res.t, res.mean(name), style, label=f"{label + ': ' if label else ''}{name}")
        ax.fill_between(res.t, lo, hi, color=line.get_color(), alpha=0.25, lw=0)
    ax.set_xlabel("t / s")
    ax.set_ylabel("d / d0")
    ax.set_title("Monte Carlo agglomeration (95 % band over the replicas)")
    ax.legend(fontsize=8)
    if fig is not None and path:
        fig.tight_layout()
        fig.savefig(path, dpi=110)
        import matplotlib.pyplot as plt

        plt.close(fig)
    return ax


def plot_psd(res: MonteCarloResult, path: str, n_times: int = 4) -> None:
    """Mass fraction per size class (bins of 2^k primaries) at n_times output times, with the 95 % bars."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    d = from_si(res.psd_edges_diameter(), "um", "m")
    mid = np.sqrt(d[:-1] * d[1:])
    used = np.nonzero(res.psd_mean.max(axis=0) > 0)[0]
    last = (used.max() + 1) if used.size else 1
    fig, ax = plt.subplots(figsize=(6.4, 4.4))
    for k in np.unique(np.linspace(0, len(res.t) - 1, n_times).round().astype(int)):
        m = res.psd_mean[k, :last]
        err = np.vstack([m - res.psd_lo[k, :last], res.psd_hi[k, :last] - m])
        ax.errorbar(mid[:last], m, yerr=np.nan_to_num(err), marker="o", capsize=2, label=f"t = {res.t[k]:g} s")
    ax.set_xscale("log")
    ax.set_xlabel("agglomerate diameter / um (classes of 2^k primaries)")
    ax.set_ylabel("mass fraction")
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
