"""The constant-volume Monte Carlo of spray fluidized-bed agglomeration (paper 003, section 7.7; docs/monte_carlo.md).

``run(params, settings, times)`` follows every particle and every deposited droplet in independent replicas (in
parallel, replica i seeded from (seed, i)) and returns a :class:`MonteCarloResult`: every recorded quantity at every
output time with its 95 % confidence interval over the replicas, the mass distribution over agglomerate sizes, and
the cost (events per second, bytes per particle). ``params()`` and ``settings()`` list the declaration (SI unit,
bounds, source). A scene file with ``engine: monte_carlo`` runs it from the command line (granuflow.montecarlo.scene).
"""
from __future__ import annotations

import csv
import math
from typing import Any, Mapping, Sequence

import numpy as np

from .. import _core
from ..quantity import ConfigError, to_si

__all__ = ["run", "params", "settings", "si_params", "MonteCarloResult", "analytic_constant_kernel"]

# Known SI units of the checked table; the declaration's other units (rad, N/m) take plain SI numbers.
_PLAIN_UNITS = ("rad", "N/m")


def params() -> list[dict]:
    """Every parameter: name, unit (SI), default, lower, upper, description, source."""
    return list(_core.montecarlo_params())


def settings() -> list[dict]:
    """Every setting: name, type, default, choices, bounds, description (the open points of paper 003 section 7.7)."""
    return list(_core.montecarlo_settings())


def si_params(values: Mapping[str, Any] | None, where: str) -> dict[str, float]:
    """Parameters by name in SI (numbers, or "value unit" text); ConfigError naming an unknown one."""
    specs = {p["name"]: p for p in params()}
    out = {}
    for name, value in (values or {}).items():
        spec = specs.get(name)
        if spec is None:
            raise ConfigError(f"{where}.{name}: not a Monte Carlo parameter; known: {', '.join(specs)}")
        if spec["unit"] in _PLAIN_UNITS:
            if isinstance(value, str) or isinstance(value, bool) or not isinstance(value, (int, float)):
                raise ConfigError(f"{where}.{name} = {value!r}: expected a plain number in {spec['unit']} (SI)")
            out[name] = float(value)
        else:
            out[name] = to_si(value, spec["unit"], f"{where}.{name}")
    return out


def _settings_text(values: Mapping[str, Any] | None) -> dict[str, str]:
    out = {}
    for name, value in (values or {}).items():
        if isinstance(value, bool):  # YAML's on/off
            value = "on" if value else "off"
        out[str(name)] = str(value)
    return out


def analytic_constant_kernel(tau) -> tuple[np.ndarray, np.ndarray]:
    """Monodisperse start, constant kernel (Smoluchowski; Scott 1968): M0/N0 = 1/(1 + tau/2), M2/(N0 v0^2) = 1 + tau,
    tau = beta0 c0 t."""
    tau = np.asarray(tau, dtype=float)
    return 1.0 / (1.0 + tau / 2.0), 1.0 + tau


class MonteCarloResult:
    """Means and 95 % intervals over the replicas at the output times ``t`` (s); quantities per primary particle."""

    def __init__(self, raw: dict, params_si: dict, settings_text: dict):
        self.raw = raw
        self.t = np.asarray(raw["times"], dtype=float)
        self.names = list(raw["quantities"])
        shape = (len(self.t), len(self.names))
        self._mean = np.asarray(raw["mean"], dtype=float).reshape(shape)
        self._lo = np.asarray(raw["lo"], dtype=float).reshape(shape)
        self._hi = np.asarray(raw["hi"], dtype=float).reshape(shape)
        bins = raw["psd_bins"]
        self.psd_mean = np.asarray(raw["psd_mean"], dtype=float).reshape(len(self.t), bins)
        self.psd_lo = np.asarray(raw["psd_lo"], dtype=float).reshape(len(self.t), bins)
        self.psd_hi = np.asarray(raw["psd_hi"], dtype=float).reshape(len(self.t), bins)
        self.per_replica = np.asarray(raw["per_replica"], dtype=float).reshape(raw["replicas"], *shape)
        self.params = params_si
        self.settings = settings_text
        self.derived = dict(raw["derived"])

    def _col(self, name: str) -> int:
        if name not in self.names:
            raise ConfigError(f"Monte Carlo quantity '{name}': known are {', '.join(self.names)}")
        return self.names.index(name)

    def mean(self, name: str) -> np.ndarray:
        return self._mean[:, self._col(name)]

    def ci(self, name: str) -> tuple[np.ndarray, np.ndarray]:
        """Lower and upper bound of the 95 % confidence interval over the replicas."""
        k = self._col(name)
        return self._lo[:, k], self._hi[:, k]

    def at(self, name: str, t: float) -> dict:
        """{mean, lo, hi} at the output time nearest t (null with a reason where undefined)."""
        k = int(np.argmin(np.abs(self.t - t)))
        return _value(self.mean(name)[k], *(b[k] for b in self.ci(name)), t=float(self.t[k]))

    def psd_edges_primaries(self) -> np.ndarray:
        """Bin edges of the distribution, in primary particles per agglomerate: 1, 2, 4, ... (bins [2^k, 2^(k+1)))."""
        return 2.0 ** np.arange(self.psd_mean.shape[1] + 1)

    def psd_edges_diameter(self) -> np.ndarray:
        """The same edges as agglomerate diameters, m (constant porosity; a single primary keeps d0)."""
        n = self.psd_edges_primaries()
        d0, eps = self.params.get("d0", _default("d0")), self.params.get("eps_agg", _default("eps_agg"))
        return np.where(n <= 1, d0, d0 * np.cbrt(n / (1.0 - eps)))

    @property
    def summary(self) -> dict:
        r = self.raw
        out = {"engine": "monte_carlo", "t_end_s": float(self.t[-1]), "replicas": r["replicas"],
               "threads": r["threads"], "confidence": "95 % interval of the mean over the replicas (Student's t)"}
        for name in ("d_mean_over_d0", "d50_over_d0", "number", "m2", "dried_unused_share", "used_share",
                     "blocked_share", "droplets_deposited"):
            out[name] = _value(self.mean(name)[-1], self.ci(name)[0][-1], self.ci(name)[1][-1])
        out["cost"] = {"events": r["events"], "collisions": r["collisions"], "successes": r["successes"],
                       "droplets": r["depositions"], "events_per_s_per_core": r["events_per_s"],
                       "bytes_per_primary_particle": r["bytes_per_particle"],
                       "bytes_per_agglomerate_slot": r["bytes_per_agglomerate"],
                       "bytes_per_droplet_slot": r["bytes_per_droplet"], "wall_time_s": r["wall_s"],
                       "doublings_mean": r["doublings_mean"]}
        out["derived"] = {k: (None if not math.isfinite(v) else v) for k, v in self.derived.items()}
        if not math.isfinite(self.derived["t_life"]):
            out["derived_reasons"] = {"t_life": "droplets never stop being wet (no drying, no imbibition)"}
        out["settings"] = dict(self.settings)
        return out

    def to_csv(self, path: str) -> None:
        """Time series: t_s, then every quantity's mean, lo and hi (empty where undefined)."""
        with open(path, "w", newline="") as f:
            w = csv.writer(f)
            w.writerow(["t_s"] + [f"{n}{s}" for n in self.names for s in ("", "_lo", "_hi")])
            for k, t in enumerate(self.t):
                row = [repr(float(t))]
                for j in range(len(self.names)):
                    row += [_cell(self._mean[k, j]), _cell(self._lo[k, j]), _cell(self._hi[k, j])]
                w.writerow(row)

    def psd_to_csv(self, path: str) -> None:
        """Mass fractions over agglomerate sizes at every output time, with their intervals."""
        n, d = self.psd_edges_primaries(), self.psd_edges_diameter()
        with open(path, "w", newline="") as f:
            w = csv.writer(f)
            w.writerow(["t_s", "n_from", "n_to", "d_from_m", "d_to_m", "mass_fraction", "lo", "hi"])
            for k, t in enumerate(self.t):
                for b in range(self.psd_mean.shape[1]):
                    w.writerow([repr(float(t)), int(n[b]), int(n[b + 1]), repr(float(d[b])), repr(float(d[b + 1])),
                                _cell(self.psd_mean[k, b]), _cell(self.psd_lo[k, b]), _cell(self.psd_hi[k, b])])


def _cell(v: float) -> str:
    return repr(float(v)) if math.isfinite(v) else ""


def _value(mean: float, lo: float, hi: float, t: float | None = None) -> dict:
    out = {} if t is None else {"t_s": t}
    if not math.isfinite(mean):
        out.update(value=None, reason="undefined: no droplet deposited yet")
        return out
    out.update(value=float(mean), ci95=[float(lo), float(hi)] if math.isfinite(lo) else None)
    return out


def _default(name: str) -> float:
    return next(p["default"] for p in params() if p["name"] == name)


def run(params: Mapping[str, Any] | None = None, settings: Mapping[str, Any] | None = None,
        times: Sequence[float] | None = None, *, t_end: Any = None, n_out: int = 31) -> MonteCarloResult:
    """Run the replicas. ``params``: name -> value (SI number or "value unit"); ``settings``: name -> choice or count
    (see settings()); output ``times`` in s, or ``n_out`` evenly spaced times up to ``t_end`` (s or "60 s")."""
    p_si = si_params(params, "params")
    s_text = _settings_text(settings)
    if times is None:
        if t_end is None:
            raise ConfigError("montecarlo.run: give the output times or t_end")
        end = to_si(t_end, "s", "t_end")
        if not (math.isfinite(end) and end > 0):
            raise ConfigError(f"t_end = {t_end!r}: expected a time > 0")
        if isinstance(n_out, bool) or not isinstance(n_out, int) or n_out < 2:
            raise ConfigError(f"n_out = {n_out!r}: expected a whole number >= 2")
        times = np.linspace(0.0, end, n_out)
    times = [float(t) for t in times]
    return MonteCarloResult(_core.montecarlo_run(p_si, s_text, times), p_si, s_text)
