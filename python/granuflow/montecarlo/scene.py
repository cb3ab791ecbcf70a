"""Scene files of the Monte Carlo: a YAML file with ``engine: monte_carlo`` (docs/monte_carlo.md, docs/scene_format.md)

    scene: NAME
    description: TEXT
    engine: monte_carlo
    t_end: 60 s
    output: {n: 31}            # or {times: [0 s, 10 s, ...]}
    monte_carlo:
      settings: {sample_size: 2000, replicas: 16, seed: 1, stokes_length: radius, ...}
      params: {F_coll: 10 1/m, d0: 0.4 mm, ...}

Anything else is refused with one line naming the key and what is allowed."""
from __future__ import annotations

import math
import os
from typing import Any

import numpy as np

from ..quantity import ConfigError, to_si
from ..textfile import load_yaml, short
from . import MonteCarloResult, params, run, settings, si_params

ENGINE = "monte_carlo"
_TOP_KEYS = ("scene", "description", "engine", "t_end", "output", "monte_carlo")


def is_scene(path: str | os.PathLike) -> bool:
    """Whether the scene file asks for this engine (anything unreadable is left to the usual loader's message)."""
    try:
        doc = load_yaml(path, "scene file")
    except (ConfigError, OSError, UnicodeError, RecursionError):
        return False
    return isinstance(doc, dict) and doc.get("engine") == ENGINE


class Scene:
    """A Monte Carlo scene read from its file: name, description, params and settings by name, output times."""

    def __init__(self, path: str | os.PathLike):
        doc = load_yaml(path, "scene file")
        where = os.fspath(path)
        if not isinstance(doc, dict):
            raise ConfigError(f"{where}: a scene is a mapping of keys ({', '.join(_TOP_KEYS)})")
        for key in doc:
            if key not in _TOP_KEYS:
                raise ConfigError(f"{where}: key '{short(key)}' is not part of a monte_carlo scene; allowed: "
                                  f"{', '.join(_TOP_KEYS)}")
        if doc.get("engine") != ENGINE:
            raise ConfigError(f"{where}: engine = {short(doc.get('engine'))}: expected {ENGINE}")
        self.name = str(doc.get("scene") or os.path.splitext(os.path.basename(where))[0])
        self.description = str(doc.get("description", ""))
        self.t_end = to_si(doc.get("t_end", "60 s"), "s", f"{where}: t_end")
        if not (math.isfinite(self.t_end) and self.t_end > 0):
            raise ConfigError(f"{where}: t_end = {short(doc.get('t_end'))}: expected a time > 0")
        self.times = self._times(doc.get("output") or {"n": 31}, where)
        mc = doc.get("monte_carlo") or {}
        if not isinstance(mc, dict) or any(k not in ("params", "settings") for k in mc):
            raise ConfigError(f"{where}: monte_carlo holds 'params' and 'settings' (mappings), got {short(mc)}")
        self.params = dict(mc.get("params") or {})
        self.settings = dict(mc.get("settings") or {})
        for what, block in (("params", self.params), ("settings", self.settings)):
            if not isinstance(block, dict):
                raise ConfigError(f"{where}: monte_carlo.{what} must be a mapping of names to values")

    def _times(self, output: Any, where: str) -> list[float]:
        if not isinstance(output, dict) or len(output) != 1 or not ({"n", "times"} & set(output)):
            raise ConfigError(f"{where}: output = {short(output)}: expected {{n: COUNT}} or {{times: [...]}}")
        if "n" in output:
            n = output["n"]
            if isinstance(n, bool) or not isinstance(n, int) or n < 2:
                raise ConfigError(f"{where}: output.n = {short(n)}: expected a whole number >= 2")
            return [float(t) for t in np.linspace(0.0, self.t_end, n)]
        times = [to_si(t, "s", f"{where}: output.times") for t in output["times"] or []]
        if not times or any(b < a for a, b in zip(times, times[1:])) or times[0] < 0 or times[-1] > self.t_end:
            raise ConfigError(f"{where}: output.times must ascend within [0, t_end]")
        return times

    def apply_sets(self, sets: dict[str, str]) -> None:
        """``--set monte_carlo.NAME=VALUE`` (or NAME=VALUE): a parameter or a setting by its name."""
        p_names = {p["name"] for p in params()}
        s_names = {s["name"] for s in settings()}
        for key, value in sets.items():
            name = key.split(".", 1)[1] if key.startswith(f"{ENGINE}.") else key
            if name in p_names:
                self.params[name] = _plain(value)
            elif name in s_names:
                self.settings[name] = value
            else:
                raise ConfigError(f"--set {key}: not a Monte Carlo parameter or setting; parameters: "
                                  f"{', '.join(sorted(p_names))}; settings: {', '.join(sorted(s_names))}")

    def describe_rows(self) -> list[dict]:
        """The parameters as ``granuflow describe`` lists a flowsheet's: value in SI, default, bounds, source."""
        given = si_params(self.params, "monte_carlo.params")
        return [{"param": f"{ENGINE}.{p['name']}", "value": given.get(p["name"], p["default"]), "unit": p["unit"],
                 "default": p["default"], "lower": p["lower"], "upper": p["upper"], "input": False,
                 "source": p["source"], "description": p["description"]} for p in params()]

    def run(self, t_end: float | None = None) -> MonteCarloResult:
        times = self.times
        if t_end is not None:
            times = [float(t) for t in np.linspace(0.0, t_end, len(times))]
        return run(self.params, self.settings, times)


def _plain(text: str) -> Any:
    try:
        return float(text)
    except ValueError:
        return text
