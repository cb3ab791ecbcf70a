"""How a summary key is shown, and which values of a run have no counterpart on a finer grid: shared by the error
estimate, the accuracy target and the grid check every plain run makes (kept apart so that the check imports
neither)."""
from __future__ import annotations

from ..outputs import per_class_names


def display_name(key: str, unit: str) -> tuple[str, str]:
    """A summary key and its unit as a line shows them: ``d50_um``, ``um`` -> ``d50``, ``µm``."""
    if key.endswith("_um"):
        return key[:-3], "µm"
    return key, "" if unit == "-" else unit


def not_corresponding(base, refined: list) -> dict[str, str]:
    """The states and outputs of ``base`` that have no counterpart on the refined grids, with the reason: those of
    one size class (their index means another range of sizes on a finer grid: issue 29, ``tracer_out_N10`` of the
    tanks-in-series scene) and the fraction in an end class (which narrows as the grid refines). Values at fixed
    sizes (the 2-D population's reporting classes) keep their names and are compared."""
    names = list(base.state_names) + list(base.output_names)
    out = {}
    for r in refined:
        for n in per_class_names(names, list(r.state_names) + list(r.output_names)):
            out[n] = "one size class's value: on a finer grid that class is another range of sizes"
    for j, role in enumerate(base.output_roles):
        if role[0] == "grid_end":
            out.setdefault(base.output_names[j], "the grid end's value: on a finer grid the end class is narrower")
    return out
