"""Measured size distributions as calibration data: a Q3 curve measured at some times becomes one observation
``unit.Q3(<size>)`` per measured size (the model's cumulative mass fraction below it; docs/measured_psd.md), with an
absolute standard deviation of its own, beside the percentiles (d10, d50, d90) a calibration fits otherwise."""
from __future__ import annotations

import math
from typing import Sequence

import numpy as np

from ..measured_psd import q3_name
from .files import Observation

__all__ = ["q3_observations"]


def q3_observations(unit: str, sizes_m: Sequence[float], t_s: Sequence[float], q3: Sequence[Sequence[float]],
                    sigma_abs: float) -> list[Observation]:
    """Observations of a measured Q3 curve: ``q3[j][k]`` is the measured cumulative mass fraction (0..1; NaN: not
    measured) below ``sizes_m[k]`` at time ``t_s[j]``; ``sigma_abs`` its standard deviation, an absolute fraction
    (e.g. 0.02). One observation ``unit.Q3(size)`` per size, sampled at the times."""
    q = np.asarray(q3, dtype=float)
    t = np.asarray(t_s, dtype=float)
    if q.shape != (len(t), len(sizes_m)):
        raise ValueError(f"q3_observations: q3 has shape {q.shape}, expected (times, sizes) = "
                         f"({len(t)}, {len(sizes_m)})")
    if not (sigma_abs > 0 and math.isfinite(sigma_abs)):
        raise ValueError(f"q3_observations: sigma_abs = {sigma_abs}: violates 0 < sigma_abs < inf")
    out = []
    for k, s in enumerate(sizes_m):
        keep = np.isfinite(q[:, k])
        out.append(Observation(q3_name(unit, s), t[keep], q[keep, k], float(sigma_abs), 0.0))
    return out
