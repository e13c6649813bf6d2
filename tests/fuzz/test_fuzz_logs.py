"""Fuzz tests of the drive-log readers: random bytes and damaged valid files as ``.csv`` / ``.npz`` /
``.mat``, random arrays as columns.

Only :class:`DriveLogError` may escape ``load_drive_log`` / ``DriveLog``; an accepted log holds finite,
strictly increasing, uniform time and finite positions, and a log written by ``save_drive_log`` reads back
equal (CSV to 1e-12 mm: ``np.savetxt`` writes 18 significant digits).

Examples per test: ``RESEARCH_FUZZ_EXAMPLES`` (default 100; the file runs in a few seconds); set it to
10000 for a long run.
"""

from __future__ import annotations

import io
import os
import tempfile
from pathlib import Path

import numpy as np
import scipy.io
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from research.errors import DriveLogError
from research.identification import DriveLog, load_drive_log, save_drive_log
from research.identification._log import UNIFORM_RTOL

EXAMPLES = int(os.environ.get("RESEARCH_FUZZ_EXAMPLES", "100"))
FUZZ = settings(max_examples=EXAMPLES, deadline=None, derandomize=EXAMPLES <= 200,
                suppress_health_check=[HealthCheck.too_slow])
FOLDER = Path(tempfile.mkdtemp(prefix="fuzz_logs_"))


def _valid_bytes(suffix: str) -> bytes:
    t = np.arange(50) * 1e-3
    xr = 5.0 * np.sin(2 * np.pi * 2 * t)
    if suffix == ".mat":
        buf = io.BytesIO()
        scipy.io.savemat(buf, {"t": t[:, None], "x_ref": xr[:, None], "x_act": xr[:, None] - 1e-3})
        return buf.getvalue()
    f = save_drive_log(DriveLog(t, xr, xr - 1e-3), FOLDER / f"valid{suffix}")
    return f.read_bytes()


VALID = {s: _valid_bytes(s) for s in (".csv", ".npz", ".mat")}


def _accepted(log: DriveLog) -> None:
    dt = np.diff(log.t)
    assert np.all(np.isfinite(log.t)) and np.all(np.isfinite(log.reference)) and np.all(np.isfinite(log.actual))
    assert np.all(dt > 0) and np.max(np.abs(dt - np.median(dt))) <= log.uniform_rtol * np.median(dt)


def _load(name: str, data: bytes):
    f = FOLDER / name
    f.write_bytes(data)
    try:
        log = load_drive_log(f)
    except DriveLogError as e:
        assert str(f) in str(e)
        return None
    _accepted(log)
    return log


@FUZZ
@given(st.sampled_from(sorted(VALID)),
       st.lists(st.tuples(st.floats(0, 1), st.binary(max_size=4)), min_size=1, max_size=4),
       st.floats(0.0, 1.0))
def test_damaged_files_raise_only_drive_log_error(suffix, edits, keep):
    data = bytearray(VALID[suffix])
    for where, new in edits:
        pos = int(where * (len(data) - 1)) if data else 0
        data[pos:pos + 1] = new
    data = bytes(data[: max(1, int(len(data) * keep))]) if keep < 0.9 else bytes(data)
    _load(f"damaged{suffix}", data)


@FUZZ
@given(st.sampled_from([".csv", ".npz", ".mat"]), st.binary(max_size=300))
def test_random_bytes_raise_only_drive_log_error(suffix, data):
    _load(f"random{suffix}", data)


CELLS = st.one_of(st.floats(allow_nan=True, allow_infinity=True).map(repr), st.integers(-10**6, 10**6).map(str),
                  st.sampled_from(["", " ", "nan", "1e400", "abc", "1,2", "0x10", "1_0", "\u00b5", "-", "+1.5e-3"]))


@FUZZ
@given(st.lists(st.lists(CELLS, min_size=1, max_size=4), max_size=8),
       st.sampled_from(["t,x_ref,x_act", "t,x_ref", "t,,x_act", "", "t,x_ref,x_act,t"]))
def test_random_csv_cells_raise_only_drive_log_error(rows, header):
    _load("cells.csv", (header + "\n" + "\n".join(",".join(r) for r in rows) + "\n").encode())


COLUMN = st.one_of(
    arrays(np.float64, st.integers(0, 8)),
    arrays(st.sampled_from([np.int32, np.float32, np.complex128, np.bool_, "U3"]), st.integers(0, 6)),
    arrays(np.float64, st.tuples(st.integers(0, 4), st.integers(0, 3))),
)


@FUZZ
@given(COLUMN, COLUMN, COLUMN, st.floats(allow_nan=True, allow_infinity=True) | st.just(UNIFORM_RTOL))
def test_random_arrays_raise_only_drive_log_error(t, xr, x, rtol):
    try:
        log = DriveLog(t, xr, x, uniform_rtol=rtol)
    except DriveLogError:
        return
    _accepted(log)


@FUZZ
@given(st.integers(3, 60), st.floats(1e-4, 1e-2), st.floats(-5.0, 5.0), st.sampled_from([".csv", ".npz"]), st.data())
def test_valid_logs_round_trip(n, period, t0, suffix, data):
    t = t0 + np.arange(n) * period
    steps = st.lists(st.floats(-1.0, 1.0), min_size=n, max_size=n)  # speeds below 1 m/s: plausible
    xr, x = (data.draw(st.floats(-100.0, 100.0)) + np.cumsum(data.draw(steps)) * period * 1e3 for _ in range(2))
    log = DriveLog(t, xr, x)
    back = load_drive_log(save_drive_log(log, FOLDER / f"rt{suffix}"))
    atol = 1e-12 if suffix == ".csv" else 0.0
    np.testing.assert_allclose(back.t, log.t, rtol=0, atol=atol)
    np.testing.assert_allclose(back.reference, log.reference, rtol=0, atol=atol)
    np.testing.assert_allclose(back.actual, log.actual, rtol=0, atol=atol)


AXIS_SPECS = st.one_of(
    st.just({"x": {"reference": "x_ref", "actual": "x_act"}}),
    st.dictionaries(st.sampled_from(["x", "y", ""]), st.dictionaries(
        st.sampled_from(["reference", "actual", "control", "bogus"]), st.sampled_from(["t", "x_ref", "x_act", "nope"]),
        max_size=4), max_size=3),
    st.sampled_from([None, [], "x", {"x": None}]),
)
UNITS = st.dictionaries(st.sampled_from(["x_ref", "x_act", "t"]), st.sampled_from(["mm", "m", "um", "in", "deg", ""]),
                        max_size=3)


@FUZZ
@given(st.sampled_from(sorted(VALID)), AXIS_SPECS, UNITS, st.sampled_from(["s", "ms", "min"]), st.booleans())
def test_axis_logs_raise_only_drive_log_error_naming_the_file(suffix, axes, units, time_unit, damage):
    """load_axis_logs (several axes, per-column units): any mapping, unit or damaged file gives logs in mm
    that pass the DriveLog checks, or a DriveLogError naming the file."""
    from research.identification import load_axis_logs

    data = bytearray(VALID[suffix])
    if damage:
        data = data[: len(data) // 2]
    f = FOLDER / f"axes{suffix}"
    f.write_bytes(bytes(data))
    try:
        logs = load_axis_logs(f, axes, time_unit=time_unit, units=units)
    except DriveLogError as e:
        assert str(f) in str(e)
        return
    for log in logs.values():
        _accepted(log)
        assert log.units["reference"] == "mm" and log.units["actual"] == "mm"
