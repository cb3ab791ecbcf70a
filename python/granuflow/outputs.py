"""What output names mean: the one module of the package that interprets the names of states, reported outputs and
summary keys.

Reported outputs carry roles the units declare in C++ (``OutputRole``): balance terms (quantity water, solids or
energy; in, out or hold-up), the size distribution (pivot diameter and class mass of class i), regularization
counts and the mass fraction at the grid's end. The core hands them over with every result
(``(role, quantity, class, unit)`` per output); this module reads them, and only the characteristic diameters
(``d10``, ``d50``, ...) are recognised by name, for display.

Display conventions (files and plots): sizes in µm (``um``), everything else in SI; summary keys carry their unit
in the name (``d50_um``, ``T_gas_out_K``).
"""
from __future__ import annotations

import re
from collections.abc import Mapping

_SIZE = re.compile(r"^(?:.*\.)?(d\d+)$")  # characteristic diameters: d10, d50, ...

BALANCE_QUANTITIES = ("water", "solids", "energy")
# Summary keys every summary.json holds (null where the scene has no such quantity).
STANDARD_SUMMARY_KEYS = ("d10_um", "d50_um", "d90_um", "bed_moisture", "T_gas_out_K")
STANDARD_SUMMARY_UNITS = {"d10_um": "um", "d50_um": "um", "d90_um": "um", "bed_moisture": "kg/kg", "T_gas_out_K": "K"}
DEFAULT_SWEEP_OUTPUTS = ("d50_um", "bed_moisture", "bed_moisture_wet", "T_gas_out_K", "d10_um", "d90_um")

# The characteristic diameters (mass-based) that calibration reads of a bed, and the observable groups of its parity
# plots and pooled statistics, with the unit each group is shown in (experiment files, calibration tables, parity
# plots). Which unit is the bed and which variable the outlet gas temperature, the scene says itself: the standard
# summary keys it declares (observable_groups), never a unit's name.
D_NAMES = ("d5", "d10", "d16", "d25", "d50", "d75", "d84", "d90", "d95")
GROUP_TITLES = {"size": "characteristic diameters d5..d95", "moisture": "bed moisture",
                "T_gas_out": "outlet gas temperature"}
GROUP_DISPLAY = {"size": "um", "moisture": "wt%", "T_gas_out": "degC"}

# Readable names of the local output/state names, for legends and labels.
_WORDS = {
    "T": "temperature", "Y": "gas humidity", "X": "moisture (dry basis)", "moisture": "moisture (dry basis)",
    "moisture_wet": "moisture (wet basis)", "mdot": "mass flow", "V_dot": "volume flow", "number": "particle number",
    "particles": "particle number", "mass": "mass", "relative_humidity": "relative humidity",
    "top_class_fraction": "mass fraction in the top class", "fwet_mean": "mean wetted fraction",
    "evaporated_fraction": "evaporated fraction",
}

# The mass fraction in an end class of a size grid (the top class holds what grew beyond the grid: fold) above which
# a result warns (summary.json `warnings`, stderr, Python warnings): with 5 % in the top class d95 and above are the
# grid's edge, not the product, and growth is held back; in the bottom class the same for d5 and below.
GRID_END_WARNING = 0.05
# The balance guard (docs/accuracy.md, "Balance closures"): a closure is the relative error of a conserved quantity
# over the run (or across the boundary at a steady state). The integrator's error control keeps it well below its
# relative tolerance (the shipped scenes close to 1e-7 or better at rtol 1e-6), so a closure above
# max(BALANCE_WARN_MIN, BALANCE_WARN_FACTOR * rtol), capped at BALANCE_WARN_MAX, is worth a warning; above
# BALANCE_FAIL (1 % of the quantity gone or made) no tolerance explains it: a unit loses or creates mass or energy.
BALANCE_WARN_MIN = 1e-6
BALANCE_WARN_FACTOR = 100.0
BALANCE_WARN_MAX = 1e-3
BALANCE_FAIL = 1e-2


def balance_limits(rtol: float | None) -> tuple[float, float]:
    """(warning limit, failure limit) of a balance closure for a solve at relative tolerance ``rtol`` (None: the
    warning limit at its floor)."""
    warn = BALANCE_WARN_MIN if rtol is None else max(BALANCE_WARN_MIN, BALANCE_WARN_FACTOR * float(rtol))
    return min(warn, BALANCE_WARN_MAX), BALANCE_FAIL


def balance_closures(balance: Mapping) -> dict[str, float]:
    """The closures of a ``balance`` map as ``{name: value}``, whatever it nests: every finite number whose key is
    ``rel`` or ends in ``_rel`` (a run's ``solids_rel``, a steady state's ``{"solids": {"rel": ...}}``, per component
    ``{"solids": {"NaBz": {"rel": ...}}}``), named by its path (``solids``, ``solids.NaBz``); null closures (a
    quantity the scene does not track) are left out."""
    out: dict[str, float] = {}

    def walk(m: Mapping, path: tuple[str, ...]):
        for k, v in m.items():
            if isinstance(v, Mapping):
                walk(v, path + (str(k),))
            elif (k == "rel" or str(k).endswith("_rel")) and isinstance(v, (int, float)) and v == v:
                name = path + (() if k == "rel" else (str(k)[:-4],))
                out[".".join(name)] = float(v)
    walk(balance, ())
    return out


def balance_findings(balance: Mapping, rtol: float | None,
                     when: str = "at the end of the run") -> tuple[list[str], list[str]]:
    """(warnings, failures) of the balance guard: a closure above the warning limit (:func:`balance_limits`) warns;
    above BALANCE_FAIL it is a failure (a unit loses or creates the quantity), listed in both; the worst first."""
    warn_at, fail_at = balance_limits(rtol)
    warns, fails = [], []
    for name, v in sorted(balance_closures(balance).items(), key=lambda kv: -kv[1]):
        if v <= warn_at:
            continue
        quantity = name.split(".")[0]
        what = "energy" if quantity == "energy" else "mass"
        tol = f"rtol {rtol:g}" if rtol is not None else "the solve's tolerance"
        if v > fail_at:
            msg = (f"balance: the {name} balance does not close {when}: closure {v:.3g} (more than "
                   f"{fail_at:g}): a unit loses or creates {what}; no solver tolerance explains it")
            fails.append(msg)
        else:
            msg = (f"balance: the {name} balance closes only to {v:.3g} {when} (more than {warn_at:g} for "
                   f"{tol}): tighten the solver's tolerances (solver: rtol, atol) or check the units")
        warns.append(msg)
    return warns, fails


# Summary keys in plots: (readable name, unit of the summary value, unit shown).
_SUMMARY_DISPLAY = {
    "d10_um": ("d10 (mass-based)", "um", "um"), "d50_um": ("d50 (mass-based)", "um", "um"),
    "d90_um": ("d90 (mass-based)", "um", "um"),
    "bed_moisture_wet": ("bed moisture (wet basis)", "kg/kg", "wt%"),
    "bed_moisture": ("bed moisture (dry basis)", "kg/kg", "wt%"),
    "T_gas_out_K": ("gas outlet temperature", "K", "degC"), "T_bed_K": ("bed temperature", "K", "degC"),
    "T_out_K": ("outlet temperature", "K", "degC"),
}


def grid_end_warnings(ends: Mapping[str, Mapping], when: str = "at the end of the run",
                      causes: Mapping[str, str | None] | None = None) -> list[str]:
    """The warnings of an end class of a size grid holding more than GRID_END_WARNING of the mass, from grid ends as
    :meth:`granuflow.Result.grid_ends` gives them (``initial``, ``final``, ``max``, ``d_um`` per end): at the start
    (the initial distribution lies outside the grid) or later; ``when`` says where the final value stands ("at the
    end of the run", "at the steady state"). Mass piles up in the top class for two reasons with opposite cures:
    ``causes`` (from the grid check, granuflow.accuracy.grid_check) names it per end, "coarse" (numerical smearing
    of a coarse grid: more classes; a wider grid makes it worse) or "range" (the product grows beyond the grid:
    widen it); without it both are named."""
    out = []
    lim = GRID_END_WARNING
    causes = causes or {}
    for name, e in ends.items():
        unit, _, end = name.rpartition(".")
        where = {"top_class": "top size class", "bottom_class": "bottom size class"}.get(end, name)
        at = f" ({e['d_um']:.4g} um)" if e["d_um"] is not None else ""
        side = "d_min" if end == "bottom_class" else "d_max"
        if e["initial"] > lim:
            out.append(f"{unit}: the initial size distribution lies outside the grid: "
                       f"{100 * e['initial']:.3g} % of the initial mass is in the {where}{at}; check the initial "
                       "distribution against the grid (particles: settings: d_min, d_max)")
        elif e["max"] > lim:
            peak = f" (up to {100 * e['max']:.3g} % during it)" if e["max"] > 1.01 * e["final"] else ""
            head = f"{unit}: {100 * e['final']:.3g} % of the mass is in the {where}{at} {when}{peak}"
            cause = causes.get(name)
            if cause == "coarse":
                out.append(f"{head}: numerical smearing of a coarse grid (on a grid twice as fine the fraction "
                           "shrinks towards zero), not product beyond the grid; use more classes (accuracy: 1% or "
                           f"particles: settings: classes), not a wider grid ({side})")
            elif cause == "range":
                out.append(f"{head}: the grid clips the distribution (more than {100 * lim:g} %, and as much on a "
                           f"grid twice as fine), so the sizes near that end are the grid's, not the product's; "
                           f"widen the grid (particles: settings: {side})")
            else:
                out.append(f"{head}: the grid clips the distribution (more than {100 * lim:g} %), so the sizes "
                           "near that end are the grid's, not the product's: either the grid is too coarse (mass "
                           "smeared into the end class: more classes) or too short (widen it: particles: settings: "
                           f"{side}); the grid check of a plain run tells which")
    return out


def null_reason(source: str, si_unit: str, when: str = "at the end of the run") -> str:
    """Why the summary value read from output ``source`` is null (summary.json ``null_reasons``): a size (unit m)
    is undefined where its population or stream is empty (the units report NaN, never 0); anything else that is
    not a finite number says so."""
    if si_unit == "m":
        return (f"{source} is undefined {when}: the population or stream it describes holds no particles (nothing "
                "discharged, an empty bed), and a size of nothing is not a number")
    return f"{source} is not a finite number {when}"


def d_values(bed: str) -> tuple[str, ...]:
    """The characteristic diameters d5..d95 of unit ``bed``."""
    return tuple(f"{bed}.{d}" for d in D_NAMES)


def observable_groups(summary_map, names) -> dict[str, tuple[str, ...]]:
    """The observable groups of a scene from its summary declarations (``Flowsheet.summary_map``) and the names of
    its states and outputs (``names``): the bed is the unit ``bed_moisture`` reads (else ``d50_um``); ``size``, its
    d5..d95, and ``moisture``, its moisture on dry and wet basis, where it reports them all; ``T_gas_out``, what
    ``T_gas_out_K`` reads. A group the scene does not have is left out."""
    names = set(names)
    groups: dict[str, tuple[str, ...]] = {}
    source = summary_map.get("bed_moisture") or summary_map.get("d50_um")
    bed = source.rpartition(".")[0] if source else ""
    for group, members in (("size", d_values(bed)), ("moisture", (f"{bed}.moisture", f"{bed}.moisture_wet"))):
        if bed and names.issuperset(members):
            groups[group] = members
    if summary_map.get("T_gas_out_K"):
        groups["T_gas_out"] = (summary_map["T_gas_out_K"],)
    return groups


def group_of(name: str, groups) -> str:
    """The group of observable ``name`` (observable_groups), or the name itself outside every group."""
    return next((g for g, members in groups.items() if name in members), name)


def observable_display(name: str, groups) -> str | None:
    """The unit observable ``name`` is shown in when it belongs to a group (observable_groups), else None."""
    return GROUP_DISPLAY.get(group_of(name, groups))


# -- roles ----------------------------------------------------------------------------------------------------------
# roles: the core's list of (role, quantity, class, unit) per output, aligned with the output names.
def balance_terms(roles) -> list[tuple[int, str, str]]:
    """``(column, quantity, kind)`` of every balance output: quantity water|solids|energy, kind in|out|hold."""
    kinds = {"balance_in": "in", "balance_out": "out", "balance_hold": "hold"}
    return [(j, q, kinds[r]) for j, (r, q, _, _) in enumerate(roles) if r in kinds]


def psd_units(roles) -> list[str]:
    """Units that report a size distribution."""
    return sorted({u for r, _, _, u in roles if r == "size_mass"})


def psd_columns(roles, unit: str) -> tuple[list[int], list[int]]:
    """Columns of the pivot diameters (m) and class masses (kg) of ``unit``, in class order."""
    d = sorted((c, j) for j, (r, _, c, u) in enumerate(roles) if u == unit and r == "size_diameter")
    m = sorted((c, j) for j, (r, _, c, u) in enumerate(roles) if u == unit and r == "size_mass")
    return [j for _, j in d], [j for _, j in m]


def is_psd(roles, j: int) -> bool:
    return roles[j][0] in ("size_diameter", "size_mass")


def regularization_columns(roles, output_names) -> list[tuple[int, str]]:
    """``(column, name)`` of the outputs counting where a closure left the paper's literal equations."""
    return [(j, output_names[j]) for j, (r, _, _, _) in enumerate(roles) if r == "regularization"]


def grid_end_columns(roles, output_names) -> list[tuple[int, str]]:
    """``(column, name)`` of the outputs a unit declares as the mass fraction at its population's grid end (the
    fluid bed's ``top_class_fraction``); :meth:`granuflow.Result.grid_ends` reads both end classes of every size
    distribution as well."""
    return [(j, output_names[j]) for j, (r, _, _, _) in enumerate(roles) if r == "grid_end"]


def per_class_names(names_a, names_b) -> set[str]:
    """The names (of states and outputs) that stand for one size class each, found by comparing two results of the
    same scene on different grids: a stem ``bed.M_`` whose indices differ between them. The same name means a
    different class on each grid, so such names are not compared."""
    def split(n):  # "bed.M_3" -> ("bed.M_", 3), as ^(.*_)(\d+)$ would, without a regular expression per name
        stem, sep, index = n.rpartition("_")
        return (stem + sep, int(index)) if sep and index.isdecimal() else None

    def stems(names):
        out: dict[str, set[int]] = {}
        for n in names:
            m = split(n)
            if m:
                out.setdefault(m[0], set()).add(m[1])
        return out
    a, b = stems(names_a), stems(names_b)
    differ = {s for s in set(a) | set(b) if a.get(s) != b.get(s)}
    return {n for n in list(names_a) + list(names_b) if (m := split(n)) and m[0] in differ}


def is_size(name: str, si_unit: str = "m") -> bool:
    """A characteristic diameter or a size-distribution pivot diameter (shown in µm)."""
    return si_unit == "m" and (bool(_SIZE.match(name)) or ".psd_d_" in name)


def size_fraction(name: str) -> float | None:
    """The mass fraction below a characteristic diameter: ``bed.d90`` -> 0.9; None for other names."""
    m = _SIZE.match(name)
    return int(m.group(1)[1:]) / 100.0 if m else None


# -- display --------------------------------------------------------------------------------------------------------
def display_unit(name: str, si_unit: str) -> str:
    """The unit ``name`` is shown in (files, plots): µm for sizes, else its SI unit."""
    return "um" if is_size(name, si_unit) else si_unit


def summary_in_um(key: str) -> bool:
    """Summary keys ending in ``_um`` hold a size in µm (the core reports m)."""
    return key.endswith("_um")


def summary_unit(key: str, si_unit: str) -> str:
    """The unit of a summary value as written to summary.json."""
    return "um" if summary_in_um(key) else si_unit


def readable(name: str) -> str:
    """A readable name for legends: ``bed.d10`` -> ``d10, mass-based (bed)``, ``gas.T`` -> ``temperature (gas)``."""
    if name in _SUMMARY_DISPLAY:
        return _SUMMARY_DISPLAY[name][0]
    unit, _, local = name.rpartition(".")
    m = _SIZE.match(local)
    words = f"{m.group(1)}, mass-based" if m else _WORDS.get(local, local.replace("_", " "))
    return f"{words} ({unit})" if unit else words


_UNIT_SUFFIX = {"um": "um", "K": "K", "s": "s", "kg": "kg", "ms": "ms", "m3h": "m3/h", "degC": "degC",
                "g_min": "g/min", "W": "W", "Pa": "Pa"}


def header(name: str, unit: str) -> str:
    """A column header for files: the name with its unit (``bed_moisture [kg/kg]``), or the name alone when it
    already ends in that unit (``d50_um``, ``T_gas_out_K``, ``wall_time_s``) or has none."""
    for suffix, u in _UNIT_SUFFIX.items():
        if name.endswith("_" + suffix) and u == unit:
            return name
    return f"{name} [{unit}]" if unit else name


def summary_display(key: str) -> tuple[str, str, str]:
    """(readable name, unit of the value, unit shown) of a summary key for plots; unknown keys as they are. The
    estimated numerical error of a key (``d50_um_err``, granuflow.accuracy) is shown as the key is."""
    if key.endswith("_err") and key[:-4] in _SUMMARY_DISPLAY:
        name, unit, shown = _SUMMARY_DISPLAY[key[:-4]]
        return f"estimated numerical error of {name}", unit, ("K" if shown == "degC" else shown)
    return _SUMMARY_DISPLAY.get(key, (key, "", ""))
