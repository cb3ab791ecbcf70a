"""Analysis of sweep tables: cube corners and main effects."""
from __future__ import annotations

import math
from typing import Iterable

from .runner import STATUS_OK


def corner_points(df, variables: Iterable[str] | None = None):
    """Boolean mask of the rows at a cube corner: every variable at its lowest or highest value in ``df``."""
    import numpy as np

    variables = list(variables if variables is not None else df.attrs.get("variables", {}))
    mask = np.ones(len(df), dtype=bool)
    for v in variables:
        col = df[v].to_numpy(dtype=float)
        lo, hi = np.nanmin(col), np.nanmax(col)
        mask &= np.isclose(col, lo) | np.isclose(col, hi)
    return mask


def main_effects(df, variables: Iterable[str] | None = None, outputs: Iterable[str] | None = None):
    """Main effect of each variable on each output over the cube corners of a two-level (or 3-level) design:
    mean of the output where the variable is at its high level minus the mean where it is at its low level.

    Only successful points count; a level with no successful corner gives NaN. Returns a DataFrame indexed by
    variable with one column per output; ``attrs["levels"]`` holds (low, high) per variable and
    ``attrs["n_corners"]`` the corners used.
    """
    import numpy as np
    import pandas as pd

    variables = list(variables if variables is not None else df.attrs.get("variables", {}))
    outputs = list(outputs if outputs is not None else df.attrs.get("outputs", []))
    if not variables or not outputs:
        raise ValueError("main_effects: name the variables and outputs (or pass a DataFrame from Sweep.run)")
    corners = df[corner_points(df, variables)]
    ok = corners[corners["status"] == STATUS_OK] if "status" in corners else corners
    rows, levels = {}, {}
    for v in variables:
        col = df[v].to_numpy(dtype=float)
        lo, hi = float(np.nanmin(col)), float(np.nanmax(col))
        levels[v] = (lo, hi)
        at_hi = np.isclose(ok[v].to_numpy(dtype=float), hi)
        at_lo = np.isclose(ok[v].to_numpy(dtype=float), lo)
        rows[v] = {o: (ok.loc[at_hi, o].astype(float).mean() - ok.loc[at_lo, o].astype(float).mean())
                   if at_hi.any() and at_lo.any() else math.nan for o in outputs}
    eff = pd.DataFrame.from_dict(rows, orient="index", columns=outputs)
    eff.index.name = "variable"
    eff.attrs["levels"] = levels
    eff.attrs["n_corners"] = int(len(ok))
    return eff
