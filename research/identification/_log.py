"""Drive logs: logged reference and actual axis positions (thesis §6.3, Fig 6.3), loaded and validated.

A :class:`DriveLog` holds one axis: time ``t`` [s], reference ``x_r`` [mm] and measured ``x`` [mm] at the
control period ``Ts``, plus, optionally, the control signal. Files are read by :func:`load_drive_log`
(CSV with a header line, MATLAB ``.mat`` through ``scipy.io.loadmat``, NumPy ``.npz``); lengths are
converted to mm and time to s at this edge, so everything downstream works in mm and s.

Validation (each failure raises :class:`~research.errors.DriveLogError` naming file, column and sample
index): both positions present, equal lengths, no NaN or inf, time strictly increasing, uniform sampling
within ``uniform_rtol`` of the median period (otherwise resample explicitly with :meth:`DriveLog.resample`,
whose method is recorded in :attr:`DriveLog.resampling`), and plausible units (:class:`Plausibility`: a
position span over 10 m, a speed over 20 m/s or a sample period outside [10 us, 0.1 s] is refused with
the likely unit mistake, um read as mm or ms read as s; pass ``plausibility=`` to override, ``None`` to
skip). A file that cannot be parsed at all (corrupt ``.npz`` / ``.mat``, non-UTF-8 CSV, a non-numeric
cell or column) is a :class:`~research.errors.DriveLogError` naming the file, and the line and column
or the column name, too.
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
#: plausibility bounds of a drive log after unit conversion (see :class:`Plausibility`)
MAX_POSITION_SPAN_MM = 10_000.0  # 10 m: no machine axis is longer; a larger span is usually um read as mm
MAX_SPEED_MM_PER_S = 20_000.0  # 20 m/s: beyond the fastest linear-motor axes; larger: um read as mm
MAX_SAMPLE_PERIOD_S = 0.1  # 10 Hz: slower than any servo log; a 1 kHz log in ms read as s has Ts = 1 "s"
MIN_SAMPLE_PERIOD_S = 1e-5  # 100 kHz: faster than servo loops log; smaller: s read as ms or us


@dataclasses.dataclass(frozen=True)
class Plausibility:
    """Bounds that catch unit mistakes in a log (positions in um read as mm, time in ms read as s).

    Attributes:
        max_span_mm: largest ``max - min`` of a position column [mm].
        max_speed_mm_per_s: largest ``|dx/dt|`` between samples of a position column [mm/s].
        min_sample_period_s, max_sample_period_s: accepted range of the median sample period [s].
    """

    max_span_mm: float = MAX_POSITION_SPAN_MM
    max_speed_mm_per_s: float = MAX_SPEED_MM_PER_S
    min_sample_period_s: float = MIN_SAMPLE_PERIOD_S
    max_sample_period_s: float = MAX_SAMPLE_PERIOD_S

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
            span = float(np.max(x) - np.min(x))
            if span > self.max_span_mm:
                raise DriveLogError(
                    f"{src}: column {name!r} ({role}) spans {span:g} mm, above {self.max_span_mm:g} mm; "
                    "are the positions in um read as mm? pass length_unit='um' (or override Plausibility.max_span_mm)")
            speed = np.abs(np.diff(x)) / np.diff(log.t)
            k = int(np.argmax(speed))
            if speed[k] > self.max_speed_mm_per_s:
                raise DriveLogError(
                    f"{src}: column {name!r} ({role}) moves at {speed[k]:g} mm/s at sample index {k + 1}, above "
                    f"{self.max_speed_mm_per_s:g} mm/s; are the positions in um read as mm (length_unit='um') "
                    "or the time in s read as ms? (or override Plausibility.max_speed_mm_per_s)")


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
def _numeric(value, where: str) -> np.ndarray:
    """``value`` as a float64 array; a non-numeric (text, object, complex, structured) one is a DriveLogError."""
    a = np.asarray(value) if not isinstance(value, np.ndarray) else value
    if a.dtype.kind not in "iuf":
        raise DriveLogError(f"{where} holds {a.dtype} data ({a.dtype.kind!r} kind); expected real numbers")
    return np.asarray(a, dtype=np.float64)


def _read_table(path: Path) -> dict[str, np.ndarray]:
    """All columns of a CSV (header line), ``.mat`` or ``.npz`` file as arrays by name.

    Raises:
        DriveLogError: the file cannot be parsed (corrupt or empty archive, non-UTF-8 or ragged CSV, a
            non-numeric cell: named by line and column), or holds no columns.
    """
    suffix = path.suffix.lower()
    if suffix not in (".mat", ".npz", ".csv"):
        raise DriveLogError(f"{path}: unknown drive-log file type {suffix!r}; expected .csv, .mat or .npz")
    try:
        size = path.stat().st_size
    except OSError as e:
        raise DriveLogError(f"{path}: cannot read ({e.strerror or e})") from None
    if size == 0:
        raise DriveLogError(f"{path}: the file is empty; expected a {suffix} drive log")
    if suffix == ".csv":
        raw = _read_csv(path)
    else:
        try:  # third-party parsers raise many types on damaged bytes; every one becomes a DriveLogError
            if suffix == ".mat":
                from scipy.io import loadmat

                raw = {k: v for k, v in loadmat(str(path)).items() if not k.startswith("__")}
            else:
                with np.load(path, allow_pickle=False) as z:
                    raw = {k: z[k] for k in z.files}
        except MemoryError:
            raise
        except Exception as e:  # noqa: BLE001 - re-raised as this package's error, naming the file
            kind = "MATLAB .mat" if suffix == ".mat" else "NumPy .npz"
            raise DriveLogError(f"{path}: not a readable {kind} file ({type(e).__name__}: {e})") from None
    if not raw:
        raise DriveLogError(f"{path}: the file holds no columns; expected t, x_ref, x_act (or the names you pass)")
    return raw


def _read_csv(path: Path) -> dict[str, np.ndarray]:
    try:
        text = path.read_bytes().decode("utf-8")
    except UnicodeDecodeError as e:
        data = path.read_bytes()
        line = data[: e.start].count(b"\n") + 1
        raise DriveLogError(f"{path}:{line}: not UTF-8 text (byte {data[e.start]:#04x}); save the log as UTF-8 CSV") from None
    except OSError as e:
        raise DriveLogError(f"{path}: cannot read ({e.strerror or e})") from None
    lines = text.splitlines()
    header = lines[0].strip() if lines else ""
    names = [h.strip() for h in header.split(",")]
    if not header or any(not n for n in names):
        raise DriveLogError(f"{path}:1: a CSV drive log needs a header line naming every column, got {header!r}")
    dup = next((n for i, n in enumerate(names) if n in names[:i]), None)
    if dup is not None:
        raise DriveLogError(f"{path}:1: column name {dup!r} appears twice in the header; names must be unique")
    rows = []
    for lineno, line in enumerate(lines[1:], start=2):
        if not line.strip() or line.lstrip().startswith("#"):
            continue
        cells = line.split(",")
        if len(cells) != len(names):
            raise DriveLogError(f"{path}:{lineno}: row has {len(cells)} values but the header names "
                                f"{len(names)} columns {names}")
        row = []
        for col, cell in enumerate(cells, start=1):
            try:
                row.append(float(cell))
            except ValueError:
                raise DriveLogError(f"{path}:{lineno}:{col}: column {names[col - 1]!r}: {cell.strip()!r} is not a "
                                    "number; expected a plain decimal number") from None
        rows.append(row)
    if not rows:
        raise DriveLogError(f"{path}: the CSV has a header {names} but no data rows")
    data = np.array(rows, dtype=np.float64)
    return {n: data[:, i] for i, n in enumerate(names)}


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
    plausibility: Plausibility | None = DEFAULT_PLAUSIBILITY,
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
        plausibility: unit-plausibility bounds (:class:`Plausibility`); ``None`` skips the check.
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
    cols = {role: _numeric(raw[name], f"{path}: column {name!r} ({role})") for role, name in wanted.items()}
    units = {"t": "s", "reference": "mm", "actual": "mm"}
    if control is not None:
        units["control"] = control_unit
    return DriveLog(
        t=cols["t"] * T, reference=cols["reference"] * L, actual=cols["actual"] * L, control=cols.get("control"),
        source=str(path), columns=wanted, units=units, uniform_rtol=uniform_rtol, plausibility=plausibility,
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
        path: ``.csv``, ``.mat`` or ``.npz`` file.
        axes: axis name -> ``{"reference": column, "actual": column[, "control": column]}``, e.g.
            ``{"x": {"reference": "X_cmd", "actual": "X_enc"}}``.
        time, time_unit: the shared time column and its unit (``TIME_UNITS``).
        units: column name -> length unit (``LENGTH_UNITS``) for position columns not in mm, e.g.
            ``{"X_cmd": "m", "X_enc": "m"}``; a control column's unit is kept as a label (default "V").
        uniform_rtol, plausibility: as :func:`load_drive_log`; plausibility is checked per axis after the
            unit conversion, so a column in um declared as mm is refused naming that column.
    Returns:
        axis name -> :class:`DriveLog` [s, mm].
    Raises:
        DriveLogError: no axes, an axis without ``reference``/``actual``, an unknown role, column or unit, or
            any failure of :func:`load_drive_log`'s checks; every message names the file.
    """
    path = Path(path)
    units = dict(units or {})
    if not isinstance(axes, dict) or not axes:
        raise DriveLogError(f"{path}: axes must map axis names to their columns, e.g. "
                            f"{{'x': {{'reference': 'X_cmd', 'actual': 'X_enc'}}}}, got {axes!r}")
    if time_unit not in TIME_UNITS:
        raise DriveLogError(f"{path}: unknown time unit {time_unit!r}; expected one of {sorted(TIME_UNITS)}")
    if not path.exists():
        raise DriveLogError(f"{path}: file not found")
    raw = _read_table(path)
    if time not in raw:
        raise DriveLogError(f"{path}: missing time column {time!r}; the file has {sorted(raw)}")
    t = _numeric(raw[time], f"{path}: column {time!r} (t)") * TIME_UNITS[time_unit]
    out = {}
    for axis, cols in axes.items():
        if not isinstance(cols, dict) or not {"reference", "actual"} <= set(cols) or not set(cols) <= {
                "reference", "actual", "control"}:
            raise DriveLogError(f"{path}: axis {axis!r} needs columns {{'reference', 'actual'}} (and optionally "
                                f"'control'), got {cols!r}")
        data, unit_of = {}, {"t": "s"}
        for role, name in cols.items():
            if name not in raw:
                raise DriveLogError(f"{path}: axis {axis!r}: missing column {name!r} for the {role}; the file has "
                                    f"{sorted(raw)}")
            a = _numeric(raw[name], f"{path}: column {name!r} ({role})")
            if role == "control":
                data[role], unit_of[role] = a, units.get(name, "V")
                continue
            u = units.get(name, "mm")
            if u not in LENGTH_UNITS:
                raise DriveLogError(f"{path}: column {name!r} ({role} of axis {axis!r}): unknown length unit {u!r}; "
                                    f"expected one of {sorted(LENGTH_UNITS)}")
            data[role], unit_of[role] = a * LENGTH_UNITS[u], "mm"
        out[axis] = DriveLog(t=t, reference=data["reference"], actual=data["actual"], control=data.get("control"),
                             source=f"{path} axis {axis}", columns={"t": time, **cols}, units=unit_of,
                             uniform_rtol=uniform_rtol, plausibility=plausibility)
    return out
