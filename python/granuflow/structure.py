"""Settings overrides: a unit's settings (size classes, a kernel's name, a mechanism on or off) shape the structure
of a flowsheet, so changing one rebuilds the flowsheet from its scene text with the setting changed. The values
are checked by the scene loader exactly as if the scene file gave them (same one-line messages), and parameter
values set on the old flowsheet carry over where the new one has the same parameter.

A name ``unit.key`` given as ``--set``, a sweep variable or a contour axis is a setting when the unit declares
a setting ``key`` (``granuflow describe`` lists them) and no parameter of that name. One name is both in some
units (``bed_mass`` of a continuous granulator: the setting ``free | controlled`` and the parameter in kg): a value
among the setting's choices sets the setting, any other the parameter."""
from __future__ import annotations

import json
from collections.abc import Mapping

from . import _core
from .quantity import is_number
from .textfile import short

ConfigError = _core.ConfigError


def setting_spec(fs, name: str) -> dict | None:
    """The declared setting ``unit.key`` of ``fs`` ({name, type, value, choices, lower, upper, description}), or
    None."""
    unit, _, key = name.partition(".")
    for s in fs.setting_specs().get(unit, []):
        if s["name"] == key:
            return s
    return None


def is_setting(fs, name: str, value=None) -> bool:
    """True when ``name`` (with ``value``, if given) addresses a setting of ``fs`` rather than a parameter: a setting
    the unit declares that is not also a parameter, or a name that is both whose ``value`` is one of the setting's
    choices. A name that is neither is taken for a (misspelt) parameter."""
    if not isinstance(name, str) or "." not in name:
        return False
    spec = setting_spec(fs, name)
    if spec is None:
        return False
    if name not in fs.params:
        return True
    return isinstance(value, str) and value.strip() in spec["choices"]


def split(fs, values: Mapping) -> tuple[dict, dict]:
    """``values`` as (settings, parameters), by :func:`is_setting`. A name the unit does not declare, of a unit
    whose declared settings are changed too, is a setting (``particles.grid=geometric`` with ``particles.q=4``:
    a setting read only under another choice); the loader checks it. A name that is both a parameter and a
    setting, with a value that fits neither, is refused naming both."""
    settings, params = {}, {}
    for k, v in values.items():
        if is_setting(fs, k, v):
            settings[k] = v
            continue
        spec = setting_spec(fs, k) if k in fs.params else None
        if spec is not None and spec["choices"] and isinstance(v, str) and not _numeric(v):
            raise ConfigError(f"{k} = {short(v)}: {k} is both a parameter ({fs.spec(k)['unit']}) and a setting "
                              f"({', '.join(spec['choices'])}) of unit {k.partition('.')[0]}; give a number with a "
                              f"unit for the parameter or one of {', '.join(spec['choices'])} for the setting")
        params[k] = v
    rebuilt = {str(k).partition(".")[0] for k in settings}
    for k in [k for k in params if isinstance(k, str) and k not in fs.params and k.partition(".")[0] in rebuilt]:
        settings[k] = params.pop(k)
    return settings, params


def _numeric(text: str) -> bool:
    from .quantity import split as split_quantity

    try:
        split_quantity(text, "value")
        return True
    except ConfigError:
        return False


def setting_text(value) -> str:
    """A setting value as the scene text holds it: booleans as true/false, numbers as Python writes them."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if is_number(value):
        return repr(int(value)) if float(value).is_integer() and not isinstance(value, float) else repr(value)
    if isinstance(value, str):
        return value.strip()
    raise ConfigError(f"setting value {short(value)}: expected a number, a string or true/false")


def with_settings(fs, settings: Mapping, where: str = "settings"):
    """A new flowsheet: the scene text of ``fs`` with ``settings`` ({"unit.key": value}) changed, built again, with
    every parameter value of ``fs`` the new flowsheet also has, and its end time. ``where`` names the source in
    messages (``--set``). ConfigError as the scene loader gives it, for the setting named."""
    if not settings:
        return fs
    by_unit: dict[str, dict] = {}
    for name, value in settings.items():
        unit, dot, key = str(name).partition(".")
        if not dot or not key:
            raise ConfigError(f"{where} {name}: expected unit.setting")
        if unit not in fs.unit_settings():
            raise ConfigError(f"{where} {name}: no unit '{unit}' in scene '{fs.name}' (units: "
                              f"{', '.join(fs.unit_settings())})")
        by_unit.setdefault(unit, {})[key] = setting_text(value)
    for unit, values in by_unit.items():
        for key, value in values.items():
            values[key] = si_text(fs, f"{unit}.{key}", value, where)
    text = fs.text
    label = fs.path or fs.name
    for unit, values in by_unit.items():
        text = splice_settings(text, unit, values, label)
    shown = ", ".join(f"{k}={setting_text(v)}" for k, v in settings.items())
    try:
        new = fs.from_text(text)
    except ConfigError as e:
        raise ConfigError(f"{where} {shown}: {_explain(fs, str(e), label)}") from None
    copy_common_values(new, fs)
    new.set_t_end(fs.t_end)
    return new


def setting_si_unit(spec: dict) -> str:
    """The SI unit of a real setting: the core declares it in the description, after a comma ("largest pivot
    diameter, m (Table 5)"); "" for a plain number. The core's reading, the one its scene files use."""
    if spec.get("type") != "number":
        return ""
    return _core.setting_si_unit(spec.get("description", ""))


def si_text(fs, name: str, text: str, where: str) -> str:
    """A real setting given with a unit ("3 mm") as its SI value, converted here at the edge; anything else as
    given (the loader checks it)."""
    from .quantity import split as split_quantity, to_si

    spec = setting_spec(fs, name)
    if spec is None or spec["type"] != "number":
        return text
    try:
        _, unit = split_quantity(text, name)
    except ConfigError:
        return text  # not a number: the loader names what is expected
    if not unit:
        return text
    si = setting_si_unit(spec)
    if not si:
        raise ConfigError(f"{where} {name} = '{text}': expected a plain number (this setting has no unit)")
    try:
        return repr(to_si(text, si, f"{where} {name}"))
    except ConfigError:
        raise ConfigError(f"{where} {name} = '{text}': unit '{unit}' does not fit the setting's SI unit {si} (e.g. "
                          f"'3 mm' for a length in m)") from None


def _explain(fs, message: str, label: str) -> str:
    """The loader's message without the file's name (the file is fine; the override is not), an unknown setting
    also naming the unit's parameters (the name may be a misspelt parameter)."""
    message = " ".join(message.split())
    if message.startswith(label + ": "):
        message = message[len(label) + 2:]
    if "unknown setting" in message:
        unit = message.split(".settings.")[0].replace("units.", "")
        params = [p.partition(".")[2] for p in fs.params if p.partition(".")[0] == unit]
        if params:
            message += f"; parameters of {unit}: {', '.join(params)}"
    return message


def copy_common_values(new, old) -> None:
    """The constant parameter values of ``old`` that ``new`` also has (a setting may add or remove a kernel's
    parameters), links respected."""
    pending = [(p, old.spec(p)["value"]) for p in old.params if p in set(new.params) and not old.spec(p).get("input")]
    for _ in range(2):  # a link target follows its source: set it after the source
        failed = []
        for p, v in pending:
            try:
                new.set(p, v)
            except ConfigError:
                failed.append((p, v))
        pending = failed
    for p, v in pending:
        new.set(p, v)  # raises, naming the parameter


def apply(fs, values: Mapping, where: str = "--set"):
    """``fs`` with ``values`` ({"unit.name": value}) applied: settings by rebuilding (a new flowsheet), then
    parameters. Returns the flowsheet to use (``fs`` itself when no setting is given)."""
    settings, params = split(fs, values)
    fs = with_settings(fs, settings, where)
    for k, v in params.items():
        try:
            fs.set(k, v)
        except ConfigError as e:
            unit = str(k).partition(".")[0]
            names = [s["name"] for s in fs.setting_specs().get(unit, [])] if k not in fs.params else []
            also = f"; settings of {unit}: {', '.join(names)}" if names else ""
            raise ConfigError(f"{where} {k} = {short(v)}: {' '.join(str(e).split())}{also}") from None
    return fs


def splice_settings(text: str, unit: str, settings: dict, label: str) -> str:
    """The scene text with the ``settings:`` of ``unit`` (the ``particles:`` section or ``units.<unit>``) holding
    ``settings`` (keys replaced or added), all else as written: the values are spliced in at the positions of the
    YAML nodes, so comments, layout and every other value the core reads stay byte for byte (the core does it,
    without PyYAML: a run's grid check needs it)."""
    # a JSON string is a YAML double-quoted scalar
    return _core.splice_settings(text, unit, [(k, json.dumps(v)) for k, v in settings.items()], label)
