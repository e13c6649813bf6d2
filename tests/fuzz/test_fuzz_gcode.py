"""Fuzz tests of the G-code reader: random programs from a grammar of valid and invalid words.

Only :class:`GCodeError` (bad input) or :class:`ParameterError` (bad keyword arguments) may escape
``parse_gcode``; accepted programs must be internally consistent and round-trip through
``to_gcode`` (their chords, bit-exact). Valid programs built from known geometry (lines and arcs in
all three planes, helical, with P turns) must be accepted with the block ends and sweeps they were
built from.

Examples per test: ``RESEARCH_FUZZ_EXAMPLES`` (default 200, the file then runs in a few seconds);
set it to 10000 for a long run.
"""

from __future__ import annotations

import math
import os

import numpy as np
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st

from research.errors import GCodeError, ParameterError
from research.paths.gcode import GCodeProgram, parse_gcode, to_gcode

EXAMPLES = int(os.environ.get("RESEARCH_FUZZ_EXAMPLES", "200"))
FUZZ = settings(max_examples=EXAMPLES, deadline=None, derandomize=EXAMPLES <= 200,
                suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much])

NUMBERS = st.one_of(
    st.sampled_from(["0", "1", "-1", "2.5", ".5", "10", "-3.25", "0.001", "100", "5.", "+2", "0.5", "-0.5"]),
    st.floats(-60, 60, allow_nan=False).map(lambda v: f"{v:.4f}"),
    st.sampled_from(["9" * 309, "9" * 308, "1e5", "", "1.2.3", "-", "1000001", "0.0000000001", "-0", "00",
                     "99999999999999999999", ".", "1.00000001"]),
)
CODES = st.sampled_from(
    ["G0", "G1", "G2", "G3", "G00", "G01", "G17", "G18", "G19", "G20", "G21", "G90", "G91", "G90.1", "G91.1",
     "G61", "G61.1", "G64", "G80", "G40", "G49", "G54", "G94", "M3", "M5", "M8", "M9", "M2", "M30", "M6", "G43", "G43 H1",
     "G4 P0.5", "M0", "M1", "G53", "G53 G0", "G53 G1",
     # refused (G28: without home, G4: without P; G53 without machine_origin, under G91 or with an arc mode)
     "G4", "G81", "G41", "G43.1", "G17.1", "G1.00000001", "G1.5", "G93", "G28", "M98", "M99", "G-1", "G5"])
ODD = st.sampled_from(
    ["#1", "#<x>", "[1+2]", "sin[30]", "o100 sub", "o100 endsub", "O<a> call", "(comment)", "(", ")", "(a(b))",
     ";tail", "%", "/", "\u00e9", "\t", "N10", "T1", "S100", "O1", "E5", "A1", "\x00", "\r", "X", "G", "$", "*",
     "N-1", "T1.5", "\u2028", "\x0b"])
WORD = st.one_of(CODES, st.tuples(st.sampled_from("XYZIJKRPQFXYZXYZ"), NUMBERS).map("".join), ODD)
RANDOM_LINE = st.tuples(st.lists(WORD, max_size=6), st.sampled_from([" ", "", "  "])).map(lambda t: t[1].join(t[0]))
SMALL = st.floats(-60, 60, allow_nan=False).map(lambda v: f"{v:.3f}")
MOVE = st.tuples(st.sampled_from(["", "G0", "G1", "G01", "G80 G1"]),
                 st.lists(st.tuples(st.sampled_from("XYZ"), SMALL).map("".join), min_size=1, max_size=3,
                          unique_by=lambda w: w[0]),
                 st.sampled_from(["", "F600", "F1200.5"])).map(lambda t: " ".join([t[0], *t[1], t[2]]).strip())
# R 100 always reaches (every chord here is shorter than 200); I5 alone is a full circle in G17/G18
ARC = st.tuples(st.sampled_from(["G2", "G3"]), st.sampled_from(["", "G17 ", "G18 ", "G19 "]),
                st.lists(st.tuples(st.sampled_from("XYZ"), SMALL).map("".join), max_size=3, unique_by=lambda w: w[0]),
                st.sampled_from(["R100", "R-100", "I5", "I5 P2", "R100 P3"])
                ).map(lambda t: f"{t[1]}{t[0]} {' '.join(t[2])} {t[3]}")
MODE = st.sampled_from(["G64 P0.01", "G64 P0.02 Q0.01", "G61", "G61.1", "G64", "G91", "G90", "G20", "G21",
                        "G17", "G90.1", "G91.1", "M3 S1000", "(comment)", "%", "", "M2"])
LINE = st.one_of(MOVE, MOVE, MOVE, MOVE, MOVE, ARC, ARC, MODE, RANDOM_LINE)
PROGRAM = st.tuples(st.sampled_from(["", "G21 G90 G1 F600\n", "G20 G0 F10\n", "G64 P0.01 G1 F300\n"]),
                    st.lists(LINE, min_size=1, max_size=12)).map(lambda t: t[0] + "\n".join(t[1]))
KWARGS = st.fixed_dictionaries({}, optional={
    "chord_tolerance": st.sampled_from([1e-3, 1e-2, 0.1, 0.0, -1.0, float("nan"), float("inf"), "x"]),
    "arc_radius_tolerance": st.sampled_from([None, 0.01, 1e-3, 0.0, -1.0, float("nan")]),
    "arc_relative_tolerance": st.sampled_from([1e-3, 0.01, 0.0, float("nan")]),
    "initial_feed": st.sampled_from([None, 100.0, 0.0, -5.0]),
    "rapid_feed": st.sampled_from([15000.0, 0.0]),
    "start": st.sampled_from([(0, 0, 0), (1.5, -2, 3), (0, 0), (0, float("nan"), 0), (1e7, 0, 0), "abc"]),
    "machine_origin": st.sampled_from([None, (0, 0, 0), (-350.0, 250.0, 300.0), (0, 0), (float("inf"), 0, 0)]),
})


def _bad_kwargs(kw: dict) -> bool:
    def bad_pos(v):
        return not isinstance(v, float) or not (math.isfinite(v) and v > 0)
    for name in ("chord_tolerance", "arc_relative_tolerance", "rapid_feed"):
        if name in kw and bad_pos(kw[name]):
            return True
    for name in ("arc_radius_tolerance", "initial_feed"):
        if kw.get(name) is not None and bad_pos(kw[name]):
            return True
    for s in (kw.get("start", (0, 0, 0)), kw.get("machine_origin") or (0, 0, 0)):
        if isinstance(s, str) or len(s) != 3 or not all(abs(float(v)) <= 1e6 for v in s):
            return True
    return False


def _check_program(prog: GCodeProgram):
    pts = prog.polyline.points
    assert np.all(np.isfinite(pts)) and np.all(np.abs(pts) <= 1e6)
    assert np.all(np.isfinite(prog.feeds)) and np.all(prog.feeds > 0)
    assert np.all(np.isfinite(prog.blocks.lengths)) and np.all(prog.blocks.lengths > 0)
    sb = prog.segment_block
    assert sb[0] == 0 and sb[-1] == prog.n_blocks - 1 and np.all(np.diff(sb) >= 0) and np.all(np.diff(sb) <= 1)
    last = np.append(np.flatnonzero(np.diff(sb)), prog.n_segments - 1)
    np.testing.assert_array_equal(prog.blocks.ends, pts[last + 1])
    np.testing.assert_array_equal(prog.lines, prog.block_lines[sb])
    tol = prog.block_tolerance
    assert np.all(np.isnan(tol) | (tol >= 0))


def _same_without_fast_path(text: str, prog: GCodeProgram, kw: dict):
    """A comment on every line sends it through the general tokenizer instead of the plain-line fast
    path; the result must be the same program."""
    lines = text.replace("\r\n", "\n").replace("\r", "\n").split("\n")  # the reader's own line ends
    slow = parse_gcode("\n".join(line + " (c)" for line in lines), **kw)
    np.testing.assert_array_equal(slow.polyline.points, prog.polyline.points)
    np.testing.assert_array_equal(slow.feeds, prog.feeds)
    np.testing.assert_array_equal(slow.lines, prog.lines)
    np.testing.assert_array_equal(slow.block_tolerance, prog.block_tolerance)
    assert slow.no_motion_lines == prog.no_motion_lines


def _round_trip(prog: GCodeProgram):
    text = to_gcode(prog.polyline, prog.feeds * 60.0, prog.rapid)
    again = parse_gcode(text, start=prog.polyline.points[0])
    np.testing.assert_array_equal(again.polyline.points, prog.polyline.points)
    assert again.rapid.tolist() == prog.rapid.tolist()
    np.testing.assert_allclose(again.feeds[~prog.rapid], prog.feeds[~prog.rapid], rtol=1e-14)
    # the blocks, arcs as arcs
    blocks = parse_gcode(to_gcode(prog), start=prog.blocks.start)
    np.testing.assert_array_equal(blocks.blocks.ends, prog.blocks.ends)
    np.testing.assert_allclose(blocks.blocks.sweeps, prog.blocks.sweeps, rtol=1e-9, atol=1e-9)
    np.testing.assert_array_equal(blocks.block_tolerance, prog.block_tolerance)
    np.testing.assert_array_equal(blocks.block_rapid, prog.block_rapid)
    np.testing.assert_allclose(blocks.block_feeds, prog.block_feeds, rtol=1e-14)


@FUZZ
@given(PROGRAM, KWARGS)
def test_random_programs_raise_only_gcode_errors(text, kw):
    """Any program and keyword arguments: a GCodeProgram, a GCodeError with line and column, or (only for
    bad keyword arguments) a ParameterError; accepted programs are consistent and round-trip."""
    try:
        prog = parse_gcode(text, **kw)
    except ParameterError:
        assert _bad_kwargs(kw), kw
        return
    except GCodeError as e:
        assert not _bad_kwargs(kw), kw
        assert e.line >= 0 and e.column >= 0 and str(e).startswith(f"<string>:{e.line}:{e.column}: ")
        assert 1 <= e.line <= text.count("\n") + 1 + text.count("\r") or "no motion" in str(e)
        return
    assert not _bad_kwargs(kw), kw
    _check_program(prog)
    _same_without_fast_path(text, prog, kw)
    _round_trip(prog)


def _fmt(v) -> str:
    """Shortest exact decimal without exponent (G-code has no exponents)."""
    return np.format_float_positional(float(v), unique=True, trim="-")


@st.composite
def valid_programs(draw):
    """Lines and consistent arcs (centre, radius, end on the circle) in random planes, with helices and P."""
    pos = np.zeros(3)
    out, ends, sweeps = ["G21 G90 G91.1 F600"], [], []
    planes = {"G17": (0, 1, 2), "G18": (2, 0, 1), "G19": (1, 2, 0)}
    for _ in range(draw(st.integers(1, 8))):
        if draw(st.booleans()):
            target = pos + np.array([draw(st.floats(-20, 20)) for _ in range(3)])
            if np.linalg.norm(target - pos) < 1e-3:
                continue
            words = [f"G{draw(st.sampled_from([0, 1]))}"] + [f"{'XYZ'[i]}{_fmt(target[i])}" for i in range(3)]
            sweeps.append(0.0)
        else:
            g = draw(st.sampled_from(["G17", "G18", "G19"]))
            a, b, c = planes[g]
            r = draw(st.floats(0.5, 30))
            start_ang = draw(st.floats(-math.pi, math.pi))
            d_ang = draw(st.floats(0.05, 2 * math.pi - 0.05))
            cw = draw(st.booleans())
            turns = draw(st.integers(1, 2))
            centre = pos.copy()
            centre[a] -= r * math.cos(start_ang)
            centre[b] -= r * math.sin(start_ang)
            end_ang = start_ang - d_ang if cw else start_ang + d_ang
            target = pos.copy()
            target[a] = centre[a] + r * math.cos(end_ang)
            target[b] = centre[b] + r * math.sin(end_ang)
            target[c] += draw(st.floats(-5, 5))
            off = centre - pos
            words = [g, "G2" if cw else "G3"] + [f"{'XYZ'[i]}{_fmt(target[i])}" for i in range(3)]
            words += [f"{'IJK'[a]}{_fmt(off[a])}", f"{'IJK'[b]}{_fmt(off[b])}"] + ([f"P{turns}"] if turns > 1 else [])
            sweeps.append(d_ang + 2 * math.pi * (turns - 1))
        if draw(st.booleans()):
            words.append(f"G64 P{draw(st.sampled_from(['0.001', '0.01', '0']))}" if words[0] in ("G0", "G1")
                         else "")
        out.append(" ".join(w for w in words if w))
        ends.append(target)
        pos = target
    return "\n".join(out), np.array(ends).reshape(-1, 3), np.array(sweeps)


@FUZZ
@given(valid_programs())
def test_valid_programs_are_accepted_with_their_geometry(case):
    """Programs built from known lines and arcs: every move is one block ending where it was built, arcs
    with the sweep they were built with (angle + 2 pi (P - 1)); chords round-trip through to_gcode."""
    text, ends, sweeps = case
    assume(len(ends) > 0)
    prog = parse_gcode(text)
    assert prog.n_blocks == len(ends), text
    np.testing.assert_allclose(prog.blocks.ends, ends, atol=1e-9)
    np.testing.assert_allclose(prog.blocks.sweeps, sweeps, rtol=1e-7, atol=1e-7)
    _check_program(prog)
    _same_without_fast_path(text, prog, {})
    _round_trip(prog)
