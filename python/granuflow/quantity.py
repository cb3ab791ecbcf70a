"""Quantities at the edges: numbers with units in scene, sweep and experiment files, command-line options, tables
and plots; SI everywhere inside.

This is the one module of the package that converts units. The factors come from the C++ core (``_core.to_si``,
which parses units with UDUNITS-2: prefixes, products, quotients and powers compose); this module adds parsing
(``"60 degC"``), the way back from SI to a display unit, differences (a standard deviation of 2 degC is one of 2 K)
and the edge units that fit an SI unit.
"""
from __future__ import annotations

import math
import sys

from . import _core
from .textfile import short

TYPE_CHECKING = False  # typing's own flag without importing typing (a plain run imports neither it nor NumPy)
if TYPE_CHECKING:
    import numpy as np

ConfigError = _core.ConfigError

# Edge units suggested for display (plots, tables, error messages), in this order; their factors come from the core.
EDGE_UNITS = ("-", "%", "K", "degC", "m", "mm", "um", "kg", "g", "s", "min", "h", "kg/s", "g/min", "g/s", "kg/h",
              "m3/s", "m3/h", "L/min", "kg/kg", "g/kg", "wt%", "W", "kW", "J", "kJ", "Pa", "kPa", "bar", "m/s",
              "kg/m3", "1/s", "1/min", "J/kg", "kJ/kg")


def real_types() -> tuple:
    """The types of a real number: int and float, and NumPy's integer and floating types once NumPy is loaded (no
    NumPy number exists before; the package imports NumPy only where a caller needs arrays)."""
    np = sys.modules.get("numpy")
    kinds = (getattr(np, "integer", None), getattr(np, "floating", None))
    return (int, float) + tuple(k for k in kinds if k is not None)


def integer_types() -> tuple:
    """int, and NumPy's integer types once NumPy is loaded."""
    k = getattr(sys.modules.get("numpy"), "integer", None)
    return (int,) if k is None else (int, k)


def bool_types() -> tuple:
    """bool, and NumPy's bool once NumPy is loaded."""
    k = getattr(sys.modules.get("numpy"), "bool_", None)
    return (bool,) if k is None else (bool, k)


def is_number(x: object) -> bool:
    """A finite real number (not a bool)."""
    return isinstance(x, real_types()) and not isinstance(x, bool) and math.isfinite(x)


def split(text: str, where: str = "") -> tuple[float, str]:
    """``"60 degC"`` -> ``(60.0, "degC")``; ``"1e-3"`` -> ``(0.001, "")``; a unit written on to the number
    (``"50um"``, ``"1e-3m"``) as the core's scene files and ``--set`` read it. ConfigError naming ``where``
    otherwise."""
    parsed = _core.parse_quantity(str(text).strip())  # the core's own reading (quantity.cpp), so both edges agree
    if parsed is not None:
        return parsed
    raise ConfigError(f"{where + ' = ' if where else ''}'{text}': expected a number, optionally followed by a "
                      "unit")


def number(value: object, where: str) -> float:
    """A plain number (or its text); ConfigError naming ``where`` otherwise."""
    if isinstance(value, str):
        try:
            return float(value)
        except ValueError:
            pass
    if isinstance(value, bool) or not isinstance(value, real_types()):
        raise ConfigError(f"{where} = {short(value)}: expected a number, optionally followed by a unit")
    return float(value)


def to_si(value: object, si_unit: str, where: str = "value", unit: str = "") -> float:
    """A number in ``unit`` (SI when empty), or a string ``"value unit"``, in ``si_unit``."""
    if isinstance(value, str):
        v, u = split(value, where)
        return _core.to_si(v, u or unit, si_unit, where)
    return _core.to_si(number(value, where), unit, si_unit, where)


def difference_to_si(value: object, si_unit: str, where: str, unit: str = "") -> float:
    """A difference (a standard deviation, a tolerance) in SI: offsets such as degC -> K cancel."""
    if isinstance(value, str):
        v, u = split(value, where)
        u = u or unit
    else:
        v, u = number(value, where), unit
    return _core.to_si(v, u, si_unit, where) - _core.to_si(0.0, u, si_unit, where)


def affine(unit: str, si_unit: str, where: str = "unit") -> tuple[float, float]:
    """``(a, b)`` with SI value = a + b * value in ``unit`` (edge units are affine in SI, e.g. degC)."""
    a = _core.to_si(0.0, unit, si_unit, where)
    return a, _core.to_si(1.0, unit, si_unit, where) - a


def fits(unit: str, si_unit: str) -> bool:
    """True if ``unit`` converts to ``si_unit``."""
    try:
        _core.to_si(1.0, unit, si_unit, "unit")
        return True
    except ConfigError:
        return False


def from_si(values, unit: str, si_unit: str) -> np.ndarray:
    """SI values in ``unit``."""
    import numpy as np

    if not unit or unit == si_unit:
        return np.asarray(values, dtype=float)
    a, b = affine(unit, si_unit)
    return (np.asarray(values, dtype=float) - a) / b


def from_si_value(value: float, unit: str, si_unit: str) -> float:
    """One SI value in ``unit``: :func:`from_si` of a number, the same operations, without NumPy."""
    if not unit or unit == si_unit:
        return float(value)
    a, b = affine(unit, si_unit)
    return (float(value) - a) / b


def display_units(si_unit: str | None = None) -> list[str]:
    """The edge units offered for ``si_unit`` (all of them when None)."""
    if si_unit is None:
        return list(EDGE_UNITS)
    out = [u for u in EDGE_UNITS if fits(u, si_unit)]
    return out if si_unit in out else [si_unit] + out


def conversion(unit: str, si_unit: str) -> tuple[float, float]:
    """``(factor, offset)`` with display = SI * factor + offset; ValueError for a unit that does not fit ``si_unit``
    (the message lists the ones that do)."""
    if unit in ("", None) or unit == si_unit:
        return 1.0, 0.0
    if not fits(unit, si_unit):
        allowed = ", ".join(display_units(si_unit)) or si_unit or "-"
        if not any(fits(unit, s) for s in EDGE_UNITS):
            raise ValueError(f"unknown unit '{unit}' (allowed for {si_unit or '-'}: {allowed})")
        raise ValueError(f"unit '{unit}' does not fit a series in {si_unit or '-'} (allowed: {allowed})")
    a, b = affine(unit, si_unit)
    return 1.0 / b, -a / b


def convert(values, unit: str, si_unit: str) -> np.ndarray:
    """SI values in the display ``unit`` (ValueError for a unit of another dimension)."""
    import numpy as np

    f, o = conversion(unit, si_unit)
    return np.asarray(values, dtype=float) * f + o


def parse_time(value: object, where: str) -> float:
    """Seconds from a number (s) or a string with a time unit (``"60 min"``)."""
    if is_number(value):
        return float(value)
    if isinstance(value, str):
        try:
            v, u = split(value, where)
        except ConfigError:
            v, u = None, ""
        if v is not None:
            return _core.to_si(v, u, "s", where)
    raise ConfigError(f"{where} = {short(value)}: expected seconds or a number with a time unit (e.g. '60 min')")


def si_or_nan(value: object, si_unit: str, where: str = "value") -> float:
    """``to_si`` where it can be read, else NaN (for recording what a failed point asked for)."""
    try:
        return to_si(value, si_unit, where)
    except ConfigError:
        return math.nan


def show(x: object) -> str:
    """A value as the user wrote it: numbers short (10, 0.5, inf), text quoted."""
    if isinstance(x, real_types()) and not isinstance(x, bool):
        return f"{float(x):g}"
    return repr(x)


def label(name: str, unit: str) -> str:
    """A column header with its unit: ``bed.T [K]``, ``bed.moisture [kg/kg]``, ``x [-]``; the name alone without one."""
    return f"{name} [{unit}]" if unit else name


_PRETTY = {"um": "µm", "degC": "°C", "m3/h": "m³/h", "m3/s": "m³/s", "m3": "m³", "kg/m3": "kg/m³", "m2": "m²"}


def pretty(unit: str) -> str:
    """A unit as typeset in plot labels: ``um`` -> ``µm``, ``degC`` -> ``°C``."""
    return _PRETTY.get(unit, unit)
