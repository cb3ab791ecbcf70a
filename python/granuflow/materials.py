"""The catalogue of solid materials (C++ core, framework/src/materials.cpp): named sets of published property values.

A scene chooses one with ``particles: material: NAME``; every parameter the material describes then starts from its
value (``granuflow describe`` shows the material as the source), and the scene's ``params:`` override any of them.
A parameter that the catalogue knows but the chosen material does not give must be set in the scene: it is never
left at paper 001's maltodextrin value. ``granuflow materials [NAME]`` prints the catalogue; ``docs/materials.md``
is generated from it (reference.py).
"""
from __future__ import annotations

from . import _core
from ._core import ConfigError


def catalogue() -> list[dict]:
    """Every material: ``name``, ``description``, ``citation`` and ``properties`` (name, value in SI, unit, source,
    description, ``applies_to``: the particle system or the units that declare a parameter of that name)."""
    return list(_core.material_catalogue())


def material(name: str) -> dict:
    """One material of the catalogue by name; ConfigError naming the value and the known names otherwise."""
    for m in catalogue():
        if m["name"] == name:
            return m
    raise ConfigError(f"material '{name}' is not in the catalogue; known: {', '.join(m['name'] for m in catalogue())}")
