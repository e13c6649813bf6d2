"""Accelerometer logs of a resonance test: read, convert to mm/s^2, check, resample.

A resonance test (a sine sweep or a series of tones on one axis, the workflow Klipper's input-shaper
calibration made common) logs the tool head's acceleration as ``time, accel_x, accel_y, accel_z`` at a
few kHz. :func:`load_accel_log` reads such a file (CSV with a header line such as
``#time,accel_x,accel_y,accel_z`` or named columns, NumPy ``.npz``, MATLAB ``.mat``) through the drive-log
table reader (:mod:`research.identification._log`), so a damaged file fails the same way: a
:class:`~research.errors.DriveLogError` naming the file, and the line and column or the column name.

Checks (each a ``DriveLogError`` naming file, column and sample index):

* NaN / inf samples, non-increasing time, fewer than :data:`MIN_SAMPLES` samples;
* units: the file's unit (``mm/s^2``, ``m/s^2`` or ``g``) is converted to mm/s^2. A peak above
  :data:`MAX_ACCEL_G` g is refused (beyond the full scale of the MEMS sensors used for these tests), and
  a log whose mean vector (gravity, if the sensor measures it) is 1 g only when read in another unit is
  refused naming that unit;
* clipping (a saturated sensor): a sample at or beyond the stated ``full_scale``, or, without one, a
  flat top: the extreme value of a column held by more samples than a smooth (parabolic) peak can give
  (:func:`_clipped`);
* irregular time stamps: steps that differ from the median period by more than ``uniform_rtol`` are
  resampled (linear interpolation onto the median period); the largest gap is reported in
  :attr:`AccelLog.resampling`, never hidden.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np

from research.errors import DriveLogError
from research.identification._log import _numeric, _read_table

#: acceleration units accepted at the edge and their size in mm/s^2 (standard gravity, CGPM 1901)
STANDARD_GRAVITY_MM_S2 = 9806.65
ACCEL_UNITS = {"mm/s^2": 1.0, "m/s^2": 1000.0, "g": STANDARD_GRAVITY_MM_S2}
#: time units accepted at the edge and their size in s
TIME_UNITS = {"s": 1.0, "ms": 1e-3, "us": 1e-6}
#: largest plausible |acceleration| [g]: the +-200 g full scale of the high-g MEMS parts (ADXL372); the
#: usual resonance-test sensors (ADXL345, LIS2DW, MPU-6050) stop at +-16 g
MAX_ACCEL_G = 200.0
#: relative tolerance on "the mean vector is 1 g": 3 axes with the +-40 mg zero-g offset of an ADXL345
#: each give sqrt(3) 0.04 = 7 %; 10 % covers it
GRAVITY_RTOL = 0.10
#: default tolerance on time-stamp jitter, relative to the median period (as for drive logs)
UNIFORM_RTOL = 1e-3
#: fewest samples a log must hold (a Welch PSD needs several segments of many samples)
MIN_SAMPLES = 64
#: a smooth peak ``a(t) = A - c t^2 / 2`` sampled uniformly spends time proportional to
#: ``sqrt(k + 1) - sqrt(k)`` in the k-th quantization level below the top, so the top level holds at most
#: ``1 / (sqrt(2) - 1) = 2.41`` times the samples of the next one; a clipped column holds far more.
#: The test flags twice that ratio (margin for the scatter of small counts) once at least
#: :data:`CLIP_MIN_SAMPLES` samples sit on the extreme.
SMOOTH_TOP_RATIO = 1.0 / (np.sqrt(2.0) - 1.0)
CLIP_MIN_SAMPLES = 8
#: the default column layouts tried in order when ``columns`` is not given
LAYOUTS = (
    ("#time", "accel_x", "accel_y", "accel_z"),  # Klipper's raw accelerometer CSV
    ("time", "accel_x", "accel_y", "accel_z"),
    ("t", "ax", "ay", "az"),
    ("t", "x", "y", "z"),
    ("time", "x", "y", "z"),
)


@dataclasses.dataclass(frozen=True, eq=False)
class AccelLog:
    """A tool-head accelerometer log on a uniform time grid.

    Attributes:
        t: ``(N,)`` sample times [s], uniform (median period :attr:`sample_period`).
        accel: ``(N, A)`` accelerations [mm/s^2], one column per axis.
        axes: axis letters of the columns, e.g. ``("x", "y", "z")``.
        source: file name or a description (used in every message).
        columns: axis -> column name in the source, plus ``"t"``.
        unit: the unit of the file (converted to mm/s^2 here).
        resampling: ``None`` when the time stamps were uniform, else ``{"method", "max_step_s",
            "at_time_s", "median_period_s"}``: the largest step of the file and where it was.
    """

    t: np.ndarray
    accel: np.ndarray
    axes: tuple[str, ...] = ("x", "y", "z")
    source: str = "<arrays>"
    columns: dict = dataclasses.field(default_factory=dict)
    unit: str = "mm/s^2"
    resampling: dict | None = None

    def __post_init__(self):
        t = np.asarray(self.t, dtype=np.float64)
        a = np.asarray(self.accel, dtype=np.float64)
        if a.ndim == 1:
            a = a[:, None]
        if t.ndim != 1 or a.ndim != 2 or a.shape[0] != t.size or a.shape[1] != len(self.axes):
            raise DriveLogError(f"{self.source}: expected t (N,) and accel (N, {len(self.axes)}) for axes "
                                f"{self.axes}, got {t.shape} and {a.shape}")
        t.setflags(write=False)
        a.setflags(write=False)
        object.__setattr__(self, "t", t)
        object.__setattr__(self, "accel", a)
        object.__setattr__(self, "axes", tuple(self.axes))

    @property
    def n_samples(self) -> int:
        return int(self.t.size)

    @property
    def sample_period(self) -> float:
        """``Ts`` [s]: the median time step."""
        return float(np.median(np.diff(self.t)))

    @property
    def sample_rate(self) -> float:
        """``1 / Ts`` [Hz]."""
        return 1.0 / self.sample_period

    @property
    def duration(self) -> float:
        """``t[-1] - t[0]`` [s]."""
        return float(self.t[-1] - self.t[0])

    def column(self, axis: str) -> np.ndarray:
        """The ``(N,)`` acceleration of ``axis`` [mm/s^2]."""
        return self.accel[:, self.axes.index(axis)]

    def to_dict(self) -> dict:
        """Description for reports (no samples)."""
        return {"source": self.source, "axes": list(self.axes), "columns": self.columns, "unit": self.unit,
                "n_samples": self.n_samples, "sample_rate_hz": self.sample_rate, "duration_s": self.duration,
                "resampling": self.resampling}


def accel_log(t, accel, *, axes=("x", "y", "z"), unit: str = "mm/s^2", time_unit: str = "s",
              source: str = "<arrays>", columns: dict | None = None, full_scale: float | None = None,
              uniform_rtol: float = UNIFORM_RTOL, check_units: bool = True) -> AccelLog:
    """Validate arrays into an :class:`AccelLog` (the checks of the module docstring).

    Args:
        t: ``(N,)`` time stamps in ``time_unit``.
        accel: ``(N, A)`` accelerations in ``unit`` (one of :data:`ACCEL_UNITS`).
        axes: axis letters of the ``A`` columns.
        full_scale: the sensor's range in ``unit`` (e.g. 16 for a +-16 g ADXL345 logged in g); a sample at
            or beyond it is clipping. ``None``: the flat-top test only.
        uniform_rtol: accepted jitter of the time steps relative to the median step; beyond it the log
            is resampled (linear) and the largest step reported.
        check_units: run the plausibility checks on the units (peak and gravity).
    Returns:
        the log in s and mm/s^2.
    Raises:
        DriveLogError: see the module docstring.
    """
    if unit not in ACCEL_UNITS:
        raise DriveLogError(f"{source}: unknown acceleration unit {unit!r}; expected one of {sorted(ACCEL_UNITS)}")
    if time_unit not in TIME_UNITS:
        raise DriveLogError(f"{source}: unknown time unit {time_unit!r}; expected one of {sorted(TIME_UNITS)}")
    axes = tuple(axes)
    cols = dict(columns) if columns else {"t": "t", **{a: a for a in axes}}
    t = _numeric(t, f"{source}: column {cols.get('t', 't')!r} (time)").reshape(-1)
    a = _numeric(accel, f"{source}: acceleration columns")
    a = a[:, None] if a.ndim == 1 else a
    if a.ndim != 2 or a.shape != (t.size, len(axes)):
        raise DriveLogError(f"{source}: expected {len(axes)} acceleration columns of {t.size} samples for axes "
                            f"{axes}, got shape {a.shape}")
    if t.size < MIN_SAMPLES:
        raise DriveLogError(f"{source}: an accelerometer log needs at least {MIN_SAMPLES} samples, got {t.size}")
    for j, ax in enumerate((("t",) + axes)):
        x = t if j == 0 else a[:, j - 1]
        bad = np.flatnonzero(~np.isfinite(x))
        if bad.size:
            raise DriveLogError(f"{source}: column {cols.get(ax, ax)!r} is {x[bad[0]]} at sample index {int(bad[0])}; "
                                "NaN or inf samples are not allowed (fix or cut the log, nothing is dropped silently)")
    t = t * TIME_UNITS[time_unit]
    dt = np.diff(t)
    bad = np.flatnonzero(dt <= 0)
    if bad.size:
        k = int(bad[0]) + 1
        raise DriveLogError(f"{source}: column {cols.get('t', 't')!r} is not strictly increasing at sample index {k} "
                            f"(t[{k}] = {t[k]!r} <= t[{k - 1}] = {t[k - 1]!r})")
    if full_scale is not None and not (np.isfinite(full_scale) and full_scale > 0):
        raise DriveLogError(f"{source}: full_scale must be finite and > 0 {unit}, got {full_scale!r}")
    for j, ax in enumerate(axes):
        _check_clipping(a[:, j], f"{source}: column {cols.get(ax, ax)!r}", full_scale, unit)
    a = a * ACCEL_UNITS[unit]
    if check_units:
        _check_units(a, source, unit, [cols.get(ax, ax) for ax in axes])
    resampling = None
    Ts = float(np.median(dt))
    k = int(np.argmax(np.abs(dt - Ts)))
    if abs(dt[k] - Ts) > uniform_rtol * Ts:
        big = int(np.argmax(dt))
        n = int(np.floor((t[-1] - t[0]) / Ts + 1e-9)) + 1
        grid = t[0] + np.arange(n) * Ts
        a = np.column_stack([np.interp(grid, t, a[:, j]) for j in range(a.shape[1])])
        resampling = {"method": "linear", "max_step_s": float(dt[big]), "at_time_s": float(t[big]),
                      "median_period_s": Ts, "samples_in": int(t.size), "samples_out": int(n)}
        t = grid
    return AccelLog(t=t, accel=a, axes=axes, source=source, columns=cols, unit=unit, resampling=resampling)


def _check_clipping(x: np.ndarray, where: str, full_scale, unit: str) -> None:
    """Refuse a saturated column: beyond ``full_scale``, or a flat top (see :data:`SMOOTH_TOP_RATIO`)."""
    if full_scale is not None:
        over = np.flatnonzero(np.abs(x) >= full_scale)
        if over.size:
            raise DriveLogError(f"{where}: {over.size} samples at or beyond the full scale +-{full_scale:g} {unit} "
                                f"(first at sample index {int(over[0])}, value {x[over[0]]:g}); the accelerometer "
                                "clipped, so the spectrum is distorted: repeat the test with a lower amplitude or a "
                                "larger range")
    if np.max(x) == np.min(x):  # a constant column has no peak to clip (no motion: the estimator's refusal)
        return
    for side, extreme in (("maximum", np.max(x)), ("minimum", np.min(x))):
        n0, n1, first = _top_counts(x, extreme, side)
        if n0 >= CLIP_MIN_SAMPLES and n0 > 2.0 * SMOOTH_TOP_RATIO * max(n1, 1):
            raise DriveLogError(
                f"{where}: {n0} samples sit exactly on the {side} {extreme:g} {unit} (first at sample index {first}) "
                f"against {n1} on the next level; a smooth peak gives at most {SMOOTH_TOP_RATIO:.2f} times, so the "
                "accelerometer clipped (saturated). Repeat the test with a lower amplitude or a larger range, or "
                "state full_scale")


def _top_counts(x: np.ndarray, extreme: float, side: str) -> tuple[int, int, int]:
    """Samples on the extreme value, on the next distinct value inward, and the first index on the extreme."""
    on = x == extreme
    n0 = int(np.count_nonzero(on))
    rest = x[~on]
    if rest.size == 0:
        return n0, 0, int(np.argmax(on))
    nxt = np.max(rest) if side == "maximum" else np.min(rest)
    return n0, int(np.count_nonzero(x == nxt)), int(np.argmax(on))


def _check_units(a_mm: np.ndarray, source: str, unit: str, names: list[str]) -> None:
    """Peak below :data:`MAX_ACCEL_G`; a mean vector of 1 g only in another unit is a unit mistake."""
    g = STANDARD_GRAVITY_MM_S2
    peak = np.abs(a_mm)
    j = int(np.argmax(np.max(peak, axis=0)))
    k = int(np.argmax(peak[:, j]))
    if peak[k, j] > MAX_ACCEL_G * g:
        raise DriveLogError(
            f"{source}: column {names[j]!r} reaches {a_mm[k, j] / ACCEL_UNITS[unit]:g} {unit} = {peak[k, j] / g:g} g at "
            f"sample index {k}, above the {MAX_ACCEL_G:g} g of any accelerometer used for resonance tests; is the log in "
            f"a smaller unit than {unit!r}? (units: {sorted(ACCEL_UNITS)})")
    mean_g = float(np.linalg.norm(np.mean(a_mm, axis=0))) / g
    if abs(mean_g - 1.0) <= GRAVITY_RTOL:
        return
    for other, size in ACCEL_UNITS.items():
        if other != unit and abs(mean_g * size / ACCEL_UNITS[unit] - 1.0) <= GRAVITY_RTOL:
            raise DriveLogError(
                f"{source}: the mean acceleration vector of columns {names} is {mean_g:.3g} g read as {unit!r}, but "
                f"exactly 1 g (gravity) read as {other!r}; is the log in {other!r}? pass unit={other!r}")


def _pick_layout(raw: dict, source) -> tuple[str, tuple[str, ...]]:
    for layout in LAYOUTS:
        if all(c in raw for c in layout):
            return layout[0], layout[1:]
    raise DriveLogError(f"{source}: no known column layout; the file has {sorted(raw)}; expected one of "
                        f"{[list(l) for l in LAYOUTS]} or pass columns={{'t': ..., 'x': ..., ...}}")


def load_accel_log(path, *, columns: dict | None = None, unit: str = "mm/s^2", time_unit: str = "s",
                   full_scale: float | None = None, uniform_rtol: float = UNIFORM_RTOL,
                   check_units: bool = True) -> AccelLog:
    """Read an accelerometer log (``.csv`` with a header line, ``.npz``, ``.mat``).

    Args:
        path: the file. Klipper's raw CSV (``#time,accel_x,accel_y,accel_z``, mm/s^2) is read as it is.
        columns: ``{"t": time column, "x": ..., "y": ..., "z": ...}`` (any subset of axes, at least one);
            default: the first of :data:`LAYOUTS` the file has.
        unit, time_unit, full_scale, uniform_rtol, check_units: as :func:`accel_log`.
    Returns:
        the validated :class:`AccelLog` (s, mm/s^2).
    Raises:
        DriveLogError: unreadable file, missing column (the available ones listed), any failed check.
    """
    path = Path(path)
    if not path.exists():
        raise DriveLogError(f"{path}: file not found")
    raw = _read_table(path)
    if columns is None:
        tname, anames = _pick_layout(raw, path)
        axes = ("x", "y", "z")
    else:
        columns = dict(columns)
        if "t" not in columns or len(columns) < 2:
            raise DriveLogError(f"{path}: columns must name 't' and at least one axis, got {columns}")
        tname = columns.pop("t")
        axes, anames = tuple(columns), tuple(columns.values())
    for name in (tname,) + tuple(anames):
        if name not in raw:
            raise DriveLogError(f"{path}: missing column {name!r}; the file has {sorted(raw)}")
    arrays = []
    for name in (tname,) + tuple(anames):
        x = _numeric(raw[name], f"{path}: column {name!r}")
        if x.ndim == 2 and 1 in x.shape:
            x = x.reshape(-1)
        if x.ndim != 1:
            raise DriveLogError(f"{path}: column {name!r} must be 1-D, got shape {x.shape}")
        if arrays and x.size != arrays[0].size:
            raise DriveLogError(f"{path}: column {name!r} has {x.size} samples but column {tname!r} has "
                                f"{arrays[0].size}; all columns need equal lengths")
        arrays.append(x)
    cols = {"t": tname, **dict(zip(axes, anames))}
    return accel_log(arrays[0], np.column_stack(arrays[1:]), axes=axes, unit=unit, time_unit=time_unit,
                     source=str(path), columns=cols, full_scale=full_scale, uniform_rtol=uniform_rtol,
                     check_units=check_units)


def save_accel_log(log: AccelLog, path, *, layout: str = "klipper") -> Path:
    """Write ``log`` in mm/s^2 and s: ``.csv`` (``layout="klipper"``: ``#time,accel_x,...``; ``"named"``:
    ``time,x,y,z``) or ``.npz`` (``time``, ``accel_x`` ...). Returns the path."""
    path = Path(path)
    if layout not in ("klipper", "named"):
        raise DriveLogError(f"{path}: unknown layout {layout!r}; expected 'klipper' or 'named'")
    names = (["#time"] + [f"accel_{a}" for a in log.axes]) if layout == "klipper" else (["time"] + list(log.axes))
    data = np.column_stack([log.t, log.accel])
    if path.suffix.lower() == ".csv":
        np.savetxt(path, data, delimiter=",", header=",".join(names), comments="", fmt="%.9g")
    elif path.suffix.lower() == ".npz":
        np.savez(path, **{n.lstrip("#"): data[:, i] for i, n in enumerate(names)})
    else:
        raise DriveLogError(f"{path}: unknown accelerometer-log file type {path.suffix!r}; expected .csv or .npz")
    return path
