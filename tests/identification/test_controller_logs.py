"""Logs of real controllers (issue 14 item 7): LinuxCNC halscope text exports, encoder counts with a stated
resolution, rotary axes in deg, plausibility after conversion, and every reader failure a DriveLogError naming
the file. The halscope layouts are those of LinuxCNC's ``scope_files.c`` ``write_log_file`` (2.9+: ``# Sampling
period is <ns> ns``, a ``;``-separated name line, ``# Position:`` / ``# Scale:`` lines, ``%.14f`` rows; 2.8:
``Sampling period is <ns> nSec`` and ``<name> <%+.14f>`` pairs)."""

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from research.errors import DriveLogError
from research.identification import Plausibility, load_axis_logs, load_drive_log, read_halscope, write_halscope

#: a LinuxCNC 2.9 export written out by hand (1 kHz, two channels, four samples)
NEW = """# Sampling period is 1000000 ns
joint.0.motor-pos-cmd;joint.0.motor-pos-fb
# Position: 0.500000;0.500000
# Scale: 0;0
0.00000000000000;0.00000000000000
0.01000000000000;0.00900000000000
0.02000000000000;0.01800000000000
0.03000000000000;0.02700000000000
"""
#: the same capture as LinuxCNC 2.8 wrote it (blank line after the header, name/value pairs, trailing space)
OLD = """Sampling period is 1000000 nSec 

joint.0.motor-pos-cmd +0.00000000000000 joint.0.motor-pos-fb +0.00000000000000 
joint.0.motor-pos-cmd +0.01000000000000 joint.0.motor-pos-fb +0.00900000000000 
joint.0.motor-pos-cmd +0.02000000000000 joint.0.motor-pos-fb +0.01800000000000 
joint.0.motor-pos-cmd +0.03000000000000 joint.0.motor-pos-fb +0.02700000000000 
"""
CMD, FB = "joint.0.motor-pos-cmd", "joint.0.motor-pos-fb"


@pytest.mark.parametrize("text", [NEW, OLD], ids=["linuxcnc-2.9", "linuxcnc-2.8"])
def test_halscope_text_both_generations(tmp_path, text):
    path = tmp_path / "scope.txt"
    path.write_text(text)
    raw = read_halscope(path)
    np.testing.assert_array_equal(raw["t"], [0.0, 1e-3, 2e-3, 3e-3])  # k * 1 000 000 ns
    np.testing.assert_array_equal(raw[FB], [0.0, 0.009, 0.018, 0.027])
    log = load_drive_log(path, reference=CMD, actual=FB)
    assert log.sample_period == pytest.approx(1e-3) and log.columns["actual"] == FB
    np.testing.assert_allclose(log.tracking_error, [0.0, 0.001, 0.002, 0.003], atol=1e-15)


def test_halscope_written_and_read_back_in_counts_with_a_resolution(tmp_path):
    """A 2-axis 2.9 export with the X encoder in counts (1000 counts/mm) and a rotary C axis in deg."""
    t = np.arange(400) * 5e-4
    x_mm = 20.0 * np.sin(2 * np.pi * 1.5 * t)
    x_counts = np.round(1000 * (x_mm - 0.002))
    c_deg = 90.0 * (1 - np.cos(2 * np.pi * t))
    path = write_halscope(tmp_path / "two_axes.log", {"x-cmd": x_mm, "x-enc": x_counts, "c-cmd": c_deg,
                                                       "c-fb": c_deg - 0.01}, 5e-4)
    logs = load_axis_logs(path, {"x": {"reference": "x-cmd", "actual": "x-enc", "counts_per_mm": 1000},
                                 "c": {"reference": "c-cmd", "actual": "c-fb"}},
                          units={"x-enc": "counts", "c-cmd": "deg", "c-fb": "deg"})
    np.testing.assert_allclose(logs["x"].actual, x_counts / 1000, atol=1e-12)
    np.testing.assert_allclose(logs["c"].reference, c_deg * np.pi / 180, atol=1e-12)
    assert logs["x"].units["actual"] == "mm" and logs["c"].units["actual"] == "rad"
    np.testing.assert_allclose(logs["x"].t, t, atol=1e-15)


def test_counts_without_a_resolution_are_refused_naming_the_column(tmp_path):
    path = tmp_path / "scope.txt"
    path.write_text(NEW.replace("0.00900000000000", "9.00000000000000").replace("0.01800000000000", "18.0")
                    .replace("0.02700000000000", "27.0"))
    with pytest.raises(DriveLogError, match=rf"scope\.txt: column '{FB}' \(actual\).*'counts' needs exactly one "
                                            "resolution"):
        load_drive_log(path, reference=CMD, actual=FB, units={"x_act": "counts"})
    log = load_drive_log(path, reference=CMD, actual=FB, units={"x_act": "counts"}, counts_per_mm=1000)
    np.testing.assert_allclose(log.actual, [0.0, 0.009, 0.018, 0.027])
    with pytest.raises(DriveLogError, match=r"counts_per_mm must be a finite number > 0"):
        load_drive_log(path, reference=CMD, actual=FB, units={"x_act": "counts"}, counts_per_mm=-5)
    with pytest.raises(DriveLogError, match=r"scope\.txt: a counts resolution \{'counts_per_mm': 1000\} is given but neither"):
        load_drive_log(path, reference=CMD, actual=FB, counts_per_mm=1000)


def test_fractional_counts_and_wrong_resolution_are_refused(tmp_path):
    """A column declared in counts holding mm (fractions), and a resolution 1000x too small (the speed check
    after conversion names the column and suggests the resolution)."""
    t = np.arange(300) * 1e-3
    mm = 10.0 * np.sin(2 * np.pi * t)
    path = tmp_path / "enc.csv"
    np.savetxt(path, np.column_stack([t, mm, mm]), delimiter=",", header="t,cmd,enc", comments="")
    with pytest.raises(DriveLogError, match=r"enc\.csv: column 'enc' \(actual\): declared 'counts' but sample index 1"):
        load_drive_log(path, reference="cmd", actual="enc", units={"x_act": "counts"}, counts_per_mm=1000)
    counts = np.round(mm * 1e4)  # 10 000 counts/mm, declared as 10 counts/mm: positions 1000x too large
    np.savetxt(path, np.column_stack([t, mm, counts]), delimiter=",", header="t,cmd,enc", comments="")
    with pytest.raises(DriveLogError, match=r"column 'enc' \(actual\) (moves at|spans).*counts_per_mm"):
        load_drive_log(path, reference="cmd", actual="enc", units={"x_act": "counts"}, counts_per_mm=10)
    log = load_drive_log(path, reference="cmd", actual="enc", units={"x_act": "counts"}, counts_per_mm=1e4)
    assert np.max(np.abs(log.tracking_error)) <= 0.5e-4 + 1e-12  # half a count
    frac = load_drive_log(path, reference="cmd", actual="enc", units={"x_act": "counts"}, counts_per_mm=1e4,
                          plausibility=Plausibility(integer_counts=False))
    assert frac.n_samples == 300


def test_rotary_plausibility_and_mixed_units(tmp_path):
    t = np.arange(500) * 1e-3
    deg = 3000.0 * t  # 3000 deg/s = 52 rad/s: a plausible table; read as rad it is 3000 rad/s (28 600 rpm)
    path = tmp_path / "c.npz"
    np.savez(path, t=t, cmd=deg, fb=deg)
    assert load_drive_log(path, reference="cmd", actual="fb", length_unit="deg").units["reference"] == "rad"
    with pytest.raises(DriveLogError, match=r"c\.npz: column 'cmd' \(reference\) moves at 3000 rad/s.*deg read as rad"):
        load_drive_log(path, reference="cmd", actual="fb", length_unit="rad")
    with pytest.raises(DriveLogError, match=r"c\.npz: the reference 'cmd' is in mm but the measured position 'fb' in rad"):
        load_drive_log(path, reference="cmd", actual="fb", units={"x_act": "deg"})
    with pytest.raises(DriveLogError, match=r"units keys \['t'\] are not position roles"):
        load_drive_log(path, reference="cmd", actual="fb", units={"t": "ms"})


@pytest.mark.parametrize("text, match", [
    (NEW.rstrip("\n") + "\n0.04000000000000\n", r"scope\.txt:9: row has 1 values but line 2 names 2 channels.*truncated"),
    (NEW.replace("0.01800000000000\n", "0.018000abc\n"), rf"scope\.txt:7:2: column '{FB}': '0\.018000abc' is not a number"),
    (OLD + "joint.0.motor-pos-cmd +0.04\n", r"scope\.txt:7: channels \['joint\.0\.motor-pos-cmd'\] differ.*truncated"),
    (OLD + "joint.0.motor-pos-cmd +0.04 joint.0.motor-pos-f\n", r"scope\.txt:7: 3 tokens.*truncated"),
    ("# Sampling period is 1000000 ns\n" + CMD + ";" + FB + "\n", r"scope\.txt: the halscope file names channels .* no samples"),
    ("# Sampling period is 0 ns\na;b\n1;2\n", r"scope\.txt:1: halscope sample period 0 ns must be > 0"),
    ("# Sampling period is 1e6 ns\na;b\n1;2\n", r"scope\.txt:1: halscope sample period '1e6' is not an integer"),
    ("# Sampling period is 1000 ns\nt;x\n1;2\n", r"scope\.txt: a halscope channel is named 't'"),
    ("# Sampling period is 1000 ns\na;a\n1;2\n", r"scope\.txt:2: column name 'a' appears twice"),
    ("time,x\n0,1\n", r"scope\.txt:1: not a halscope text export"),
])
def test_halscope_failures_name_file_and_line(tmp_path, text, match):
    path = tmp_path / "scope.txt"
    path.write_text(text)
    with pytest.raises(DriveLogError, match=match):
        load_drive_log(path, reference=CMD, actual=FB)


def test_empty_and_non_utf8_halscope_files(tmp_path):
    empty = tmp_path / "e.log"
    empty.write_bytes(b"")
    with pytest.raises(DriveLogError, match=r"e\.log: the file is empty"):
        load_drive_log(empty)
    bad = tmp_path / "b.log"
    bad.write_bytes(b"# Sampling period is 1000 ns\na;b\n\xff;1\n")
    with pytest.raises(DriveLogError, match=r"b\.log:3: not UTF-8"):
        load_drive_log(bad)


@settings(max_examples=60, deadline=None, derandomize=True, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(cut=st.integers(0, len(NEW)), junk=st.binary(max_size=20))
def test_damaged_halscope_exports_raise_only_drive_log_errors(tmp_path, cut, junk):
    """A valid export cut anywhere and followed by random bytes: it loads (a cut at a row boundary) or raises a
    DriveLogError naming the file, never another exception."""
    path = tmp_path / "fuzz.txt"
    path.write_bytes(NEW.encode()[:cut] + junk)
    try:
        log = load_drive_log(path, reference=CMD, actual=FB, plausibility=None)
    except DriveLogError as e:
        assert "fuzz.txt" in str(e)
    else:
        assert log.n_samples >= 3 and np.all(np.isfinite(log.actual))
