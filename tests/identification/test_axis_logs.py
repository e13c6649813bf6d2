"""Several axes per file with column mapping and per-column units (issue 14 item 7)."""

import numpy as np
import pytest

from research.errors import DriveLogError
from research.identification import load_axis_logs


def _write(path, cols):
    names = list(cols)
    np.savetxt(path, np.column_stack([cols[n] for n in names]), delimiter=",", header=",".join(names), comments="")
    return path


@pytest.fixture
def trace(tmp_path):
    t = np.arange(500) * 1e-3
    xr = 0.05 * np.sin(2 * np.pi * t)  # metres
    yr = 20.0 * np.sin(2 * np.pi * 2 * t)  # mm
    return t, xr, yr, _write(tmp_path / "trace.csv", {"time_s": t, "X_cmd": xr, "X_enc": 0.999 * xr, "Y_cmd": yr,
                                                        "Y_enc": 0.99 * yr, "Y_cur": np.cos(t)})


def test_two_axes_with_units_and_a_current_column(trace):
    t, xr, yr, path = trace
    logs = load_axis_logs(path, {"x": {"reference": "X_cmd", "actual": "X_enc"},
                                 "y": {"reference": "Y_cmd", "actual": "Y_enc", "control": "Y_cur"}},
                          time="time_s", units={"X_cmd": "m", "X_enc": "m", "Y_cur": "A"})
    np.testing.assert_allclose(logs["x"].reference, 1000 * xr)  # m -> mm, computed here
    np.testing.assert_allclose(logs["y"].actual, 0.99 * yr)
    assert logs["y"].units["control"] == "A" and logs["x"].columns["reference"] == "X_cmd"
    assert "axis y" in logs["y"].source


def test_positions_in_um_declared_as_mm_are_refused_naming_the_column(tmp_path):
    t = np.arange(500) * 1e-3
    xr = 4e6 * t  # 4e6 um/s = 4 m/s, read as mm: 4000 m/s and a 2 km span
    path = _write(tmp_path / "um.csv", {"t": t, "X_cmd": xr, "X_enc": xr})
    with pytest.raises(DriveLogError, match=r"um\.csv.*'X_cmd'.*um"):
        load_axis_logs(path, {"x": {"reference": "X_cmd", "actual": "X_enc"}})


def test_reader_failures_name_the_file(trace, tmp_path):
    *_, path = trace
    with pytest.raises(DriveLogError, match=r"trace\.csv.*missing column 'Z_cmd'"):
        load_axis_logs(path, {"z": {"reference": "Z_cmd", "actual": "X_enc"}}, time="time_s")
    with pytest.raises(DriveLogError, match=r"trace\.csv.*unknown position unit .furlong."):
        load_axis_logs(path, {"x": {"reference": "X_cmd", "actual": "X_enc"}}, time="time_s", units={"X_cmd": "furlong"})
    with pytest.raises(DriveLogError, match=r"trace\.csv.*needs columns"):
        load_axis_logs(path, {"x": {"reference": "X_cmd"}}, time="time_s")
    with pytest.raises(DriveLogError, match=r"trace\.csv.*missing time column 't'"):
        load_axis_logs(path, {"x": {"reference": "X_cmd", "actual": "X_enc"}})
    empty = tmp_path / "empty.npz"
    empty.write_bytes(b"")
    with pytest.raises(DriveLogError, match=r"empty\.npz.*empty"):
        load_axis_logs(empty, {"x": {"reference": "a", "actual": "b"}})
