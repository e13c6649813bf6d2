"""Drive logs: logged reference and actual axis positions (thesis §6.3, Fig 6.3), loaded and validated.

A :class:`DriveLog` holds one axis: time ``t`` [s], reference ``x_r`` [mm] and measured ``x`` [mm] (rad for a
rotary axis) at the control period ``Ts``, plus, optionally, the control signal. Files are read by
:func:`load_drive_log` and :func:`load_axis_logs` (CSV with a header line, MATLAB ``.mat``, NumPy ``.npz``,
LinuxCNC halscope text exports: :mod:`research.identification._log_read`); positions are converted to mm
(m, um, in), rad (deg) or through an encoder resolution (counts) and time to s at this edge
(:mod:`research.identification._log_units`), so everything downstream works in mm (rad) and s.

Validation (each failure raises :class:`~research.errors.DriveLogError` naming file, column and sample
index): both positions present, equal lengths, no NaN or inf, time strictly increasing, uniform sampling
within ``uniform_rtol`` of the median period (otherwise resample explicitly with :meth:`DriveLog.resample`,
whose method is recorded in :attr:`DriveLog.resampling`), and plausible units (:class:`Plausibility`: a
position span over 10 m, a speed over 20 m/s (10 000 rpm for rotary axes), a sample period outside
[10 us, 0.1 s] or fractional counts are refused with the likely unit mistake; pass ``plausibility=`` to
override, ``None`` to skip). A file that cannot be parsed at all (corrupt ``.npz`` / ``.mat``, non-UTF-8
text, a non-numeric cell or column, a truncated row) is a :class:`~research.errors.DriveLogError` naming
the file, and the line and column or the column name, too.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from research.errors import DriveLogError
from research.identification._log_read import _numeric, _read_table
from research.identification._log_units import (
    ANGLE_UNITS,
    COUNTS,
    LENGTH_UNITS,
    POSITION_UNITS,
    TIME_UNITS,
    convert_position,
    time_factor,
)

if TYPE_CHECKING:
    from research.trajectory import Trajectory

__all__ = ["ANGLE_UNITS", "LENGTH_UNITS", "POSITION_UNITS", "TIME_UNITS", "DriveLog", "Plausibility", "load_axis_logs",
           "load_drive_log", "save_drive_log", "_numeric", "_read_table"]

#: keys of one axis in :func:`load_axis_logs`
AXIS_KEYS = {"reference", "actual", "control", "counts_per_mm", "counts_per_rev"}
#: interpolation methods of :meth:`DriveLog.resample`
RESAMPLING_METHODS = ("linear", "cubic")
#: default tolerance on sampling jitter, relative to the median sample period
UNIFORM_RTOL = 1e-3
#: plausibility bounds of a drive log after unit conversion (see :class:`Plausibility`)
MAX_POSITION_SPAN_MM = 10_000.0  # 10 m: no machine axis is longer; a larger span is usually um read as mm
MAX_SPEED_MM_PER_S = 20_000.0  # 20 m/s: beyond the fastest linear-motor axes; larger: um read as mm
MAX_SAMPLE_PERIOD_S = 0.1  # 10 Hz: slower than any servo log; a 1 kHz log in ms read as s has Ts = 1 "s"
MIN_SAMPLE_PERIOD_S = 1e-5  # 100 kHz: faster than servo loops log; smaller: s read as ms or us
MAX_SPEED_RAD_PER_S = 2 * np.pi * 10_000 / 60  # 10 000 rpm: beyond rotary feed axes (direct-drive tables ~1000 rpm)


@dataclasses.dataclass(frozen=True)
class Plausibility:
    """Bounds that catch unit mistakes in a log (positions in um read as mm, time in ms read as s, counts with the
    wrong resolution), checked after the unit conversion.

    No acceleration bound: a step-response log (a common identification input) has a reference acceleration
    of ``step / Ts^2`` (1 mm at 1 kHz: 100 g), so a bound strict enough to catch um read as mm would refuse it;
    the span and speed bounds catch that mistake.

    Attributes:
        max_span_mm: largest ``max - min`` of a linear position column [mm] (rotary axes may turn any number of
            revolutions: no span bound in rad).
        max_speed_mm_per_s: largest ``|dx/dt|`` between samples of a linear position column [mm/s].
        max_speed_rad_per_s: the same for a rotary axis [rad/s].
        min_sample_period_s, max_sample_period_s: accepted range of the median sample period [s].
        integer_counts: a column declared in counts must hold whole numbers (:mod:`._log_units`).
    """

    max_span_mm: float = MAX_POSITION_SPAN_MM
    max_speed_mm_per_s: float = MAX_SPEED_MM_PER_S
    min_sample_period_s: float = MIN_SAMPLE_PERIOD_S
    max_sample_period_s: float = MAX_SAMPLE_PERIOD_S
    max_speed_rad_per_s: float = MAX_SPEED_RAD_PER_S
    integer_counts: bool = True

    def check(self, log: "DriveLog") -> None:
        """Raise :class:`DriveLogError` naming the column and the likely unit if ``log`` is implausible."""
        src, cols = log.source, log.columns
        tname = cols.get("t", "t")
        Ts = log.sample_period
        if Ts > self.max_sample_period_s:
            raise DriveLogError(
                f"{src}: column {tname!r} (t): sample period {Ts:g} s is above {self.max_sample_period_s:g} s; "
                "is the time in ms (or us) read as s? pass time_unit='ms' (or override Plausibility.max_sample_period_s)")
        if Ts < self.min_sample_period_s:
            raise DriveLogError(
                f"{src}: column {tname!r} (t): sample period {Ts:g} s is below {self.min_sample_period_s:g} s; "
                "is the time in s read as ms? pass time_unit='s' (or override Plausibility.min_sample_period_s)")
        for role in ("reference", "actual"):
            x, name = getattr(log, role), cols.get(role, role)
            rotary = log.units.get(role) == "rad"
            span = float(np.max(x) - np.min(x))
            if not rotary and span > self.max_span_mm:
                raise DriveLogError(
                    f"{src}: column {name!r} ({role}) spans {span:g} mm, above {self.max_span_mm:g} mm; are the "
                    "positions in um (or counts) read as mm? pass length_unit='um' or 'counts' with counts_per_mm "
                    "(or override Plausibility.max_span_mm)")
            speed = np.abs(np.diff(x)) / np.diff(log.t)
            k = int(np.argmax(speed))
            bound, unit = (self.max_speed_rad_per_s, "rad/s") if rotary else (self.max_speed_mm_per_s, "mm/s")
            if speed[k] > bound:
                hint = ("are the angles in deg read as rad, or counts with a wrong counts_per_rev?" if rotary else
                        "are the positions in um read as mm (length_unit='um'), counts with a wrong counts_per_mm, "
                        "or the time in s read as ms?")
                raise DriveLogError(
                    f"{src}: column {name!r} ({role}) moves at {speed[k]:g} {unit} at sample index {k + 1}, above "
                    f"{bound:g} {unit}; {hint} (or override Plausibility.max_speed_{unit.replace('/', '_per_')})")


#: the bounds every log is checked against unless told otherwise
DEFAULT_PLAUSIBILITY = Plausibility()


@dataclasses.dataclass(frozen=True, eq=False)
class DriveLog:
    """One axis' logged closed-loop motion (thesis §6.3: ``x_r,k``, ``x_k`` captured at ``Ts``).

    Attributes:
        t: ``(N,)`` sample times [s], strictly increasing and uniform within ``uniform_rtol``.
        reference: ``(N,)`` commanded position ``x_r`` [mm] (rad for rotary axes).
        actual: ``(N,)`` measured position ``x`` [mm].
        control: optional ``(N,)`` control signal (e.g. amplifier voltage), unit in ``units["control"]``.
        source: file name or a description (used in every error message).
        columns: role -> column name in the source (``{"t": "t", "reference": "qg", ...}``).
        units: role -> unit after loading (``{"t": "s", "reference": "mm", ...}``).
        resampling: ``None`` for logged samples, else the method that produced them (e.g. ``"linear"``).
        uniform_rtol: accepted sampling jitter relative to the median period (finite, >= 0).
        plausibility: unit-plausibility bounds (:class:`Plausibility`), ``None`` to skip the check.

    Raises:
        DriveLogError: unequal lengths, NaN/inf, non-increasing or non-uniform time, fewer than 3 samples,
            a bad ``uniform_rtol``, implausible units.
    """

    t: np.ndarray
    reference: np.ndarray
    actual: np.ndarray
    control: np.ndarray | None = None
    source: str = "<arrays>"
    columns: dict = dataclasses.field(default_factory=lambda: {"t": "t", "reference": "reference", "actual": "actual"})
    units: dict = dataclasses.field(default_factory=lambda: {"t": "s", "reference": "mm", "actual": "mm"})
    resampling: str | None = None
    uniform_rtol: float = UNIFORM_RTOL
    plausibility: Plausibility | None = DEFAULT_PLAUSIBILITY

    def __post_init__(self):
        rtol = self.uniform_rtol
        if isinstance(rtol, bool) or not isinstance(rtol, (int, float, np.floating, np.integer)) or not (
                np.isfinite(rtol) and rtol >= 0):
            raise DriveLogError(f"{self.source}: uniform_rtol must be a finite number >= 0 (relative jitter), got {rtol!r}")
        arrays = {"t": self.t, "reference": self.reference, "actual": self.actual}
        if self.control is not None:
            arrays["control"] = self.control
        cols = dict(self.columns)
        n = None
        for role, value in arrays.items():
            name = cols.get(role, role)
            a = _numeric(value, f"{self.source}: column {name!r} ({role})")
            if a.ndim == 2 and 1 in a.shape:
                a = a.reshape(-1)
            if a.ndim != 1:
                raise DriveLogError(f"{self.source}: column {name!r} ({role}) must be 1-D, got shape {a.shape}")
            if n is None:
                n = a.size
            elif a.size != n:
                raise DriveLogError(
                    f"{self.source}: column {name!r} ({role}) has {a.size} samples but column "
                    f"{cols.get('t', 't')!r} has {n}; all columns need equal lengths"
                )
            bad = np.flatnonzero(~np.isfinite(a))
            if bad.size:
                raise DriveLogError(
                    f"{self.source}: column {name!r} ({role}) is {a[bad[0]]} at sample index {int(bad[0])}; "
                    "NaN or inf samples are not allowed (fix or cut the log, nothing is dropped silently)"
                )
            a.setflags(write=False)
            object.__setattr__(self, role, a)
        if n < 3:
            raise DriveLogError(f"{self.source}: a drive log needs at least 3 samples, got {n}")
        dt = np.diff(self.t)
        bad = np.flatnonzero(dt <= 0)
        if bad.size:
            k = int(bad[0]) + 1
            raise DriveLogError(
                f"{self.source}: column {cols.get('t', 't')!r} is not strictly increasing at sample index {k} "
                f"(t[{k}] = {float(self.t[k])!r} <= t[{k - 1}] = {float(self.t[k - 1])!r})"
            )
        Ts = float(np.median(dt))
        dev = np.abs(dt - Ts)
        k = int(np.argmax(dev))
        if dev[k] > self.uniform_rtol * Ts:
            raise DriveLogError(
                f"{self.source}: column {cols.get('t', 't')!r} is not uniformly sampled: step {float(dt[k])!r} s at sample "
                f"index {k + 1} differs from the median period {float(Ts)!r} s by more than {self.uniform_rtol:g} relative; "
                f"resample explicitly with DriveLog.resample(period, method) (methods {RESAMPLING_METHODS})"
            )
        object.__setattr__(self, "columns", cols)
        object.__setattr__(self, "units", dict(self.units))
        if self.plausibility is not None:
            self.plausibility.check(self)

    # -- views ---------------------------------------------------------------------------------
    @property
    def n_samples(self) -> int:
        return int(self.t.size)

    @property
    def sample_period(self) -> float:
        """``Ts`` [s]: the median time step (jitter within ``uniform_rtol`` is ignored)."""
        return float(np.median(np.diff(self.t)))

    @property
    def duration(self) -> float:
        """``t[-1] - t[0]`` [s]."""
        return float(self.t[-1] - self.t[0])

    @property
    def tracking_error(self) -> np.ndarray:
        """``x_r - x`` [mm]."""
        return self.reference - self.actual

    def reference_trajectory(self) -> Trajectory:
        """The reference as a one-axis :class:`Trajectory` on the uniform grid ``k Ts`` (time from 0);
        derivatives by second-order finite differences (``Trajectory.from_positions``)."""
        from research.trajectory import Trajectory  # imports JAX: only here, a log loads without it

        t = np.arange(self.n_samples) * self.sample_period
        return Trajectory.from_positions(t, self.reference[:, None], axes=("x",))

    # -- slicing -------------------------------------------------------------------------------
    def window(self, start: float, stop: float) -> DriveLog:
        """Samples with ``start <= t < stop`` [s] (same source, columns and units).

        Raises:
            DriveLogError: fewer than 3 samples in the window.
        """
        keep = (self.t >= start) & (self.t < stop)
        ctl = None if self.control is None else self.control[keep]
        return dataclasses.replace(
            self, t=self.t[keep], reference=self.reference[keep], actual=self.actual[keep], control=ctl,
            source=f"{self.source}[{start:g} s, {stop:g} s)",
        )

    def split(self, at: float) -> tuple[DriveLog, DriveLog]:
        """``(t < at, t >= at)``: an estimation part and a held-out validation part [s]."""
        return self.window(-np.inf, at), self.window(at, np.inf)

    def resample(self, sample_period: float, method: str = "linear") -> DriveLog:
        """Explicit resampling onto ``t[0] + k sample_period`` [s] with ``method`` ("linear": ``np.interp``,
        "cubic": ``scipy.interpolate.CubicSpline``); the method is recorded in :attr:`resampling`.

        Use this only for logs whose time stamps are genuinely irregular; it interpolates, so it smooths.
        """
        if method not in RESAMPLING_METHODS:
            raise DriveLogError(f"{self.source}: unknown resampling method {method!r}; expected one of {RESAMPLING_METHODS}")
        if not (np.isfinite(sample_period) and sample_period > 0):
            raise DriveLogError(f"{self.source}: resampling period must be finite and > 0 s, got {sample_period!r}")
        t = self.t[0] + np.arange(int(np.floor(self.duration / sample_period + 1e-9)) + 1) * sample_period
        if method == "linear":
            f = lambda y: np.interp(t, self.t, y)
        else:
            from scipy.interpolate import CubicSpline

            f = lambda y: CubicSpline(self.t, y)(t)
        ctl = None if self.control is None else f(self.control)
        return dataclasses.replace(
            self, t=t, reference=f(self.reference), actual=f(self.actual), control=ctl, resampling=method
        )

    def to_dict(self) -> dict:
        """Description for JSON results (no samples): source, columns, units, N, Ts, duration."""
        return {
            "source": self.source, "columns": self.columns, "units": self.units, "n_samples": self.n_samples,
            "sample_period_s": self.sample_period, "duration_s": self.duration, "resampling": self.resampling,
        }


# -- loading ---------------------------------------------------------------------------------------
def load_drive_log(
    path,
    *,
    time: str = "t",
    reference: str = "x_ref",
    actual: str = "x_act",
    control: str | None = None,
    length_unit: str = "mm",
    time_unit: str = "s",
    control_unit: str = "V",
    units: dict | None = None,
    counts_per_mm: float | None = None,
    counts_per_rev: float | None = None,
    uniform_rtol: float = UNIFORM_RTOL,
    plausibility: Plausibility | None = DEFAULT_PLAUSIBILITY,
) -> DriveLog:
    """Read a drive log and map its columns by name.

    Args:
        path: ``.csv`` (header line with column names), ``.mat``, ``.npz``, or a LinuxCNC halscope text export
            (``.txt`` / ``.log``: channels by HAL name, time ``t`` from the sample period; see
            :func:`research.identification.read_halscope`).
        time, reference, actual: names of the time, commanded-position and measured-position columns.
        control: optional name of a control-signal column (kept, not used by the identification).
        length_unit: unit of both position columns, one of ``POSITION_UNITS`` (mm, m, um, in -> mm; deg, rad ->
            rad for a rotary axis; counts -> mm or rad through ``counts_per_mm`` / ``counts_per_rev``).
        time_unit: unit of the time column, one of ``TIME_UNITS``; converted to s.
        control_unit: unit label of the control column (not converted).
        units: per-column override of ``length_unit`` by role, ``{"x_ref": "mm", "x_act": "counts"}`` (a
            controller that logs the command in mm and the encoder in counts).
        counts_per_mm, counts_per_rev: encoder resolution of the columns in counts (one of the two).
        uniform_rtol: accepted sampling jitter relative to the median period.
        plausibility: unit-plausibility bounds (:class:`Plausibility`); ``None`` skips the check.
    Returns:
        the validated :class:`DriveLog` in s and mm (rad for a rotary axis).
    Raises:
        DriveLogError: unknown file type or unit, counts without a resolution (the column named), a missing
            column (the available ones are listed), or any failed validation (see :class:`DriveLog`).
    """
    path = Path(path)
    units = dict(units or {})
    bad = set(units) - {"x_ref", "x_act"}
    if bad:
        raise DriveLogError(f"{path}: units keys {sorted(bad)} are not position roles; expected 'x_ref' and/or 'x_act' "
                            "(the time unit is time_unit=, the control's control_unit=)")
    T = time_factor(time_unit, str(path))
    if not path.exists():
        raise DriveLogError(f"{path}: file not found")
    raw = _read_table(path)
    cols = {"reference": reference, "actual": actual} | ({"control": control} if control is not None else {})
    by_column = {reference: units.get("x_ref", length_unit), actual: units.get("x_act", length_unit)}
    if control is not None:
        by_column[control] = control_unit
    return _axis_log(path, raw, time, T, cols, by_column, {"counts_per_mm": counts_per_mm, "counts_per_rev": counts_per_rev},
                     str(path), uniform_rtol, plausibility)


def _axis_log(path, raw, time, T, cols, by_column, scales, source, uniform_rtol, plausibility) -> DriveLog:
    """One axis from the raw columns: look up, convert (:func:`convert_position`), validate (:class:`DriveLog`)."""
    if time not in raw:
        raise DriveLogError(f"{path}: missing time column {time!r}; the file has {sorted(raw)}")
    data, unit_of = {"t": _numeric(raw[time], f"{path}: column {time!r} (t)") * T}, {"t": "s"}
    for role, name in cols.items():
        if name not in raw:
            raise DriveLogError(f"{path}: missing column {name!r} for the {role}; the file has {sorted(raw)}")
        where = f"{path}: column {name!r} ({role})"
        a = _numeric(raw[name], where)
        if role == "control":
            data[role], unit_of[role] = a, by_column.get(name, "V")
            continue
        unit = by_column.get(name, "mm")
        data[role], unit_of[role] = convert_position(
            a, unit, where, **(scales if unit == COUNTS else {}),
            integer_counts=plausibility is None or plausibility.integer_counts)
    given = {k: v for k, v in scales.items() if v is not None}
    if given and COUNTS not in (by_column.get(cols["reference"], "mm"), by_column.get(cols["actual"], "mm")):
        raise DriveLogError(f"{path}: a counts resolution {given} is given but neither {cols['reference']!r} nor "
                            f"{cols['actual']!r} is declared in {COUNTS!r}; declare the unit or drop the resolution")
    if unit_of["reference"] != unit_of["actual"]:
        raise DriveLogError(f"{path}: the reference {cols['reference']!r} is in {unit_of['reference']} but the measured "
                            f"position {cols['actual']!r} in {unit_of['actual']} after conversion; a linear axis needs "
                            "two lengths, a rotary one two angles")
    return DriveLog(t=data["t"], reference=data["reference"], actual=data["actual"], control=data.get("control"),
                    source=source, columns={"t": time, **cols}, units=unit_of, uniform_rtol=uniform_rtol,
                    plausibility=plausibility)


def save_drive_log(log: DriveLog, path) -> Path:
    """Write ``t``, ``x_ref``, ``x_act`` (and ``control``) to ``.npz`` or ``.csv`` (s, mm); returns the path."""
    path = Path(path)
    cols = {"t": log.t, "x_ref": log.reference, "x_act": log.actual}
    if log.control is not None:
        cols["control"] = log.control
    if path.suffix.lower() == ".npz":
        np.savez(path, **cols)
    elif path.suffix.lower() == ".csv":
        np.savetxt(path, np.column_stack(list(cols.values())), delimiter=",", header=",".join(cols), comments="")
    else:
        raise DriveLogError(f"{path}: unknown drive-log file type {path.suffix!r}; expected .csv or .npz")
    return path


def load_axis_logs(
    path,
    axes: dict,
    *,
    time: str = "t",
    time_unit: str = "s",
    units: dict | None = None,
    uniform_rtol: float = UNIFORM_RTOL,
    plausibility: Plausibility | None = DEFAULT_PLAUSIBILITY,
) -> dict[str, DriveLog]:
    """Several axes logged in one file (a controller trace of X, Y, Z ...), one :class:`DriveLog` each.

    Args:
        path: ``.csv``, ``.mat``, ``.npz`` or halscope text (``.txt`` / ``.log``) file.
        axes: axis name -> ``{"reference": column, "actual": column[, "control": column][, "counts_per_mm": r |
            "counts_per_rev": r]}``, e.g. ``{"x": {"reference": "X_cmd", "actual": "X_enc", "counts_per_mm": 1000}}``;
            the resolution applies to that axis' columns declared in counts.
        time, time_unit: the shared time column and its unit (``TIME_UNITS``; a halscope file's is ``t`` in s).
        units: column name -> unit (``POSITION_UNITS``) for position columns not in mm, e.g.
            ``{"X_cmd": "m", "X_enc": "counts", "C_cmd": "deg"}``; a control column's unit is kept as a label
            (default "V").
        uniform_rtol, plausibility: as :func:`load_drive_log`; plausibility is checked per axis after the
            unit conversion, so a column in um declared as mm is refused naming that column.
    Returns:
        axis name -> :class:`DriveLog` [s, mm or rad].
    Raises:
        DriveLogError: no axes, an axis without ``reference``/``actual``, an unknown key, column or unit, counts
            without a resolution, or any failure of :func:`load_drive_log`'s checks; every message names the file.
    """
    path = Path(path)
    units = dict(units or {})
    if not isinstance(axes, dict) or not axes:
        raise DriveLogError(f"{path}: axes must map axis names to their columns, e.g. "
                            f"{{'x': {{'reference': 'X_cmd', 'actual': 'X_enc'}}}}, got {axes!r}")
    T = time_factor(time_unit, str(path))
    if not path.exists():
        raise DriveLogError(f"{path}: file not found")
    raw = _read_table(path)
    if time not in raw:
        raise DriveLogError(f"{path}: missing time column {time!r}; the file has {sorted(raw)}")
    out = {}
    for axis, spec in axes.items():
        if not isinstance(spec, dict) or not {"reference", "actual"} <= set(spec) or not set(spec) <= AXIS_KEYS:
            raise DriveLogError(f"{path}: axis {axis!r} needs columns {{'reference', 'actual'}} (optionally 'control', "
                                f"and 'counts_per_mm' or 'counts_per_rev' for columns in counts), got {spec!r}")
        cols = {k: v for k, v in spec.items() if k in ("reference", "actual", "control")}
        scales = {k: spec.get(k) for k in ("counts_per_mm", "counts_per_rev")}
        by_column = {name: units.get(name, "V" if role == "control" else "mm") for role, name in cols.items()}
        try:
            out[axis] = _axis_log(path, raw, time, T, cols, by_column, scales, f"{path} axis {axis}", uniform_rtol,
                                  plausibility)
        except DriveLogError as e:
            if f"axis {axis}" in str(e):
                raise
            raise DriveLogError(f"{e} (axis {axis!r})") from None
    return out
