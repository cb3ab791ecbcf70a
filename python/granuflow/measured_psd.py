"""Measured particle size distributions: sieve analyses, laser diffraction or image analysis tables, as a starting
bed, a feed, or calibration data (docs/measured_psd.md).

A table is sizes (m) and values of one *kind* and one *basis*:

* ``kind="Q"``: cumulative undersize at each size (nondecreasing, last value the total);
* ``kind="retained"``: amount retained on the sieve of each mesh size, i.e. between it and the next size (the top
  sieve's class ends at the same size ratio; a first size 0 is the pan);
* ``kind="q"``: density per unit size over the class from each size to the next (1/m; the last value 0);
* ``basis``: ``"mass"``, ``"volume"`` (the same fractions for one solid density: Q3, q3) or ``"number"`` (Q0, q0).

Totals must be 1 or 100 % (within 0.5 %). The checks, the reading of CSV files and the mapping onto a size grid are
the C++ core's, so a scene (``initial_psd: table``, ``initial_psd_file: ...``) and Python accept and refuse the same
tables with the same one-line messages (a ``ConfigError``, a ``ValueError``).

Example::

    import granuflow as gf
    from granuflow import measured_psd as mp
    bed = mp.read("flowsheets/data/gf25_example_sieve_start.csv")   # or mp.table(sizes_m, values, "Q", "mass")
    bed.map_to_grid(fs.size_edges("bed"))                          # mass fractions per class, outside fraction
    mp.set_table("my_bed", bed)     # scene: settings: {initial_psd: table, initial_psd_table: my_bed}

As calibration data, the observable ``unit.Q3(<size>)`` (e.g. ``bed.Q3(500 um)``) is the model's cumulative mass
fraction below that size; :func:`granuflow.calibration.q3_observations` turns a measured Q3 curve at some times
into such observations.
"""
from __future__ import annotations

import os
from dataclasses import dataclass
from typing import Sequence

import numpy as np

from . import _core
from .quantity import from_si

__all__ = ["MeasuredPSD", "table", "read", "set_table", "tables", "q3_name"]


@dataclass(frozen=True)
class MeasuredPSD:
    """A checked table (SI sizes; kind q in 1/m). Build it with :func:`table` or :func:`read`."""
    sizes_m: np.ndarray
    values: np.ndarray
    basis: str
    kind: str
    source: str = "arrays"

    def _args(self) -> tuple:
        return ([float(x) for x in self.sizes_m], [float(x) for x in self.values], self.basis, self.kind, self.source)

    def cumulative(self, sizes_m: Sequence[float]) -> np.ndarray:
        """Q (0..1, in the table's basis) at the given sizes: linear in ln d between the table's sizes, 0 below the
        first (what lies below it is taken just below it), 1 above the last."""
        return np.array(_core.measured_psd_cumulative(*self._args(), [float(x) for x in np.atleast_1d(sizes_m)]))

    def map_to_grid(self, diameter_edges_m: Sequence[float]) -> dict:
        """The table on a size grid with these class edges (m; pivots at the volume midpoints, as a scene's
        geometric grid): ``mass`` (mass fraction per class, sums to 1), ``number`` (number basis: number fraction per
        class), ``below`` and ``above`` (fraction of the measured amount outside the grid, folded into the end
        classes), ``pivots_m``. A unit maps the table on its own grid the same way."""
        r = dict(_core.measured_psd_map(*self._args(), [float(x) for x in diameter_edges_m]))
        return {k: (np.array(v) if isinstance(v, list) else v) for k, v in r.items()}


def _from_core(d: dict) -> MeasuredPSD:
    return MeasuredPSD(np.array(d["sizes_m"], dtype=float), np.array(d["values"], dtype=float), d["basis"], d["kind"],
                       d["source"])


def table(sizes_m: Sequence[float], values: Sequence[float], kind: str = "Q", basis: str = "mass", *,
          source: str = "arrays") -> MeasuredPSD:
    """A measured table from arrays: sizes in m (strictly increasing), values as fractions or % (kind ``q``: per
    m). ``kind``: ``Q`` | ``retained`` | ``q``; ``basis``: ``mass`` | ``volume`` | ``number``. Raises ConfigError
    (a ValueError) naming the row and value of a bad entry."""
    sizes = np.asarray(sizes_m, dtype=float).ravel()
    vals = np.asarray(values, dtype=float).ravel()
    return _from_core(_core.measured_psd_check([float(x) for x in sizes], [float(x) for x in vals], basis, kind,
                                               source))


def read(path: str | os.PathLike) -> MeasuredPSD:
    """A measured table from a CSV file (header ``size_um,Q3`` and the like; docs/measured_psd.md)."""
    return _from_core(_core.read_measured_psd(os.fspath(path)))


def set_table(name: str, psd: MeasuredPSD) -> None:
    """Make ``psd`` available to scenes built after this call under ``name``: a unit's settings
    ``{initial_psd: table, initial_psd_table: name}`` (a solids feed: ``{psd: table, psd_table: name}``)."""
    _core.set_measured_psd(name, *psd._args())


def tables() -> list[str]:
    """Names of the tables set with :func:`set_table` in this process."""
    return list(_core.measured_psd_names())


def q3_name(unit: str, size_m: float) -> str:
    """The calibration observable of Q3 at one size: ``unit.Q3(<size> um)``."""
    return f"{unit}.Q3({float(from_si(size_m, 'um', 'm')):.6g} um)"
