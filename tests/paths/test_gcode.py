"""Tests of the G-code reader/writer `research.paths.gcode`."""

from __future__ import annotations

import math
import re
import time

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from research.errors import GCodeError, ParameterError
from research.paths.gcode import GCodeProgram, ZERO_LENGTH_MM, parse_gcode, read_gcode, to_gcode
from research.paths.polyline import Polyline


def pts(prog: GCodeProgram) -> np.ndarray:
    return prog.polyline.points


# -- linear moves, modal state, feeds ------------------------------------------------------------
def test_g0_g1_modal_feeds_lines():
    prog = parse_gcode("G21 G90\nG1 X10 F600\nY5\nG0 Z2\nX0\nG1 X-5 F1200\n")
    np.testing.assert_array_equal(pts(prog), [[0, 0, 0], [10, 0, 0], [10, 5, 0], [10, 5, 2], [0, 5, 2], [-5, 5, 2]])
    np.testing.assert_allclose(prog.feeds, [10, 10, 250, 250, 20])  # mm/s
    assert prog.rapid.tolist() == [False, False, True, True, False]
    assert prog.lines.tolist() == [2, 3, 4, 5, 6]
    assert prog.source == "<string>" and prog.no_motion_lines == ()
    assert prog.polyline.axes == ("x", "y", "z") and prog.polyline.dim == 3
    assert prog.n_segments == 5
    np.testing.assert_allclose(prog.nominal_durations[0], 1.0)


def test_rapid_feed_initial_feed_and_start():
    prog = parse_gcode("G0 X1\nG1 X2\nF60 X3", rapid_feed=6000, initial_feed=120, start=(0, 0, 5))
    np.testing.assert_array_equal(pts(prog)[0], [0, 0, 5])
    np.testing.assert_allclose(prog.feeds, [100, 2, 1])


def test_feed_is_modal_across_g0_and_f_without_motion():
    prog = parse_gcode("F300\nG1 X1\nG0 X2\nG1 X3")
    np.testing.assert_allclose(prog.feeds, [5, 250, 5])


def test_results_are_read_only():
    prog = parse_gcode("G1 X1 F60")
    for a in (prog.feeds, prog.rapid, prog.lines, prog.polyline.points):
        with pytest.raises(ValueError):
            a[0] = 0
    with pytest.raises(AttributeError):
        prog.source = "x"


# -- lexical features ---------------------------------------------------------------------------
def test_comments_percent_blank_lines_case_no_spaces_and_line_numbers():
    text = (
        "%\n"
        "O1234 (PART: bracket; op 1)\n"
        "\n"
        "N10 G21 G90 G17 G40 G49 G80 G94 G54 ; setup\r\n"
        "N20 T1 M6\n"
        "N30 S12000 M3 M8\n"
        "   \t\n"
        "N40 g0 z5.\n"
        "N50G1X10Y5F600(no spaces at all)\n"
        "n60 x.5 y-.25 ( lower case )\n"
        "N70 G01 X+1.0\n"
        "N80 G61 G59 G91.1\nN85 G64\nN86 G61.1\n"
        "N90 M9 M5\n"
        "N100 M30\n"
        "%\n"
    )
    prog = parse_gcode(text)
    np.testing.assert_array_equal(pts(prog), [[0, 0, 0], [0, 0, 5], [10, 5, 5], [0.5, -0.25, 5], [1, -0.25, 5]])
    assert prog.lines.tolist() == [8, 9, 10, 11]
    np.testing.assert_allclose(prog.feeds, [250, 10, 10, 10])


def test_m2_ends_program_but_trailing_non_motion_lines_are_fine():
    prog = parse_gcode("G1 X1 F60 M2\nM5 (after end)\n%\n")
    assert prog.n_segments == 1


# -- units and distance modes ---------------------------------------------------------------------
def test_g20_converts_coordinates_and_feed():
    prog = parse_gcode("G20 G90\nG1 X1 Y2 F10\nG21 X1")
    np.testing.assert_allclose(pts(prog), [[0, 0, 0], [25.4, 50.8, 0], [1, 50.8, 0]], rtol=0, atol=1e-12)
    # F10 in/min = 254 mm/min; the physical feed stays after G21 until the next F word
    np.testing.assert_allclose(prog.feeds, [254 / 60, 254 / 60])


def test_g91_incremental_and_g20_g91_combined():
    prog = parse_gcode("G91 G21\nG1 X1 Y1 F60\nX1\nG20 Y1\nG90 G21 X0")
    np.testing.assert_allclose(pts(prog), [[0, 0, 0], [1, 1, 0], [2, 1, 0], [2, 26.4, 0], [0, 26.4, 0]], atol=1e-12)


def test_g91_start_offset():
    prog = parse_gcode("G91 G0 X1 Z-1", start=(10, 20, 30))
    np.testing.assert_array_equal(pts(prog), [[10, 20, 30], [11, 20, 29]])


def test_f_on_g20_line_uses_inches():
    prog = parse_gcode("G20 F1 G1 X1")
    np.testing.assert_allclose(prog.feeds, [25.4 / 60])


# -- no-motion lines --------------------------------------------------------------------------
def test_zero_length_moves_are_recorded_not_dropped_silently():
    prog = parse_gcode("G1 X0 F60\nX5\nX5\nG91 Y0\nG90 G0 X5 Y0 Z0\nX6\nG91 X0.0000000001\n")
    np.testing.assert_array_equal(pts(prog), [[0, 0, 0], [5, 0, 0], [6, 0, 0]])
    assert prog.no_motion_lines == (1, 3, 4, 5, 7)
    assert prog.lines.tolist() == [2, 6]


def test_many_tiny_incremental_moves_accumulate_into_a_segment():
    text = "G91 F60\n" + "G1 X0.0000000004\n" * 5 + "X1"
    prog = parse_gcode(text)
    # distances from the last vertex: 0.4e-9, 0.8e-9 (none), 1.2e-9 (segment), 0.4e-9, 0.8e-9 (none)
    assert ZERO_LENGTH_MM == 1e-9
    assert prog.no_motion_lines == (2, 3, 5, 6)
    assert prog.lines.tolist() == [4, 7]
    np.testing.assert_allclose(pts(prog)[1:, 0], [1.2e-9, 1 + 2e-9], rtol=1e-9)  # commanded position kept


def test_program_without_motion_is_an_error():
    with pytest.raises(GCodeError, match="no motion"):
        parse_gcode("G21 G90\nM3 S100\nG0 X0\n")
    with pytest.raises(GCodeError, match="no motion"):
        parse_gcode("")


# -- arcs ---------------------------------------------------------------------------------------
def _sagittas(points_xy, centre, r):
    mid = 0.5 * (points_xy[1:] + points_xy[:-1])
    return r - np.linalg.norm(mid - centre, axis=1)


@pytest.mark.parametrize("tol", [1e-1, 1e-3, 1e-5])
@pytest.mark.parametrize("r", [0.5, 10.0, 300.0])
def test_arc_chord_tolerance_and_radius(tol, r):
    prog = parse_gcode(f"G1 X{r} F600\nG3 X0 Y{r} I{-r} J0\nG3 X{-r} Y0 I0 J{-r}", chord_tolerance=tol)
    arc = pts(prog)[1:]
    radii = np.linalg.norm(arc[:, :2], axis=1)
    np.testing.assert_allclose(radii, r, rtol=0, atol=1e-9)
    s = _sagittas(arc[:, :2], np.zeros(2), r)
    assert s.max() <= tol * (1 + 1e-9)
    # the chord count is the smallest allowed by 2 acos(1 - tol / r) (or the 90 deg cap)
    dmax = min(2 * math.acos(1 - tol / r), math.pi / 2)
    assert prog.n_segments - 1 == 2 * math.ceil((math.pi / 2) / dmax - 1e-9)
    assert np.all(arc[:, 1] >= -1e-12)  # CCW from (r, 0) through the upper half plane
    np.testing.assert_array_equal(arc[-1], [-r, 0, 0])


def test_g2_is_clockwise_and_g3_counterclockwise():
    cw = pts(parse_gcode("G0 X10\nG2 X0 Y-10 I-10 F600"))[2:-1]
    ccw = pts(parse_gcode("G0 X10\nG3 X0 Y-10 I-10 F600"))[2:-1]
    assert np.all(cw[:, 0] > 0) and np.all(cw[:, 1] < 0)  # 90 deg through the 4th quadrant
    assert np.any(ccw[:, 0] < 0) and np.any(ccw[:, 1] > 0)  # 270 deg the long way round
    lc = Polyline(pts(parse_gcode("G0 X10\nG2 X0 Y-10 I-10 F600"))[1:]).length
    lcc = Polyline(pts(parse_gcode("G0 X10\nG3 X0 Y-10 I-10 F600"))[1:]).length
    np.testing.assert_allclose([lc, lcc], [5 * math.pi, 15 * math.pi], rtol=1e-4)  # chords are shorter


@pytest.mark.parametrize("word, sweep", [("R10", 0.5 * math.pi), ("R-10", 1.5 * math.pi)])
@pytest.mark.parametrize("g", ["G2", "G3"])
def test_r_format_short_and_long_arcs(word, sweep, g):
    prog = parse_gcode(f"G0 X10\n{g} X0 Y-10 {word} F600", chord_tolerance=1e-6)
    arc = pts(prog)[1:, :2]
    # centre: the point at distance 10 from both ends, on the side implied by direction and R's sign
    cands = np.array([[0.0, 0.0], [10.0, -10.0]])
    centre = cands[np.argmin([np.ptp(np.linalg.norm(arc - c, axis=1)) for c in cands])]
    np.testing.assert_allclose(np.linalg.norm(arc - centre, axis=1), 10, atol=1e-9)
    length = Polyline(arc).length
    np.testing.assert_allclose(length, 10 * sweep, rtol=1e-5)
    ang = np.unwrap(np.arctan2(arc[:, 1] - centre[1], arc[:, 0] - centre[0]))
    assert np.all(np.diff(ang) < 0) if g == "G2" else np.all(np.diff(ang) > 0)


def test_semicircle_with_r():
    arc = pts(parse_gcode("G0 X10\nG3 X-10 R10 F60", chord_tolerance=1e-4))[1:]
    np.testing.assert_allclose(np.linalg.norm(arc[:, :2], axis=1), 10, atol=1e-6)
    assert np.all(arc[:, 1] >= -1e-9)


def test_full_circle_and_helix():
    prog = parse_gcode("G0 X5\nG2 I-5 Z-2 F600\nG3 X5 Y0 I-5 J0", chord_tolerance=1e-3)
    arc1 = pts(prog)[1:][prog.lines == 2]
    np.testing.assert_allclose(np.linalg.norm(arc1[:, :2], axis=1), 5, atol=1e-9)
    np.testing.assert_array_equal(arc1[-1], [5, 0, -2])
    # Z is linear in the swept angle
    ang = np.unwrap(np.concatenate([[0.0], np.arctan2(arc1[:, 1], arc1[:, 0])]))
    z = np.concatenate([[0.0], arc1[:, 2]])
    np.testing.assert_allclose(z, -2 * ang / ang[-1], atol=1e-12)
    assert ang[-1] < 0 and ang[-1] == pytest.approx(-2 * math.pi)
    # second line: full CCW circle at constant Z
    arc2 = pts(prog)[1:][prog.lines == 3]
    np.testing.assert_allclose(arc2[:, 2], -2)
    np.testing.assert_allclose(Polyline(np.vstack([arc1[-1], arc2])).length, 10 * math.pi, rtol=1e-4)
    assert prog.no_motion_lines == ()


def test_g90_1_absolute_centre_and_g20_arc():
    a = pts(parse_gcode("G0 X10 Y10\nG90.1 G3 X0 Y20 I0 J10 F60"))
    b = pts(parse_gcode("G0 X10 Y10\nG3 X0 Y20 I-10 J0 F60"))
    np.testing.assert_allclose(a, b, atol=1e-12)
    inch = pts(parse_gcode("G20 G0 X1\nG3 X0 Y1 I-1 F1", chord_tolerance=1e-3))[1:]
    np.testing.assert_allclose(np.linalg.norm(inch[:, :2], axis=1), 25.4, atol=1e-9)


def test_lines_after_the_program_end_are_not_read_but_listed():
    """LinuxCNC (G-code overview): "Lines of a file that occur after the end of a program are not to
    be executed. The interpreter does not even read them", and of a file opened by a '%' line, "The
    useful contents of a file demarcated by percents stop after the second percent line. Anything
    after that is ignored." Text after M2 / M30 / the closing '%', even malformed, is not read; its
    non-blank lines are listed in ``unread_lines`` and ``end_line`` names where reading stopped. A
    '%' that did not open the file ends nothing; a UTF-8 byte-order mark is not an error."""
    prog = parse_gcode("G0 X1\nG1 X2 F60 M30\n\nG0 X9 (motion after the end)\nthis is not G-code\n")
    assert prog.polyline.points[-1].tolist() == [2.0, 0.0, 0.0]
    assert prog.end_line == 2 and prog.unread_lines == (4, 5)
    prog = parse_gcode("\n%\nG1 X1 F60\n%\nO0002 (a second program)\nG0 X5 #1\n")
    assert prog.polyline.points[-1].tolist() == [1.0, 0.0, 0.0]
    assert prog.end_line == 4 and prog.unread_lines == (5, 6)
    prog = parse_gcode("G1 X1 F60\n%\nG1 X3\n")  # no opening '%': this one ends nothing
    assert prog.polyline.points[-1].tolist() == [3.0, 0.0, 0.0] and prog.end_line == 0 and prog.unread_lines == ()
    prog = parse_gcode("\ufeffG21 G90\nG1 X4 F60\nM2\n")
    assert prog.polyline.points[-1].tolist() == [4.0, 0.0, 0.0] and prog.end_line == 3 and prog.unread_lines == ()


def test_arc_radius_tolerance_is_linuxcnc_default():
    """Default end-radius rule = LinuxCNC's G2/G3 documentation: "It is an error if ... [the radii
    differ] by more than (.05 inch/.5 mm) OR ((.0005 inch/.005mm) AND .1% of radius)", with
    interp_internal.hh's absolute tolerance CENTER_ARC_RADIUS_TOLERANCE_MM = 2 * 0.01 * sqrt(2) =
    0.02828 mm and the hard limit 100 times it (2.828 mm). Cases on either side of each limit:
    r = 1: 0.02 mm (2 %) accepted (below the absolute tolerance); r = 10: 0.03 mm (0.3 %) refused;
    r = 50: 0.03 mm (0.06 %) accepted and blended to end exactly; r = 2000: 2.9 mm (0.14 %) refused,
    r = 3000: 2.9 mm (0.097 %) refused by the hard limit, 2.8 mm accepted."""
    prog = parse_gcode("G0 X1\nG3 X0 Y1.02 I-1 F60")
    np.testing.assert_array_equal(pts(prog)[-1], [0, 1.02, 0])
    with pytest.raises(GCodeError, match=r"<string>:2:14: G3 end point is not on the arc: start radius 10 mm and "
                                         r"end radius 10.03 mm"):
        parse_gcode("G0 X10\nG3 X0 Y10.03 I-10 F60")
    prog = parse_gcode("G0 X50\nG3 X0 Y50.03 I-50 F60")
    np.testing.assert_array_equal(pts(prog)[-1], [0, 50.03, 0])
    for text in ("G0 X2000\nG3 X0 Y2002.9 I-2000 F60", "G0 X3000\nG3 X0 Y3002.9 I-3000 F60"):
        with pytest.raises(GCodeError, match="not on the arc"):
            parse_gcode(text)
    parse_gcode("G0 X3000\nG3 X0 Y3002.8 I-3000 F60")
    # an explicit absolute tolerance replaces LinuxCNC's in the same rule (here looser, then stricter)
    parse_gcode("G0 X10\nG3 X0 Y10.03 I-10 F60", arc_radius_tolerance=0.05)
    with pytest.raises(GCodeError, match="not on the arc"):
        parse_gcode("G0 X1\nG3 X0 Y1.002 I-1 F60", arc_radius_tolerance=1e-3)
    # an absolute limit alone: a tiny relative tolerance
    with pytest.raises(GCodeError, match="not on the arc"):
        parse_gcode("G0 X50\nG3 X0 Y50.03 I-50 F60", arc_relative_tolerance=1e-12)


def test_small_arcs_written_to_three_decimals_are_read():
    """LinuxCNC's G2/G3 documentation: "an error due to rounding can result from using a precision of
    less than ... 3 decimal places (0.000) for millimeters", so 3 decimals must be read. Arcs of
    radius 0.3-3 mm with start, end and centre offsets rounded to 3 decimals (radius error up to
    about 2 * 0.0005 * sqrt(2) = 1.4 um, up to 0.5 % of 0.3 mm): every one is read, and its end is
    the programmed point."""
    rng = np.random.default_rng(7)
    for radius in (0.3, 0.75, 1.5, 3.0):
        for _ in range(50):
            c = rng.uniform(-50, 50, 2)
            a0, a1 = rng.uniform(0, 2 * np.pi, 2)
            s = np.round(c + radius * np.array([np.cos(a0), np.sin(a0)]), 3)
            e = np.round(c + radius * np.array([np.cos(a1), np.sin(a1)]), 3)
            ij = np.round(c - s, 3)
            prog = parse_gcode(f"G0 X{s[0]:.3f} Y{s[1]:.3f}\nG3 X{e[0]:.3f} Y{e[1]:.3f} I{ij[0]:.3f} "
                               f"J{ij[1]:.3f} F600")
            np.testing.assert_allclose(pts(prog)[-1, :2], e, atol=1e-12)


def test_arc_feeds_and_lines():
    prog = parse_gcode("G1 X1 F60\nG2 X2 R0.5 F120")
    assert prog.lines.tolist()[0] == 1 and set(prog.lines.tolist()[1:]) == {2}
    np.testing.assert_allclose(prog.feeds[1:], 2)
    assert not prog.rapid.any()


# -- errors: line and column named -------------------------------------------------------------
BAD = [
    # (text, line, column, fragment of the message)
    ("G1 X1.2.3 F100", 1, 4, "X1.2.3"),
    ("G0 X1\nG0 X", 2, 4, "not followed by a number"),
    ("F100\nG1 X1 (unclosed", 2, 7, "not closed"),
    ("G0 X1 (a (b) c)", 1, 10, "nested"),  # at the inner "("
    ("G0 X1 )", 1, 7, "')'"),
    ("G0 X1 # 3", 1, 7, "parameters (# 3) are not supported"),  # was "unexpected character" before #-diagnosis
    ("G0 X1\n  G18.1", 2, 3, "G18.1"),  # G18 / G19 are accepted since arcs work in all three planes
    ("G19.1 G0 X1", 1, 1, "G19.1"),
    ("G0 X1\nG41 D1 X2", 2, 1, "G41"),
    ("G42 X2", 1, 1, "G42"),
    ("G43.1 Z1", 1, 1, "G43.1"),
    ("G0 X1 H1", 1, 7, "H word with no G43"),
    ("G43 H1.5", 1, 5, "H1.5"),
    ("G0 Z5\nG81 X1 Y1 Z-1 R2 F100", 2, 1, "canned cycle G81"),
    ("G83 X1 Y1 Z-1 R2 Q1", 1, 1, "canned cycle G83"),
    ("G93 G1 X1 F2", 1, 1, "inverse-time"),
    ("G4", 1, 1, "dwell"),
    ("G92 X0", 1, 1, "G92"),
    ("G71 G90\nG1 X1 F60", 1, 1, "metric units in Mach3 and old Fanuc) is not supported: for mm units write G21"),
    ("G1.5 X1", 1, 1, "unsupported G-code"),
    ("M99", 1, 1, "unsupported M-code"),
    ("G0 X1 E5", 1, 7, "unknown word letter 'E'"),
    ("G0 A90\nG1 X1 A45 F100", 2, 7, "moves the A axis from 90 to 45 deg"),
    ("G1 X1 A45 F100", 1, 7, "A45 first given on a G1 feed move"),
    ("G91 G0 A5", 1, 8, "A5 under G91 moves the A axis"),
    ("G0 B1 B1", 1, 7, "B given twice"),
    ("G2 X1 K1 F60", 1, 7, "K"),
    ("G0 G1 X1 F100", 1, 4, "two motion G-codes"),
    ("F100\nG1G2X1", 2, 3, "two motion G-codes"),
    ("G20 G21", 1, 5, "units"),
    ("G90 G91", 1, 5, "distance"),
    ("M3 M5", 1, 4, "spindle"),
    ("G0 X1 X2", 1, 7, "twice"),
    ("N1.5 G0 X1", 1, 1, "N1.5"),
    ("N-3 G0 X1", 1, 1, "non-negative integer"),
    ("T1.5", 1, 1, "T1.5"),
    ("S-5", 1, 1, "spindle speed"),
    ("G0 X1\nG1 X2", 2, 1, "before any F"),
    ("G0 X1\nG1\nX2", 3, 1, "before any F"),
    ("G0 X1\nG3 X0 Y1 I-1", 2, 1, "before any F"),
    ("F0 G1 X1", 1, 1, "feed > 0"),
    ("G1 X1 F-10", 1, 7, "feed > 0"),
    ("X1", 1, 1, "no motion mode"),
    ("G80 X1", 1, 5, "G80"),
    ("G0 X1\nG80\nY1", 3, 1, "no motion mode"),
    ("G0 I1 X1", 1, 4, "only used with G2/G3"),
    ("G1 X1 R1 F9", 1, 7, "only used with G2/G3"),
    ("F60 G2 X1", 1, 5, "without I/J or R"),
    ("F60 G2 X1 I1 R1", 1, 14, "both I/J and R"),
    ("F60 G2 X10 I3", 1, 12, "not on the arc"),
    ("F60 G2 X10 I0 J0", 1, 12, "radius 0"),
    ("F60 G2 X1 R0.2", 1, 11, "smaller than half the chord"),
    ("F60 G2 R5", 1, 8, "undefined"),
    ("F60 G3 Z1 R5", 1, 11, "undefined"),
    ("F60 G90.1 G2 X1 I1", 1, 17, "without both I and J"),
    ("G0 X1 %", 1, 7, "'%'"),
    ("% G0 X1", 1, 1, "'%'"),
    ("G0 X1 ; fine\nG0 X" + "9" * 400, 2, 4, "finite"),
]


@pytest.mark.parametrize("text, line, column, fragment", BAD)
def test_malformed_input_names_line_and_column(text, line, column, fragment):
    with pytest.raises(GCodeError) as info:
        parse_gcode(text, source="part.nc")
    e = info.value
    assert (e.line, e.column) == (line, column), str(e)
    assert f"part.nc:{line}:{column}:" in str(e)
    assert fragment in str(e)
    assert "expected" in str(e) or "not supported" in str(e)


def test_chord_count_limit_is_an_error():
    with pytest.raises(GCodeError, match=r":1:.*chord_tolerance"):
        parse_gcode("G2 X0 I1000 F60 (huge circle)", chord_tolerance=1e-14)


@pytest.mark.parametrize("kw", [dict(chord_tolerance=0), dict(chord_tolerance=-1), dict(rapid_feed=0),
                                dict(initial_feed=-1), dict(start=(0, 0)), dict(start=(0, np.nan, 0)),
                                dict(arc_radius_tolerance=float("nan"))])
def test_bad_parameters(kw):
    with pytest.raises(ParameterError):
        parse_gcode("G0 X1", **kw)


# -- files -------------------------------------------------------------------------------------
def test_read_gcode_file_and_missing_file(tmp_path):
    f = tmp_path / "part.nc"
    f.write_bytes(b"%\r\nG21 G90\r\nG1 X5 F300\r\nG1 X5 Y\r\n%\r\n")
    with pytest.raises(GCodeError) as info:
        read_gcode(f)
    assert info.value.source == str(f) and (info.value.line, info.value.column) == (4, 7)
    f.write_text("G21 G90\nG1 X5 F300\n")
    prog = read_gcode(f, start=(1, 0, 0))
    assert prog.source == str(f)
    np.testing.assert_array_equal(pts(prog), [[1, 0, 0], [5, 0, 0]])
    with pytest.raises(GCodeError, match="cannot read") as info:
        read_gcode(tmp_path / "missing.nc")
    assert str(tmp_path / "missing.nc") in str(info.value)
    with pytest.raises(GCodeError):
        read_gcode(tmp_path)  # a directory


# -- writer and round trip ---------------------------------------------------------------------
def test_to_gcode_round_trip_exact_with_rapids_and_feeds():
    rng = np.random.default_rng(1)
    p = np.cumsum(rng.normal(size=(50, 3)), axis=0) * np.pi
    poly = Polyline(p)
    feeds = rng.uniform(100, 5000, 49)
    feeds[10:20] = 1234.5
    rapid = np.zeros(49, bool)
    rapid[[0, 5, 30]] = True
    text = to_gcode(poly, feeds, rapid, line_numbers=True)
    prog = parse_gcode(text, start=poly.points[0])
    np.testing.assert_array_equal(pts(prog), poly.points)  # bit-exact, well within 1e-9 mm
    assert prog.rapid.tolist() == rapid.tolist()
    np.testing.assert_allclose(prog.feeds[~rapid] * 60, feeds[~rapid], rtol=1e-14)
    np.testing.assert_allclose(prog.feeds[rapid], 15000 / 60)
    body = [ln for ln in text.splitlines() if ln.startswith("N") and ("X" in ln or "Y" in ln or "Z" in ln)]
    assert len(body) == 49
    assert sum("F" in ln for ln in body) == 49 - 3 - 9  # F only when the feed changes, never on G0
    assert "G21" in text and "G90" in text
    # and back again from the parsed program
    again = parse_gcode(to_gcode(prog.polyline, prog.feeds * 60, prog.rapid), start=poly.points[0])
    np.testing.assert_array_equal(pts(again), poly.points)


def test_to_gcode_2d_scalar_feed_and_validation():
    text = to_gcode(Polyline([[0, 0], [1e-3, 0], [1e-3, 123456.789]]), 600)
    assert re.search(r"\d[eE]", text) is None  # never exponent notation
    prog = parse_gcode(text)
    np.testing.assert_array_equal(pts(prog)[:, :2], [[0, 0], [1e-3, 0], [1e-3, 123456.789]])
    with pytest.raises(ParameterError):
        to_gcode(Polyline([[0, 0], [1, 0]]), 0)
    with pytest.raises(ParameterError):
        to_gcode(Polyline([[0, 0], [1, 0], [2, 0]]), [1.0])
    with pytest.raises(ParameterError):
        to_gcode(Polyline([[0, 0], [1e-10, 0]]), 100)  # would read back as no motion
    with pytest.raises(ParameterError):
        to_gcode(Polyline([[0, 0], [1, 0]], axes=("x", "a")), 100)
    to_gcode(Polyline([[0, 0], [1, 0]]), 0, rapid=[True])  # feed unused on G0


coord = st.floats(-1e4, 1e4, allow_nan=False, allow_infinity=False)


@settings(max_examples=60, deadline=None)
@given(
    st.lists(st.tuples(coord, coord, coord), min_size=2, max_size=30),
    st.lists(st.floats(1e-3, 1e5, allow_nan=False), min_size=29, max_size=29),
    st.lists(st.booleans(), min_size=29, max_size=29),
    st.booleans(),
)
def test_property_to_gcode_round_trip(points, feeds, rapid, numbered):
    p = np.array(points)
    keep = np.concatenate([[True], np.linalg.norm(np.diff(p, axis=0), axis=1) > 1e-6])
    p = p[keep]
    if len(p) < 2:
        return
    m = len(p) - 1
    f, r = np.array(feeds[:m]), np.array(rapid[:m])
    prog = parse_gcode(to_gcode(Polyline(p), f, r, line_numbers=numbered), start=p[0])
    np.testing.assert_array_equal(pts(prog), p)
    assert prog.rapid.tolist() == r.tolist()
    np.testing.assert_allclose(prog.feeds[~r] * 60, f[~r], rtol=1e-14)
    assert prog.no_motion_lines == ()


# -- speed on CAM-like output ------------------------------------------------------------------
def _cam_program(n_lines: int, seed: int):
    """Seeded CAM-like program; returns (text, expected segment count, expected end point)."""
    rng = np.random.default_rng(seed)
    out = ["%", "O0001 (GENERATED TEST PART)", "(T1 D=6 FLAT)", "N1 G21 G90 G17 G40 G49 G80 G94", "N2 T1 M6",
           "N3 S18000 M3", "N4 G54 G0 X0 Y0", "N5 Z5. M8", "N6 G1 Z-1. F300."]
    segs = 2
    x = y = 0.0
    n = 7
    r, tol = 2.0, 1e-3
    chords_per_circle = math.ceil(2 * math.pi / (2 * math.acos(1 - tol / r)))
    for k in range(n_lines):
        n += 1
        if k % 2000 == 1999:  # a full circle around a point 2 mm to the left
            out.append(f"N{n} G3 I-2. J0. F900. (circle)")
            out.append(f"N{n + 1} G1")
            n += 1
            segs += chords_per_circle
            continue
        x += float(rng.uniform(0.05, 0.5))
        y += float(rng.uniform(-0.2, 0.2))
        x, y = round(x, 4), round(y, 4)
        comment = " (contour)" if k % 97 == 0 else ""
        feed = f" F{int(rng.integers(600, 3000))}." if k % 500 == 0 else ""
        out.append(f"N{n} X{x:.4f} Y{y:.4f}{feed}{comment}")
        segs += 1
    out += [f"N{n + 1} G0 Z5. M9", f"N{n + 2} M5", f"N{n + 3} M30", "%"]
    segs += 1
    return "\n".join(out) + "\n", segs, (x, y, 5.0)


def test_cam_like_program_is_fast():
    text, segs, end = _cam_program(20_000, seed=42)
    t0 = time.perf_counter()
    prog = parse_gcode(text, chord_tolerance=1e-3)
    elapsed = time.perf_counter() - t0
    assert prog.n_segments == segs >= 10_000
    np.testing.assert_allclose(pts(prog)[-1], end, atol=1e-12)
    assert prog.rapid.sum() == 2 and prog.no_motion_lines == (7,)  # "G0 X0 Y0" at the origin
    assert elapsed < 5.0, f"parsing {segs} segments took {elapsed:.2f} s"


# -- LinuxCNC subset: refusals of unsupported features and bad arcs name file:line:column ------------
N9 = "9" * 309
BAD_SUBSET = [
    # (text, line, column, fragment of the message)
    ("o100 sub\nG0 X1\no100 endsub", 1, 1, "O-word subroutines/control flow (o100 sub) are not supported"),
    ("G0 X1\n  O<probe> call [1]", 2, 3, "O-word subroutines/control flow (O<probe> call)"),
    ("o101 if [#1 GT 0]", 1, 1, "O-word"),
    ("#1 = 5\nG0 X#1", 1, 1, "parameters (#1) are not supported"),
    ("G0 X#<depth>", 1, 5, "parameters (#<depth>)"),
    ("G0 X[1 + 2]", 1, 5, "expressions [..] are not supported"),
    ("G1 X1 F[60*2]", 1, 8, "expressions [..]"),
    ("G17.1 G0 X1", 1, 1, "G17.1"),  # unknown planes
    ("G0 X1 G19.1", 1, 7, "G19.1"),
    ("G2 X1 K1 F60", 1, 7, "K given for an arc in the G17 (XY) plane"),
    ("G18 G2 X1 J1 F60", 1, 11, "J given for an arc in the G18 (ZX) plane"),
    ("G19 G2 Y1 I1 F60", 1, 11, "I given for an arc in the G19 (YZ) plane"),
    ("G18 G2 X1 F60", 1, 5, "without K/I or R"),
    ("G19 G3 Z1 F60", 1, 5, "without J/K or R"),
    ("F60 G2 X0 I0.001", 1, 11, "zero-radius arc"),  # below LinuxCNC's 0.00127 mm
    ("F60 G2 X0.001 R0.0005", 1, 15, "zero-radius arc"),
    ("F60 G2 X0.0001 I0.0001", 1, 16, "zero-radius arc"),
    ("F60 G2 I5 R5", 1, 11, "both I/J and R"),
    ("F60 G3 P2 R5", 1, 11, "undefined"),  # full circle with R, with P
    ("F60 G2 I1 P0", 1, 11, "P0: expected the number of turns"),  # full circle, P not >= 1
    ("F60 G2 I1 P1.5", 1, 11, "P1.5"),
    ("F60 G2 I1 P-1", 1, 11, "P-1"),
    ("F60 G2 I1 P" + N9, 1, 11, "number of turns"),
    ("F60 G64 P2 G2 X2 I1", 1, 9, "P used by both"),
    ("G1 X1 P3 F60", 1, 7, "P word with no G2/G3, G4 or G64"),
    ("G1 X1 Q3 F60", 1, 7, "Q word with no G64"),
    ("G64 P-0.1", 1, 5, "blend tolerance >= 0"),
    ("G64 P" + N9, 1, 5, "finite tolerance"),
    ("G64 P0.1 Q-1", 1, 10, "tolerance >= 0"),
    ("F60 G3 X0 Y50.04 I-50 J0\n", 1, 18, "end radius"),
    ("M98 P100", 1, 1, "M98 (subroutine call)"),
    ("/2 G0 X1", 1, 1, "block delete with a skip level (/2)"),  # Fanuc's skip levels
    ("% vfd enable\nG0 X1", 1, 3, "'%' program delimiter must be alone on its line"),  # a Fusion post's line
    ("G0 X1 /G1 X2 F60", 1, 7, "'/' after the start of the line"),
    ("G0 X1 O1.5", 1, 7, "program number"),
    ("G80 X1 G0 G1", 1, 11, "two motion G-codes"),
    ("G17 G18", 1, 5, "plane group"),
    ("G61 G64", 1, 5, "path mode group"),
    # reliability issue: each raised OverflowError or was accepted on the previous main
    ("N" + N9 + " G1 X1 F60", 1, 1, "non-negative integer line number"),
    ("T" + N9 + " G1 X1 F60", 1, 1, "non-negative integer tool number"),
    ("G" + N9 + " G1 X1 F60", 1, 1, "unsupported G-code"),
    ("M" + N9 + " G1 X1 F60", 1, 1, "unsupported M-code"),
    ("G1 X1 F" + N9, 1, 7, "feed > 0"),  # F inf was accepted
    ("G1 X" + "9" * 308 + " F60", 1, 4, "finite coordinate"),  # 1e308: infinite segment length was accepted
    ("G0 X1 S" + N9, 1, 7, "finite spindle speed"),
    ("G0 X1\nG91 G0 X900000\nX900000", 3, 1, "finite coordinate"),  # incremental beyond MAX_COORDINATE_MM
    ("G1.00000001 X1 F60", 1, 1, "unsupported G-code G1.00000001"),  # was read as G1
    ("G0 X10000000000000\nG1 X10000000000000.001 F60", 1, 4, "1e+06 mm"),  # 1e13 mm: refused, not line 2 blamed
    ("G0 X999999\nG1 X999999.0000001 F60\nG1 X0", 2, 1, "path resolution"),  # 1e-7 mm at 1e6 mm: its own line
]


@pytest.mark.parametrize("text, line, column, fragment", BAD_SUBSET, ids=[t[:30] for t, *_ in BAD_SUBSET])
def test_unsupported_features_and_bad_numbers_name_line_and_column(text, line, column, fragment):
    with pytest.raises(GCodeError) as info:
        parse_gcode(text, source="part.ngc")
    e = info.value
    assert (e.line, e.column) == (line, column), str(e)
    assert f"part.ngc:{line}:{column}:" in str(e)
    assert fragment in str(e), str(e)
    assert "expected" in str(e) or "not supported" in str(e)


@pytest.mark.parametrize("text", ["G80 G0 X1", "G0 G80 X1", "G1 G80 X1 F60"])
def test_g80_with_a_motion_code_on_one_line(text):
    """LinuxCNC: G80 and a motion code on one line, the motion code wins (was "two motion G-codes")."""
    prog = parse_gcode(text)
    np.testing.assert_array_equal(pts(prog), [[0, 0, 0], [1, 0, 0]])
    assert prog.rapid.tolist() == [text.startswith("G1") is False]


def test_g64_p_q_tolerance_changes_mid_program():
    """G64 P (Q ignored) per block; G61 / G61.1 -> 0; G64 alone -> NaN; values from the program text."""
    prog = parse_gcode("G64 P0.005 Q0.001\nG1 X1 F60\nG2 X2 R0.5\nG61\nG1 X3\nG64 P0.1\nX4\nG61.1 X5\nG64 X6")
    np.testing.assert_array_equal(prog.block_tolerance, [0.005, 0.005, 0.0, 0.1, 0.0, np.nan])
    np.testing.assert_array_equal(prog.block_lines, [2, 3, 5, 7, 8, 9])
    assert np.all(prog.block_tolerance[prog.segment_block][prog.lines == 3] == 0.005)  # every chord of the arc


def test_g64_p0_is_no_tolerance_as_a_bare_g64():
    """``G64 P0`` (with or without ``Q0``, as four of LinuxCNC's trajectory-planner test programs
    write it) is no tolerance, as a bare ``G64``, not the exact path of ``G61``: LinuxCNC's
    ``tcFindBlendTolerance`` reads "Detect zero tolerance = no tolerance and force to reasonable
    maximum". So an arc under it is planned by the FIR stage at the config's eps (it refuses arcs
    under G61, tolerance 0)."""
    prog = parse_gcode("G21 G90\nG64 P0 Q0\nG1 X10 F600\nG2 X20 R5\nG1 Y10\nG61\nG1 X30\nG64 P0.\nG1 Y0")
    np.testing.assert_array_equal(prog.block_tolerance, [np.nan, np.nan, np.nan, 0.0, np.nan])


def test_an_off_plane_centre_word_of_zero_is_read_as_grbl_posts_write_it():
    """FreeCAD's GRBL post writes ``I J K`` on every arc (``K0.000`` in G17); GRBL ignores it,
    LinuxCNC refuses it. A zero off-plane word moves no centre, so it is read: the blocks are those
    of the same arcs without it (G17 with K0, G18 with J0); a nonzero one stays an error."""
    for plane, with_zero, without in (("G17", "G2 X2 Y0 I1 J0 K0.000 F60", "G2 X2 Y0 I1 J0 F60"),
                                      ("G18", "G2 X2 Z0 I1 K0 J-0 F60", "G2 X2 Z0 I1 K0 F60")):
        a = parse_gcode(f"{plane}\n{with_zero}").blocks
        b = parse_gcode(f"{plane}\n{without}").blocks
        np.testing.assert_array_equal(a.ends, b.ends)
        np.testing.assert_array_equal(a.centers, b.centers)
        np.testing.assert_array_equal(a.sweeps, b.sweeps)
    with pytest.raises(GCodeError, match=r"K given for an arc in the G17 \(XY\) plane"):
        parse_gcode("G2 X2 Y0 I1 J0 K0.001 F60")


def test_full_circle_with_p_turns_and_helical_g18():
    """G2 I-5 P3: three full turns, sweep 6 pi, length 2 pi 5 * 3; G18 helical arc along Y."""
    prog = parse_gcode("G0 X5\nG2 I-5 P3 F600\nG18 G3 X5 Z0 I0 K-2 Y4")
    b = prog.blocks
    np.testing.assert_allclose(b.sweeps[1:], [6 * math.pi, 2 * math.pi], rtol=1e-12)
    np.testing.assert_allclose(b.lengths[1], 30 * math.pi, rtol=1e-12)
    np.testing.assert_allclose(b.lengths[2], math.hypot(4 * math.pi, 4), rtol=1e-12)
    np.testing.assert_array_equal(b.normals[2], [0, 1, 0])
    # three turns of chords: the polyline is close to 3 circumferences
    assert Polyline([[5, 0, 0]] + pts(prog)[1:][prog.lines == 2].tolist()).length == pytest.approx(30 * math.pi, rel=1e-4)


def test_hundred_thousand_short_lines_are_fast():
    """10^5 plain G1 lines (the fast path); measured 0.55 s on the idle 2-core dev machine (the previous
    reader: 1.2 s). CPU time of this process, so a loaded machine (parallel tests) does not fail it."""
    text = "G21 G90 F600\n" + "".join(f"N{i} G1 X{i * 0.01:.4f} Y{(i % 7) * 0.01:.4f}\n" for i in range(1, 100_001))
    t0 = time.process_time()
    prog = parse_gcode(text)
    elapsed = time.process_time() - t0
    assert prog.n_segments == prog.n_blocks == 100_000
    np.testing.assert_allclose(pts(prog)[-1], [1000.0, (100_000 % 7) * 0.01, 0], atol=1e-12)
    assert elapsed < 3.0, f"10^5 lines took {elapsed:.2f} s"


def test_to_gcode_program_argument_checks():
    prog = parse_gcode("G1 X1 F60\nG2 X2 R0.5")
    with pytest.raises(ParameterError, match="carries its own feeds"):
        to_gcode(prog, 600)
    with pytest.raises(ParameterError, match="required"):
        to_gcode(prog.polyline)
    text = to_gcode(prog)
    assert "G2 X2 I0.5 J0" in text and text.startswith("%\n(research.paths.gcode.to_gcode: start X0 Y0 Z0)")


def test_extra_axes_that_never_move_are_read():
    """A 4-axis post's 3-axis job (Mastercam style): ``A0.`` on the first rapid and again on a feed
    move, a rotary axis that never moves. The blocks are those of the same program without the A
    words (X, Y, Z alone are planned); an A word that would move the axis is refused (above)."""
    body = ("G20\nG0 G17 G40 G49 G80 G90\nT1 M6\nG0 G90 G54 X.5 Y.25{a} S5000 M3\nG43 H1 Z.1\nG1 Z-.05 F10.\n"
            "X1.5 F20.\nG3 X1.75 Y.5 R.25\nG1 Y1.5{a}\nG2 X1.5 Y1.75 R.25\nG1 X.5\nY.25\nG0 Z.1\nM5\nM30\n")
    with_a = parse_gcode(body.format(a=" A0."))
    without = parse_gcode(body.format(a=""))
    np.testing.assert_array_equal(with_a.blocks.ends, without.blocks.ends)
    np.testing.assert_array_equal(with_a.block_feeds, without.block_feeds)
    assert with_a.blocks.is_arc.tolist() == without.blocks.is_arc.tolist()
