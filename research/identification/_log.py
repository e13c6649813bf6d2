"""Drive logs: logged reference and actual axis positions (thesis §6.3, Fig 6.3), loaded and validated.

A :class:`DriveLog` holds one axis: time ``t`` [s], reference ``x_r`` [mm] and measured ``x`` [mm] at the
control period ``Ts``, plus, optionally, the control signal. Files are read by :func:`load_drive_log`
(CSV with a header line, MATLAB ``.mat`` through ``scipy.io.loadmat``, NumPy ``.npz``); lengths are
converted to mm and time to s at this edge, so everything downstream works in mm and s.

Validation (each failure raises :class:`~research.errors.DriveLogError` naming file, column and sample
index): both positions present, equal lengths, no NaN or inf, time strictly increasing, uniform sampling
within ``uniform_rtol`` of the median period (otherwise resample explicitly with :meth:`DriveLog.resample`,
whose method is recorded in :attr:`DriveLog.resampling`).
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np

from research.errors import DriveLogError
from research.trajectory import Trajectory

#: length units accepted at the edge and their size in mm
LENGTH_UNITS = {"mm": 1.0, "m": 1000.0, "um": 1e-3, "in": 25.4}
#: time units accepted at the edge and their size in s
TIME_UNITS = {"s": 1.0, "ms": 1e-3}
#: interpolation methods of :meth:`DriveLog.resample`
RESAMPLING_METHODS = ("linear", "cubic")
#: default tolerance on sampling jitter, relative to the median sample period
UNIFORM_RTOL = 1e-3


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
        uniform_rtol: accepted sampling jitter relative to the median period.

    Raises:
        DriveLogError: unequal lengths, NaN/inf, non-increasing or non-uniform time, fewer than 3 samples.
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

    def __post_init__(self):
        arrays = {"t": self.t, "reference": self.reference, "actual": self.actual}
        if self.control is not None:
            arrays["control"] = self.control
        cols = dict(self.columns)
        n = None
        for role, value in arrays.items():
            name = cols.get(role, role)
            a = np.asarray(value, dtype=np.float64)
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
                f"(t[{k}] = {self.t[k]!r} <= t[{k - 1}] = {self.t[k - 1]!r})"
            )
        Ts = float(np.median(dt))
        dev = np.abs(dt - Ts)
        k = int(np.argmax(dev))
        if dev[k] > self.uniform_rtol * Ts:
            raise DriveLogError(
                f"{self.source}: column {cols.get('t', 't')!r} is not uniformly sampled: step {dt[k]!r} s at sample "
                f"index {k + 1} differs from the median period {Ts!r} s by more than {self.uniform_rtol:g} relative; "
                f"resample explicitly with DriveLog.resample(period, method) (methods {RESAMPLING_METHODS})"
            )
        object.__setattr__(self, "columns", cols)
        object.__setattr__(self, "units", dict(self.units))

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
def _read_table(path: Path) -> dict[str, np.ndarray]:
    """All numeric columns of a CSV (header line), ``.mat`` or ``.npz`` file as 1-D arrays by name."""
    suffix = path.suffix.lower()
    if suffix == ".mat":
        from scipy.io import loadmat

        raw = {k: v for k, v in loadmat(str(path)).items() if not k.startswith("__")}
    elif suffix == ".npz":
        with np.load(path, allow_pickle=False) as z:
            raw = {k: z[k] for k in z.files}
    elif suffix == ".csv":
        with open(path, encoding="utf-8") as fh:
            header = fh.readline().strip()
        names = [h.strip() for h in header.split(",")]
        if not header or any(not n for n in names):
            raise DriveLogError(f"{path}: a CSV drive log needs a header line naming every column, got {header!r}")
        try:
            data = np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2)
        except ValueError as exc:
            raise DriveLogError(f"{path}: cannot read the numeric CSV body: {exc}") from None
        if data.shape[1] != len(names):
            raise DriveLogError(f"{path}: header names {len(names)} columns but rows have {data.shape[1]}")
        raw = {n: data[:, i] for i, n in enumerate(names)}
    else:
        raise DriveLogError(f"{path}: unknown drive-log file type {suffix!r}; expected .csv, .mat or .npz")
    return raw


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
    uniform_rtol: float = UNIFORM_RTOL,
) -> DriveLog:
    """Read a drive log and map its columns by name.

    Args:
        path: ``.csv`` (header line with column names), ``.mat`` or ``.npz`` file.
        time, reference, actual: names of the time, commanded-position and measured-position columns.
        control: optional name of a control-signal column (kept, not used by the identification).
        length_unit: unit of the position columns in the file, one of ``LENGTH_UNITS``; converted to mm.
        time_unit: unit of the time column, one of ``TIME_UNITS``; converted to s.
        control_unit: unit label of the control column (not converted).
        uniform_rtol: accepted sampling jitter relative to the median period.
    Returns:
        the validated :class:`DriveLog` in s and mm.
    Raises:
        DriveLogError: unknown file type or unit, a missing column (the available ones are listed), or any
            failed validation (see :class:`DriveLog`).
    """
    path = Path(path)
    if length_unit not in LENGTH_UNITS:
        raise DriveLogError(f"{path}: unknown length unit {length_unit!r}; expected one of {sorted(LENGTH_UNITS)}")
    if time_unit not in TIME_UNITS:
        raise DriveLogError(f"{path}: unknown time unit {time_unit!r}; expected one of {sorted(TIME_UNITS)}")
    if not path.exists():
        raise DriveLogError(f"{path}: file not found")
    raw = _read_table(path)
    wanted = {"t": time, "reference": reference, "actual": actual}
    if control is not None:
        wanted["control"] = control
    for role, name in wanted.items():
        if name not in raw:
            raise DriveLogError(f"{path}: missing column {name!r} for the {role}; the file has {sorted(raw)}")
    L, T = LENGTH_UNITS[length_unit], TIME_UNITS[time_unit]
    cols = {role: np.asarray(raw[name], dtype=np.float64) for role, name in wanted.items()}
    units = {"t": "s", "reference": "mm", "actual": "mm"}
    if control is not None:
        units["control"] = control_unit
    return DriveLog(
        t=cols["t"] * T, reference=cols["reference"] * L, actual=cols["actual"] * L, control=cols.get("control"),
        source=str(path), columns=wanted, units=units, uniform_rtol=uniform_rtol,
    )


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
