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
from research.identification._log import Plausibility


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
    (tmp_path / "x.xlsx").write_text("1,2,3")
    with pytest.raises(DriveLogError, match=r"unknown drive-log file type '\.xlsx'"):
        load_drive_log(tmp_path / "x.xlsx")
    (tmp_path / "x.txt").write_text("1,2,3")  # .txt is a halscope export: its first line must say so
    with pytest.raises(DriveLogError, match=r"x\.txt:1: not a halscope text export.*'1,2,3'"):
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


# -- readers raise only DriveLogError (issue: fuzz-proof readers) -----------------------------------------
def _good_npz(tmp_path):
    t, xr, x = _arrays()
    return save_drive_log(DriveLog(t, xr, x), tmp_path / "good.npz")


@pytest.mark.parametrize("name, content, match", [  # item 12
    ("trunc.npz", lambda p: _good_npz(p).read_bytes()[:200], r"trunc\.npz: not a readable NumPy \.npz file"),
    ("empty.npz", lambda p: b"", r"empty\.npz: the file is empty"),
    ("empty.mat", lambda p: b"", r"empty\.mat: the file is empty"),
    ("junk.mat", lambda p: b"MATLAB 5.0 MAT-file" + bytes(range(256)) * 2, r"junk\.mat: not a readable MATLAB \.mat file"),
    ("latin1.csv", lambda p: "t,x_ref,x_act\n0,1,2 \xb5m\n".encode("latin-1"), r"latin1\.csv:2: not UTF-8"),
    ("header.csv", lambda p: b"t,x_ref,x_act\n", r"header\.csv: the CSV has a header .* but no data rows"),
    ("cell.csv", lambda p: b"t,x_ref,x_act\n0,1,2\n0.001,abc,2\n", r"cell\.csv:3:2: column 'x_ref': 'abc' is not a number"),
    ("ragged.csv", lambda p: b"t,x_ref,x_act\n0,1,2\n0.001,1\n", r"ragged\.csv:3: row has 2 values but the header names 3"),
    ("dup.csv", lambda p: b"t,x_act,x_act\n0,1,2\n", r"dup\.csv:1: column name 'x_act' appears twice"),
])
def test_corrupt_files_raise_drive_log_error_naming_the_file(tmp_path, name, content, match):
    f = tmp_path / name
    f.write_bytes(content(tmp_path))
    with pytest.raises(DriveLogError, match=match):
        load_drive_log(f)


def test_object_and_text_columns_are_drive_log_errors(tmp_path):  # item 12
    t, xr, x = _arrays()
    np.savez(tmp_path / "text.npz", t=t, x_ref=xr.astype(str), x_act=x)
    with pytest.raises(DriveLogError, match=r"text\.npz: column 'x_ref' \(reference\) holds <U\d+ data.*real numbers"):
        load_drive_log(tmp_path / "text.npz")
    scipy.io.savemat(tmp_path / "cell.mat", {"t": t[:, None], "x_ref": np.array([["a"], [1.0]], dtype=object), "x_act": x[:, None]})
    with pytest.raises(DriveLogError, match=r"cell\.mat"):
        load_drive_log(tmp_path / "cell.mat")


def test_negative_seed_is_a_parameter_error():  # item 13
    from research.errors import ParameterError
    from research.identification import identification_program

    with pytest.raises(ParameterError, match=r"seed must be an int >= 0.*-1"):
        identification_program(-1)
    with pytest.raises(ParameterError, match=r"n_moves must be an int >= 1"):
        identification_program(0, n_moves=2.5)


def test_synthetic_log_refuses_a_two_axis_reference():  # item 14
    from research.drives import table_6_1_closed_loop
    from research.identification import synthetic_log
    from research.trajectory import Trajectory

    t = np.arange(200) * 1e-3
    ref = Trajectory.from_positions(t, np.column_stack([np.sin(t), np.cos(t)]), axes=("x", "y"))
    with pytest.raises(DriveLogError, match=r"2 axes \('x', 'y'\).*one-axis reference"):
        synthetic_log(table_6_1_closed_loop(), ref)


@pytest.mark.parametrize("rtol", [float("nan"), float("inf"), -1e-3, "0.1", True])
def test_uniform_rtol_must_be_finite_and_non_negative(rtol):  # item 15
    t, xr, x = _arrays()
    t[200:] += 3e-4  # not uniform: a NaN tolerance used to accept it
    with pytest.raises(DriveLogError, match=r"uniform_rtol must be a finite number >= 0"):
        DriveLog(t, xr, x, uniform_rtol=rtol)


def test_um_read_as_mm_and_ms_read_as_s_are_refused(tmp_path):  # item 16
    t = np.arange(2000) * 1e-3
    xr = 50.0 * np.sin(2 * np.pi * 0.5 * t)  # +-50 mm, peak 157 mm/s
    np.savez(tmp_path / "um.npz", t=t, x_ref=xr * 1e3, x_act=xr * 1e3)  # file in um
    with pytest.raises(DriveLogError, match=r"column 'x_ref' \(reference\) spans 100000 mm.*length_unit='um'"):
        load_drive_log(tmp_path / "um.npz")
    assert load_drive_log(tmp_path / "um.npz", length_unit="um").reference == pytest.approx(xr, abs=1e-9)
    small = 0.5 * np.sin(2 * np.pi * 5 * t)  # 1 mm span, peak 15.7 mm/s: in um read as mm, 1 m and 15.7 m/s
    np.savez(tmp_path / "um_small.npz", t=t, x_ref=small * 1e3, x_act=small * 1e3)
    with pytest.raises(DriveLogError, match=r"moves at .* mm/s .*um read as mm"):
        load_drive_log(tmp_path / "um_small.npz", plausibility=Plausibility(max_speed_mm_per_s=10_000.0))
    np.savez(tmp_path / "ms.npz", t=t * 1e3, x_ref=xr, x_act=xr)  # time in ms
    with pytest.raises(DriveLogError, match=r"column 't' \(t\): sample period 1 s .*time_unit='ms'"):
        load_drive_log(tmp_path / "ms.npz")
    assert load_drive_log(tmp_path / "ms.npz", time_unit="ms").sample_period == pytest.approx(1e-3)
    # the bounds are the caller's to move
    assert load_drive_log(tmp_path / "ms.npz", plausibility=Plausibility(max_sample_period_s=2.0)).n_samples == 2000
    assert load_drive_log(tmp_path / "um.npz", plausibility=None).n_samples == 2000


def test_spreadsheet_csv_dialects_read_the_same_log(tmp_path):
    """Spreadsheet exports: a UTF-8 byte-order mark, ';' or tab separators, and with ';' the decimal
    comma of locales that write one ("0,5"). Each reads the same samples as the plain CSV (the cells
    written with repr, so exactly); a comma cell in a ',' file stays an error naming line and column."""
    t, xr, x = _arrays()
    rows = list(zip(t, xr, x))
    dialects = {
        "plain.csv": ("t,x_ref,x_act\n", lambda r: ",".join(repr(float(v)) for v in r)),
        "bom.csv": ("\ufefft,x_ref,x_act\n", lambda r: ",".join(repr(float(v)) for v in r)),
        "semicolon.csv": ("t;x_ref;x_act\n", lambda r: ";".join(repr(float(v)).replace(".", ",") for v in r)),
        "tab.csv": ("t\tx_ref\tx_act\n", lambda r: "\t".join(repr(float(v)) for v in r)),
    }
    for name, (head, line) in dialects.items():
        (tmp_path / name).write_text(head + "\n".join(line(r) for r in rows) + "\n", encoding="utf-8")
        log = load_drive_log(tmp_path / name)
        np.testing.assert_array_equal(log.actual, x)
        np.testing.assert_array_equal(log.reference, xr)
    (tmp_path / "bad.csv").write_text("t,x_ref,x_act\n0,0,0\n0,001,0,0\n")
    with pytest.raises(DriveLogError, match=r"bad.csv:3: row has 4 values"):
        load_drive_log(tmp_path / "bad.csv")


def test_header_only_csv_names_the_real_problem(tmp_path):  # item 17
    (tmp_path / "h.csv").write_text("t,x_ref,x_act\n")
    with pytest.raises(DriveLogError, match=r"no data rows") as e:
        load_drive_log(tmp_path / "h.csv")
    assert "rows have" not in str(e.value)


def test_logs_and_least_squares_load_without_jax():
    """The JAX-free parts of the package (log loading and validation, the eq 6.12 least squares, the
    simulation-error fit, the model store) import neither JAX nor optimistix; JAX-backed names still resolve
    through the lazy package ``__init__``, and every public name has a home."""
    import os
    import subprocess
    import sys
    from pathlib import Path

    import research.identification as ident

    code = ("import sys; import research.identification as i; bare = 'jax' in sys.modules; "
            "from research.identification import DriveLog, build_regression, least_squares, load_drive_log, "
            "load_identified, particle_swarm, simulation_error_fit; "
            "print('LOADED', bare, sorted(m for m in ('jax', 'optimistix', 'research.drives') if m in sys.modules))")
    repo = Path(__file__).resolve().parents[2]
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True, cwd=repo,
                         env={**os.environ, "PYTHONPATH": str(repo)}).stdout
    assert "LOADED False []" in out, out
    assert set(ident.__all__) == set(ident._EXPORTS) and set(ident.__all__) <= set(dir(ident))
    assert callable(ident.bounded_fit) and ident.fit_report.__module__ == "research.identification._report"
    with pytest.raises(AttributeError, match="no attribute 'not_a_name'"):
        ident.not_a_name
