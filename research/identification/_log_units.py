"""Units of logged columns, converted at the reading edge: lengths to mm, angles to rad, time to s, and encoder
counts through a stated resolution (counts per mm for a linear axis, counts per revolution for a rotary one).

A column in counts without a resolution is refused: a count has no size of its own, and guessing one is the
unit mistake the plausibility checks exist to catch. A counts column must hold whole numbers (an encoder
counts); a column with fractions is most likely already scaled (or interpolated by the drive: then pass
``Plausibility(integer_counts=False)``).
"""

from __future__ import annotations

import numpy as np

from research.errors import DriveLogError

#: length units accepted at the edge and their size in mm
LENGTH_UNITS = {"mm": 1.0, "m": 1000.0, "um": 1e-3, "in": 25.4}
#: angle units (rotary axes) and their size in rad
ANGLE_UNITS = {"rad": 1.0, "deg": np.pi / 180.0}
#: encoder counts: scaled by ``counts_per_mm`` or ``counts_per_rev``
COUNTS = "counts"
#: every unit a position column may have
POSITION_UNITS = tuple(LENGTH_UNITS) + tuple(ANGLE_UNITS) + (COUNTS,)
#: time units accepted at the edge and their size in s
TIME_UNITS = {"s": 1.0, "ms": 1e-3, "us": 1e-6, "ns": 1e-9}
#: largest distance of a counts sample from a whole number that still reads as an integer count
COUNT_ROUNDING = 1e-6


def _scale(value, name: str, where: str) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)) or not (
            np.isfinite(value) and value > 0):
        raise DriveLogError(f"{where}: {name} must be a finite number > 0, got {value!r}")
    return float(value)


def position_factor(unit: str, where: str, *, counts_per_mm=None, counts_per_rev=None) -> tuple[float, str]:
    """``(factor, unit after conversion)`` for a position column in ``unit``: lengths -> mm, angles -> rad, counts
    -> mm (``counts_per_mm``) or rad (``counts_per_rev``).

    Args:
        unit: one of :data:`POSITION_UNITS`.
        where: ``"<file>: column '<name>' (<role>)"``, the start of every error message.
        counts_per_mm: encoder counts per mm of a linear axis (counts only).
        counts_per_rev: encoder counts per revolution of a rotary axis (counts only).
    Raises:
        DriveLogError: unknown unit, counts without exactly one resolution, a resolution that is not > 0, or a
            resolution given for a column that is not in counts.
    """
    if unit not in POSITION_UNITS:
        raise DriveLogError(f"{where}: unknown position unit {unit!r}; expected one of {POSITION_UNITS}")
    if unit != COUNTS:
        if counts_per_mm is not None or counts_per_rev is not None:
            raise DriveLogError(f"{where}: a counts resolution is given but the column's unit is {unit!r}; declare "
                                f"the unit {COUNTS!r} or drop the resolution")
        return (LENGTH_UNITS[unit], "mm") if unit in LENGTH_UNITS else (ANGLE_UNITS[unit], "rad")
    if (counts_per_mm is None) == (counts_per_rev is None):
        raise DriveLogError(f"{where}: unit {COUNTS!r} needs exactly one resolution: counts_per_mm (linear axis) or "
                            f"counts_per_rev (rotary axis), got counts_per_mm={counts_per_mm!r}, "
                            f"counts_per_rev={counts_per_rev!r}")
    if counts_per_mm is not None:
        return 1.0 / _scale(counts_per_mm, "counts_per_mm", where), "mm"
    return 2 * np.pi / _scale(counts_per_rev, "counts_per_rev", where), "rad"


def convert_position(values: np.ndarray, unit: str, where: str, *, counts_per_mm=None, counts_per_rev=None,
                     integer_counts: bool = True) -> tuple[np.ndarray, str]:
    """``values`` in ``unit`` -> ``(values in mm or rad, "mm" | "rad")`` (:func:`position_factor`).

    Raises:
        DriveLogError: as :func:`position_factor`, and a counts column holding fractions when ``integer_counts``
            (the sample index and value are named).
    """
    factor, out = position_factor(unit, where, counts_per_mm=counts_per_mm, counts_per_rev=counts_per_rev)
    if unit == COUNTS and integer_counts:
        frac = np.abs(values - np.round(values))
        k = int(np.argmax(frac)) if frac.size else 0
        if frac.size and np.isfinite(frac[k]) and frac[k] > COUNT_ROUNDING:
            raise DriveLogError(f"{where}: declared {COUNTS!r} but sample index {k} is {values[k]!r}, not a whole count; "
                                "is the column already in mm (or deg)? (drives that interpolate counts: pass "
                                "Plausibility(integer_counts=False))")
    return values * factor, out


def time_factor(unit: str, where: str) -> float:
    """Size of one ``unit`` in s. Raises DriveLogError for an unknown unit."""
    if unit not in TIME_UNITS:
        raise DriveLogError(f"{where}: unknown time unit {unit!r}; expected one of {sorted(TIME_UNITS)}")
    return TIME_UNITS[unit]
