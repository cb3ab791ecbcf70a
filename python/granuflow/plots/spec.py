"""The `plots:` list of a scene file: schema and checks before a run."""
from __future__ import annotations

import math
import os

from .. import _core
from ..quantity import conversion, display_units
from ..textfile import short

ConfigError = _core.ConfigError

_SERIES_KEYS = ("title", "y", "unit", "ylabel", "file")
_PSD_KEYS = ("kind", "times_min", "file")


def _plot_file(name, where: str, formats: list[str] | None) -> str:
    """A plot's `file:`: a plain file name (no folder) with an extension matplotlib writes (not checked when
    ``formats`` is None: no plots are drawn)."""
    if not isinstance(name, str) or not name.strip():
        raise ConfigError(f"{where} = {short(name)}: expected a file name such as plot.png")
    if name != os.path.basename(name) or "/" in name or "\\" in name or name in (".", "..") or os.path.isabs(name):
        raise ConfigError(f"{where} = '{name}': expected a plain file name inside the output folder "
                          "(no folder part, e.g. plot.png)")
    ext = os.path.splitext(name)[1].lstrip(".").lower()
    if formats is not None and ext not in formats:
        raise ConfigError(f"{where} = '{name}': extension '{ext}' is not an image format matplotlib writes "
                          f"(allowed: {', '.join(formats)})")
    return name


def plot_specs(fs, *, drawing: bool = True) -> list[dict]:
    """The scene's ``plots:`` list, checked before the run: each ``kind: psd`` (``times_min`` within the scene's
    t_end; a shorter ``--t-end`` leaves the later times out of the plot and says so) or
    with ``y``, a list of names, and a ``unit`` that fits them; ``file`` a plain image file name (with an extension
    matplotlib writes, checked only when ``drawing``: that needs matplotlib). Raises ConfigError naming the key."""
    specs = fs.extra.get("plots") or []
    where = f"{fs.path or fs.name}: plots"
    if not isinstance(specs, list):
        raise ConfigError(f"{where}: expected a list of plot mappings, got {short(specs)}")
    known = set(fs.state_names) | set(fs.output_names)
    formats = None
    if specs and drawing:
        from .series import supported_formats

        formats = supported_formats()
    t_end_min = fs.t_end / 60.0
    for k, spec in enumerate(specs):
        w = f"{where}[{k}]"
        if isinstance(spec, dict) and "kind" in spec:
            if spec["kind"] != "psd":
                raise ConfigError(f"{w}.kind = {short(spec['kind'])}: not one of psd (or leave kind out and give y)")
            for key in spec:
                if key not in _PSD_KEYS:
                    raise ConfigError(f"{w}: unknown key '{key}' (allowed for kind psd: {', '.join(_PSD_KEYS)})")
            if "file" in spec:
                _plot_file(spec["file"], f"{w}.file", formats)
            if "times_min" in spec:
                times = spec["times_min"]
                if not isinstance(times, list) or not times:
                    raise ConfigError(f"{w}.times_min = {short(times)}: expected a non-empty list of times in minutes")
                for i, t in enumerate(times):
                    ok = isinstance(t, (int, float)) and not isinstance(t, bool) and math.isfinite(t)
                    if not ok or not 0 <= t <= t_end_min * (1 + 1e-12):
                        raise ConfigError(f"{w}.times_min[{i}] = {short(t)}: expected a time in minutes within "
                                          f"[0, {t_end_min:g}] (the scene's t_end)")
            continue
        if not isinstance(spec, dict) or not isinstance(spec.get("y"), list):
            raise ConfigError(f"{w} = {short(spec)}: expected a mapping with y: [state or output names] "
                              "(or kind: psd)")
        for key in spec:
            if key not in _SERIES_KEYS:
                raise ConfigError(f"{w}: unknown key '{key}' (allowed: {', '.join(_SERIES_KEYS)}; or kind: psd)")
        unit = spec.get("unit", "")
        if unit is None:
            unit = ""
        if not isinstance(unit, str):
            raise ConfigError(f"{w}.unit = {short(unit)}: expected a unit name (allowed: {', '.join(display_units())})")
        for n in spec["y"]:
            if n not in known:
                raise ConfigError(f"{w}.y: '{n}' is neither a state nor an output of scene '{fs.name}'")
            try:
                conversion(unit, fs.unit_of(n))
            except ValueError as e:
                raise ConfigError(f"{w}.unit = '{unit}' for {n}: {e}") from None
        if "file" in spec:
            _plot_file(spec["file"], f"{w}.file", formats)
    return specs
