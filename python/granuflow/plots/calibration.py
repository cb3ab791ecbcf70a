"""Parity plots of a calibration: model against data per observable group, in the units people read."""
from __future__ import annotations

import math
import os

import numpy as np

from .. import outputs
from ..quantity import from_si, pretty
from .series import figure


def parity_plots(predictions: dict, fit_rows: list[dict], out_dir: str, *, units: dict,
                 groups: dict | None = None) -> list[str]:
    """One PNG per observable group (size, moisture, outlet gas temperature; ``groups`` from
    ``outputs.observable_groups`` of the scene's summary declarations) with the data sets of ``predictions`` (set name
    -> predictions) as markers and R² from ``fit_rows`` in the legend; ``units``: SI unit per observable. Observables
    outside those groups (another scene's, e.g. ``drying.sigma`` of paper 003's two-zone bed) get one PNG each,
    lengths shown in µm."""
    os.makedirs(out_dir, exist_ok=True)
    written = []
    groups = groups or {}
    grouped = {m for members in groups.values() for m in members}
    others = sorted({p["observable"] for preds in predictions.values() for p in preds} - grouped)
    panels = [(g, members, outputs.GROUP_TITLES[g]) for g, members in groups.items()]
    panels += [(o, (o,), o) for o in others]
    for group, members, title in panels:
        fig, ax = figure((4.6, 4.4))
        lo, hi, any_pts = math.inf, -math.inf, False
        shown = ""
        for (setname, preds), marker in zip(predictions.items(), ("o", "^", "s")):
            d, m = [], []
            for p in preds:
                if p["observable"] in members:
                    si = units.get(p["observable"], "")
                    shown = (outputs.observable_display(p["observable"], groups) or ("um" if si == "m" else si)
                             if si else "")
                    d.append(from_si(p["data"], shown, si))
                    m.append(from_si(p["model"], shown, si))
            if not d:
                continue
            d, m = np.concatenate(d), np.concatenate(m)
            r2 = next((r["r2"] for r in fit_rows if r["set"] == setname and r["output"] == group), math.nan)
            ax.scatter(d, m, s=9, marker=marker, alpha=0.6, label=f"{setname} (R² {r2:.3f})")
            lo, hi, any_pts = min(lo, np.nanmin(d), np.nanmin(m)), max(hi, np.nanmax(d), np.nanmax(m)), True
        if not any_pts:
            continue
        ax.plot([lo, hi], [lo, hi], "k-", lw=0.8)
        ax.set_xlabel(f"measured / {pretty(shown)}" if shown else "measured")
        ax.set_ylabel(f"model / {pretty(shown)}" if shown else "model")
        ax.set_title(title)
        ax.legend(fontsize=8)
        fig.tight_layout()
        name = os.path.join(out_dir, f"parity_{group}.png")
        fig.savefig(name, dpi=110)
        written.append(name)
    return written
