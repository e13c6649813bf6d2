"""Accelerometer-log reader: column layouts, file types, units, resampling and each bad input (issue 20)."""

import numpy as np
import pytest
from scipy.io import savemat

from research.errors import DriveLogError
from research.vibration import accel_log, load_accel_log, save_accel_log, synthetic_accel_log, TrueMode

G = 9806.65  # mm/s^2 (standard gravity)


@pytest.fixture(scope="module")
def small_log():
    return synthetic_accel_log([TrueMode("x", 30.0, 0.05)], direction=(1, 0, 0), f0=5, f1=60, duration=2.0,
                               rate=800.0, snr_db=30.0, seed=0)


def _write_csv(path, header, data):
    path.write_text(header + "\n" + "\n".join(",".join(f"{v:.10g}" for v in row) for row in data) + "\n")
    return path


def test_klipper_csv_round_trip(tmp_path, small_log):
    """Klipper's raw accelerometer CSV: header '#time,accel_x,accel_y,accel_z', mm/s^2."""
    p = save_accel_log(small_log, tmp_path / "raw.csv")
    assert p.read_text().splitlines()[0] == "#time,accel_x,accel_y,accel_z"
    log = load_accel_log(p)
    assert log.axes == ("x", "y", "z") and log.columns["t"] == "#time"
    np.testing.assert_allclose(log.accel, small_log.accel, rtol=1e-8, atol=1e-6)
    assert log.resampling is None and log.sample_rate == pytest.approx(800.0)


@pytest.mark.parametrize("header,columns", [
    ("time,x,y,z", None),
    ("t,ax,ay,az", None),
    ("stamp_ms,acc_y", {"t": "stamp_ms", "y": "acc_y"}),
])
def test_named_column_variants(tmp_path, small_log, header, columns):
    n = len(header.split(","))
    data = np.column_stack([small_log.t, small_log.accel])[:, :n]
    if columns is not None:  # time in ms, one axis (y) under a custom name
        data = np.column_stack([small_log.t * 1e3, small_log.accel[:, 1]])
    p = _write_csv(tmp_path / "log.csv", header, data)
    log = load_accel_log(p, columns=columns, time_unit="ms" if columns else "s", check_units=columns is None)
    assert log.n_samples == small_log.n_samples
    if columns:
        assert log.axes == ("y",)
        np.testing.assert_allclose(log.column("y"), small_log.accel[:, 1], rtol=1e-8, atol=1e-6)


def test_npz_and_mat(tmp_path, small_log):
    p = save_accel_log(small_log, tmp_path / "log.npz")
    np.testing.assert_allclose(load_accel_log(p).accel, small_log.accel)
    q = tmp_path / "log.mat"
    savemat(q, {"t": small_log.t[:, None], "ax": small_log.accel[:, 0] / 1000.0, "ay": small_log.accel[:, 1] / 1000.0,
                "az": small_log.accel[:, 2] / 1000.0})
    log = load_accel_log(q, unit="m/s^2")
    np.testing.assert_allclose(log.accel, small_log.accel, rtol=1e-12)


def test_units_converted_and_checked(small_log):
    a_g = small_log.accel / G
    np.testing.assert_allclose(accel_log(small_log.t, a_g, unit="g").accel, small_log.accel, rtol=1e-12)
    with pytest.raises(DriveLogError, match="pass unit='g'"):  # a g-log read as mm/s^2: gravity is 1 g only in g
        accel_log(small_log.t, a_g, unit="mm/s^2", source="g.csv")
    with pytest.raises(DriveLogError, match="pass unit='m/s\\^2'"):
        accel_log(small_log.t, small_log.accel / 1000.0, unit="mm/s^2", source="ms2.csv")
    with pytest.raises(DriveLogError, match="above the 200 g"):  # a mm/s^2 log read as g
        accel_log(small_log.t, small_log.accel, unit="g", source="mm.csv")
    with pytest.raises(DriveLogError, match="unknown acceleration unit"):
        accel_log(small_log.t, small_log.accel, unit="gal")


def test_irregular_sampling_is_resampled_and_the_gap_reported(small_log):
    t = small_log.t.copy()
    t[400:] += 0.01  # a 10 ms dropout after sample 399
    log = accel_log(t, small_log.accel, source="gap.csv")
    r = log.resampling
    assert r["method"] == "linear" and r["max_step_s"] == pytest.approx(0.01 + 1 / 800.0)
    assert r["at_time_s"] == pytest.approx(t[399])
    assert np.allclose(np.diff(log.t), 1 / 800.0)


def test_clipped_accelerometer_is_refused(small_log):
    x = small_log.accel.copy()
    top = 0.5 * np.max(x[:, 0])
    x[:, 0] = np.minimum(x[:, 0], top)
    with pytest.raises(DriveLogError, match="clipped"):
        accel_log(small_log.t, x, source="clip.csv")
    with pytest.raises(DriveLogError, match="full scale"):
        accel_log(small_log.t, small_log.accel / G, unit="g", full_scale=0.5 * np.max(np.abs(small_log.accel[:, 0])) / G)


def test_quantized_unclipped_sine_is_accepted():
    """A sine quantized to 3.9 mg steps (ADXL345 full-resolution LSB) is not clipping: its top level holds no
    more samples than a smooth peak allows."""
    t = np.arange(8000) / 3200.0
    lsb = 0.0039 * G
    a = np.round(2000.0 * np.sin(2 * np.pi * 5.0 * t) / lsb) * lsb
    log = accel_log(t, np.column_stack([a, 0 * a, 0 * a + G]), source="quantized.csv")
    assert log.n_samples == 8000


@pytest.mark.parametrize("damage,match", [
    (lambda t, a: (t, np.where(np.arange(a.size).reshape(a.shape) == 30, np.nan, a)), "NaN"),
    (lambda t, a: (np.concatenate([t[:10], t[9:-1]]), a), "not strictly increasing"),
    (lambda t, a: (t[:20], a[:20]), "at least 64 samples"),
])
def test_bad_arrays(small_log, damage, match):
    t, a = damage(small_log.t.copy(), small_log.accel.copy())
    with pytest.raises(DriveLogError, match=match):
        accel_log(t, a)


def test_bad_files(tmp_path, small_log):
    with pytest.raises(DriveLogError, match="file not found"):
        load_accel_log(tmp_path / "missing.csv")
    p = _write_csv(tmp_path / "cols.csv", "t,foo,bar", np.zeros((100, 3)))
    with pytest.raises(DriveLogError, match="no known column layout"):
        load_accel_log(p)
    p = _write_csv(tmp_path / "miss.csv", "t,x", np.zeros((100, 2)))
    with pytest.raises(DriveLogError, match="missing column 'y'"):
        load_accel_log(p, columns={"t": "t", "y": "y"})
    p = tmp_path / "text.csv"
    p.write_text("#time,accel_x,accel_y,accel_z\n0,1,2,3\n0.1,abc,2,3\n")
    with pytest.raises(DriveLogError, match="text.csv:3:2"):
        load_accel_log(p)
