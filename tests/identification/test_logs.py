"""DriveLog loading and validation: every bad input raises DriveLogError naming file, column and index."""

import numpy as np
import pytest
import scipy.io

from research.errors import DriveLogError
from research.identification import (
    DriveLog,
    build_regression,
    load_drive_log,
    save_drive_log,
)


def _arrays(n=400):
    t = np.arange(n) * 1e-3
    xr = 10 * np.sin(2 * np.pi * t)
    return t, xr, xr - 0.01 * np.cos(2 * np.pi * t)


@pytest.mark.parametrize("suffix", [".csv", ".npz"])
def test_round_trip(tmp_path, suffix):
    t, xr, x = _arrays()
    path = save_drive_log(DriveLog(t, xr, x), tmp_path / f"log{suffix}")
    log = load_drive_log(path)
    np.testing.assert_allclose(log.actual, x, rtol=0, atol=1e-12)
    assert log.sample_period == pytest.approx(1e-3) and log.units["actual"] == "mm"


def test_mat_in_metres_is_converted_to_mm(tmp_path):
    t, xr, x = _arrays()
    scipy.io.savemat(tmp_path / "a.mat", {"time": t[:, None], "qg": xr[:, None] / 1000, "qm": x[:, None] / 1000})
    log = load_drive_log(tmp_path / "a.mat", time="time", reference="qg", actual="qm", length_unit="m")
    np.testing.assert_allclose(log.reference, xr, rtol=1e-12)
    assert log.columns == {"t": "time", "reference": "qg", "actual": "qm"}


def test_nan_names_file_column_and_index(tmp_path):
    t, xr, x = _arrays()
    x[123] = np.nan
    np.savez(tmp_path / "bad.npz", t=t, x_ref=xr, x_act=x)
    with pytest.raises(DriveLogError, match=r"bad\.npz.*'x_act'.*sample index 123"):
        load_drive_log(tmp_path / "bad.npz")


def test_non_monotonic_time():
    t, xr, x = _arrays()
    t[50] = t[49]
    with pytest.raises(DriveLogError, match=r"'t' is not strictly increasing at sample index 50"):
        DriveLog(t, xr, x, source="mylog")


def test_jitter_needs_explicit_resampling():
    t, xr, x = _arrays()
    t[200:] += 3e-4
    with pytest.raises(DriveLogError, match=r"not uniformly sampled.*index 200.*resample"):
        DriveLog(t, xr, x)
    tt = np.sort(np.concatenate([t[:200], t[200:]]))
    log = DriveLog(tt, xr, x, uniform_rtol=0.5).resample(1e-3, "linear")
    assert log.resampling == "linear" and np.allclose(np.diff(log.t), 1e-3)


def test_unequal_lengths_missing_column_unknown_type(tmp_path):
    t, xr, x = _arrays()
    with pytest.raises(DriveLogError, match=r"'actual'.*399 samples.*400"):
        DriveLog(t, xr, x[:-1])
    np.savez(tmp_path / "m.npz", t=t, x_ref=xr)
    with pytest.raises(DriveLogError, match=r"missing column 'x_act'.*\['t', 'x_ref'\]"):
        load_drive_log(tmp_path / "m.npz")
    (tmp_path / "x.txt").write_text("1,2,3")
    with pytest.raises(DriveLogError, match=r"unknown drive-log file type '\.txt'"):
        load_drive_log(tmp_path / "x.txt")


def test_not_exciting_enough_reports_condition_number():
    t, xr, x = _arrays(2000)
    with pytest.raises(DriveLogError, match=r"too few"):
        build_regression(DriveLog(t[:250], xr[:250], x[:250]))
    const = np.full(t.size, 5.0)
    with pytest.raises(DriveLogError, match=r"condition number"):
        build_regression(DriveLog(t, const, const))
    ramp = 10.0 * t  # a pure ramp: x'' = x_r'' = 0 and x' = x_r' constant -> rank deficient
    with pytest.raises(DriveLogError, match=r"condition number (inf|\d)"):
        build_regression(DriveLog(t, ramp, ramp - 0.01))
