"""The G-code reader on the test programs under tests/paths/programs/ (one per accepted feature) and
on LinuxCNC-style programs: arcs kept as ToolPath blocks, per-block tolerances, LinuxCNC rules.

Expected values are computed here from the program text by hand (centres, radii, sweeps from the
geometry of each move; lengths as R * sweep or sqrt((R sweep)^2 + dz^2)), not by the reader.
"""

from __future__ import annotations

import math
import pathlib

import numpy as np
import pytest

from research.errors import GCodeError, PathError
from research.paths.gcode import GCodeProgram, parse_gcode, read_gcode, to_gcode
from research.paths.polyline import Polyline

PROGRAMS = pathlib.Path(__file__).parent / "programs"
PI = math.pi
#: reader arguments a test program needs (mill_post.ngc returns home with G28)
PROGRAM_ARGS = {"mill_post.ngc": {"home": (0.0, 0.0, 50.0), "start": (0.0, 0.0, 50.0)},
                "fanuc_post.ngc": {"home": (0.0, 0.0, 50.8), "start": (0.0, 0.0, 50.8)}}
NAN = float("nan")


def read(name: str, **kw) -> GCodeProgram:
    return read_gcode(PROGRAMS / name, **kw)


def check_consistent(prog: GCodeProgram, chord_tolerance: float = 1e-3):
    """Chords belong to their blocks: chord ends of block k lie on block k (within the chord
    tolerance), block ends are polyline vertices, per-chord arrays agree with per-block ones."""
    b, sb = prog.blocks, prog.segment_block
    assert sb.shape == (prog.n_segments,) and sb[0] == 0 and sb[-1] == prog.n_blocks - 1
    assert np.all(np.diff(sb) >= 0) and np.all(np.diff(sb) <= 1)
    last = np.append(np.flatnonzero(np.diff(sb)), prog.n_segments - 1)
    np.testing.assert_array_equal(b.ends, prog.polyline.points[last + 1])
    np.testing.assert_array_equal(b.start, prog.polyline.points[0])
    np.testing.assert_array_equal(prog.feeds, prog.block_feeds[sb])
    np.testing.assert_array_equal(prog.rapid, prog.block_rapid[sb])
    np.testing.assert_array_equal(prog.lines, prog.block_lines[sb])
    mids = 0.5 * (prog.polyline.points[1:] + prog.polyline.points[:-1])
    # ToolPath._block_distance projects on the chord of every block before overriding arcs, which
    # divides 0 / 0 for full circles (start == end); the arc result replaces it, so silence that here
    with np.errstate(invalid="ignore", divide="ignore"):
        assert b.distance(prog.polyline.points).max() <= 1e-9
        assert b.distance(mids).max() <= chord_tolerance * (1 + 1e-6)


def test_arcs_g17_centres_normals_sweeps_lengths():
    """arcs_g17.ngc: centres and sweeps worked out from each line's geometry (see the file)."""
    prog = read("arcs_g17.ngc")
    b = prog.blocks
    assert prog.block_lines.tolist() == [6, 7, 8, 9, 10, 11]
    assert b.is_arc.tolist() == [False, True, True, True, True, False]
    np.testing.assert_allclose(b.ends, [[10, 0, 0], [0, 10, 0], [-10, 20, 0], [-10, 20, 0], [0, 30, 0], [20, 30, 0]],
                               atol=1e-12)
    arcs = b.is_arc
    np.testing.assert_allclose(b.centers[arcs], [[0, 0, 0], [0, 20, 0], [-10, 15, 0], [-10, 30, 0]], atol=1e-9)
    np.testing.assert_array_equal(b.normals[arcs, 2], [1, -1, 1, -1])  # G3 +z, G2 -z
    np.testing.assert_allclose(b.sweeps[arcs], [PI / 2, PI / 2, 4 * PI, 3 * PI / 2], rtol=1e-12)
    r = np.array([10, 10, 5, 10])
    np.testing.assert_allclose(b.lengths[arcs], r * b.sweeps[arcs], rtol=1e-12)
    np.testing.assert_allclose(b.lengths[~arcs], [10, 20], rtol=1e-12)
    # the quarter G2 R10 from (0, 10) to (-10, 20) passes through the centre (0, 20) + 10 (-cos 45, -sin 45)
    mid = b.arc_points(2, [PI / 4])[0]
    np.testing.assert_allclose(mid, [-10 / math.sqrt(2), 20 - 10 / math.sqrt(2), 0], atol=1e-9)
    np.testing.assert_allclose(prog.block_feeds, [250, 10, 10, 10, 10, 10])
    check_consistent(prog)
    # the chord polyline of the P2 circle goes round twice: its length is close to 2 * 2 pi * 5
    chords = Polyline(prog.polyline.points[np.r_[prog.segment_block == 3, False] | np.r_[False, prog.segment_block == 3]])
    assert chords.length == pytest.approx(20 * PI, rel=1e-4)


def test_arcs_g18_g19_plane_conventions():
    """arcs_g18_g19.ngc: RS274/NGC planes. G18 arcs are in (Z, X) order, G3 counter-clockwise from +Z to +X,
    so about +Y; G19 in (Y, Z), G3 about +X. Block 0 (G18 G3, centre z 10 x 0, from (x0, z0) to (x10, z10)) goes
    from angle 180 deg to 90 deg counter-clockwise in (Z, X): 270 deg, so its midpoint (225 + 90 = 315 deg)
    is (z, x) = (10 + 10 cos 315, 0 + 10 sin 315)."""
    prog = read("arcs_g18_g19.ngc")
    b = prog.blocks
    assert b.is_arc.all()
    np.testing.assert_allclose(b.normals, [[0, 1, 0], [-1, 0, 0], [1, 0, 0], [0, -1, 0]])
    np.testing.assert_allclose(b.sweeps, [3 * PI / 2, PI / 2, PI / 2, 2 * PI], rtol=1e-12)
    np.testing.assert_allclose(b.centers, [[0, 0, 10], [10, 10, 10], [10, 0, 20], [10, 0, 25]], atol=1e-9)
    mid = b.arc_points(0, [3 * PI / 4])[0]
    c = math.cos(7 * PI / 4)
    np.testing.assert_allclose(mid, [10 * math.sin(7 * PI / 4), 0, 10 + 10 * c], atol=1e-9)
    # G19 G2 R10 from (y0, z10) to (y10, z20) clockwise about +X: centre (y10, z10), midpoint at 135 deg
    mid = b.arc_points(1, [PI / 4])[0]
    np.testing.assert_allclose(mid, [10, 10 - 10 / math.sqrt(2), 10 + 10 / math.sqrt(2)], atol=1e-9)
    # helical full circle in G18: along Y 0 -> -5, radius 5
    np.testing.assert_allclose(b.lengths[3], math.hypot(2 * PI * 5, 5), rtol=1e-12)
    np.testing.assert_allclose(b.ends[3], [10, -5, 30], atol=1e-12)
    np.testing.assert_allclose(b.lengths[:3], [10 * 3 * PI / 2, 10 * PI / 2, 10 * PI / 2], rtol=1e-12)
    check_consistent(prog)


def test_helix_turns_and_length():
    """helix.ngc: G2 90 deg + P3 (two extra turns) with Z 0 -> -3: sweep pi/2 + 4 pi, length
    sqrt((5 sweep)^2 + 3^2); Z linear in the angle (checked on the chords)."""
    prog = read("helix.ngc")
    b = prog.blocks
    sweep = PI / 2 + 4 * PI
    np.testing.assert_allclose(b.sweeps[1:], [sweep, PI / 2], rtol=1e-12)
    np.testing.assert_allclose(b.lengths[1:], [math.hypot(5 * sweep, 3), math.hypot(5 * PI / 2, 2)], rtol=1e-12)
    np.testing.assert_allclose(b.normals[1:, 2], [-1, 1])
    chords = prog.polyline.points[1:][prog.segment_block == 1]
    ang = np.unwrap(np.concatenate([[0.0], np.arctan2(chords[:, 1], chords[:, 0])]))
    np.testing.assert_allclose(np.concatenate([[0.0], chords[:, 2]]), -3 * ang / ang[-1], atol=1e-12)
    assert ang[-1] == pytest.approx(-sweep)
    check_consistent(prog)


def test_spiral_arcs_within_linuxcnc_tolerance():
    """spiral.ngc: r0 30 -> r1 30.0125 and r0 5 -> r1 5.0025, accepted (LinuxCNC: |dr| <= 0.0283 mm and
    <= 0.1 %); the ToolPath radius is blended linearly, so its length is the integral of
    sqrt(r^2 + (dr/dphi)^2) over the sweep (computed here with a fine trapezoid rule)."""
    prog = read("spiral.ngc")
    b = prog.blocks
    np.testing.assert_allclose(b.ends[[1, 3]], [[0, 30.0125, 0], [0, 5.0025, 0]], atol=0)
    for k, r0, r1 in ((1, 30, 30.0125), (3, 5, 5.0025)):
        phi = np.linspace(0, PI / 2, 200001)
        r = r0 + (r1 - r0) * phi / (PI / 2)
        expect = np.trapezoid(np.hypot(r, (r1 - r0) / (PI / 2)), phi)
        assert b.lengths[k] == pytest.approx(expect, rel=1e-9)
        assert b.radii[k] == pytest.approx(r0)
        p = b.arc_points(k, [PI / 4])[0]
        assert np.hypot(p[0], p[1]) == pytest.approx(0.5 * (r0 + r1), rel=1e-12)
    check_consistent(prog)


def test_tolerance_modes():
    """tolerance_modes.ngc: NaN before any path-control word and after plain G64; G64 P values;
    0 after G61 / G61.1; G20 G64 P0.001 = 0.0254 mm (comments of the file give each block's value)."""
    prog = read("tolerance_modes.ngc")
    np.testing.assert_array_equal(prog.block_tolerance, [NAN, 0.01, 0.02, 0, 0, NAN, 0.001 * 25.4, 0.001 * 25.4])
    assert prog.blocks.is_arc.tolist() == [False] * 7 + [True]
    np.testing.assert_allclose(prog.blocks.ends[6], [7.62, 0, 0], atol=1e-12)
    check_consistent(prog)


def test_linuxcnc_tp_style_program():
    """linuxcnc_tp_style.ngc (G20): 10 short G1 moves of 0.01 in, arcs in G17/G18/G19 of radius 0.05 in,
    a helical full circle with Z -0.1 in, G80 with G0 on one line; every block has G64 P0.001 in."""
    prog = read("linuxcnc_tp_style.ngc")
    b = prog.blocks
    assert prog.n_blocks == 16 and prog.no_motion_lines == (5,)
    np.testing.assert_allclose(prog.block_tolerance, 0.0254)
    assert b.is_arc.tolist() == [False] * 10 + [True] * 5 + [False]
    np.testing.assert_allclose(b.lengths[:10], np.hypot(0.254, 0.0254), rtol=1e-12)
    r = 0.05 * 25.4
    np.testing.assert_allclose(b.sweeps[10:15], [PI, PI, PI, PI, 2 * PI], rtol=1e-7)  # 0.05 in rounds in float
    np.testing.assert_allclose(b.lengths[10:14], r * PI, rtol=1e-12)
    np.testing.assert_allclose(b.lengths[14], math.hypot(2 * PI * r, 2.54), rtol=1e-12)
    np.testing.assert_allclose(b.normals[10:15], [[0, 0, -1], [0, 0, 1], [0, -1, 0], [1, 0, 0], [0, 0, -1]])
    np.testing.assert_allclose(b.ends[-1], [10.16, 2.54, 12.7], atol=1e-12)
    assert prog.block_rapid.tolist() == [False] * 15 + [True]
    np.testing.assert_allclose(prog.block_feeds[:10], 20 * 25.4 / 60)
    np.testing.assert_allclose(prog.block_feeds[10:15], 10 * 25.4 / 60)
    check_consistent(prog)


def test_cam_post_output():
    """cam_post.ngc: G90.1 absolute centres (20, 10) and (20, 20), both quarter CCW arcs of radius 10."""
    prog = read("cam_post.ngc")
    b = prog.blocks
    assert b.is_arc.tolist() == [False, False, False, True, False, True, False, False]
    np.testing.assert_allclose(b.centers[b.is_arc], [[20, 10, -1], [20, 20, -1]], atol=1e-12)
    np.testing.assert_allclose(b.lengths[b.is_arc], 10 * PI / 2, rtol=1e-12)
    np.testing.assert_allclose(prog.block_tolerance, 0.005)
    assert prog.block_lines.tolist() == [11, 12, 13, 14, 15, 16, 17, 18]
    check_consistent(prog)


def test_mill_post_with_home_and_tool_length_offset():
    """mill_post.ngc read with home = (0, 0, 50), from (0, 0, 50). By hand (LinuxCNC G28 semantics):
    line 8 ``G28 G91 Z0`` goes via the current point to z = 50 (already there: no move); G43 Z15 H1 is
    a plain rapid to z = 15 in program (tool-tip) coordinates; line 21 ``G28 G91 Z0`` from (25, 20, 15)
    to (25, 20, 50); line 23 ``G28 X30 Y20`` (G90 again) a rapid to (30, 20, 50), then X and Y home to
    (0, 0, 50), Z unchanged."""
    prog = read("mill_post.ngc", home=(0.0, 0.0, 50.0), start=(0.0, 0.0, 50.0))
    b = prog.blocks
    ends = [[10, 5, 50], [10, 5, 15], [10, 5, 5], [10, 5, -1], [20, 5, -1], [25, 10, -1], [25, 20, -1],
            [25, 20, 15], [25, 20, 50], [30, 20, 50], [0, 0, 50]]
    np.testing.assert_allclose(b.ends, ends, atol=1e-12)
    assert prog.block_lines.tolist() == [13, 14, 15, 16, 17, 18, 19, 20, 21, 23, 23]
    assert b.is_arc.tolist() == [False] * 5 + [True] + [False] * 5
    assert prog.block_rapid.tolist() == [True, True, True, False, False, False, False, True, True, True, True]
    assert 8 in prog.no_motion_lines
    check_consistent(prog)


def test_dwells_and_program_stops_are_pauses_at_their_vertices():
    """dwell_stops.ngc, by hand from the file's comments (RS274/NGC order of execution: G4 before the
    line's motion, M0/M1 after it; dwells at one vertex add up): 2.5 s at the start (before any move),
    0 + 0.25 s at vertex 3 (M1, then the dwell before Y10), 0 + 1.5 s at vertex 5 (M0 after X0, then
    G04 P1.5), 0.125 s at the end (after the last move); NaN elsewhere."""
    prog = read("dwell_stops.ngc")
    np.testing.assert_array_equal(prog.blocks.ends, [[0, 0, 5], [0, 0, 1], [10, 0, 1], [10, 10, 1], [0, 10, 1],
                                                     [0, 10, 5]])
    np.testing.assert_array_equal(prog.block_pauses, [2.5, NAN, NAN, 0.25, NAN, 1.5, 0.125])
    assert prog.block_lines.tolist() == [7, 8, 9, 11, 12, 14]
    check_consistent(prog)


@pytest.mark.parametrize("text, line, column, match", [
    ("G1 X1 F60\nG4", 2, 1, r"G4 \(dwell\) without P"),
    ("G1 X1 F60\nG4 P-0.5", 2, 4, r"G4 P-0.5: expected a finite dwell >= 0 s \(P is in seconds"),
    ("G1 X1 F60\nG4 G64 P0.01", 2, 8, r"P used by both G64 \(tolerance\) and G4"),
    ("G1 X1 F60\nG4 P1 G3 X2 Y1 R1", 2, 4, r"P used by both G4 \(dwell\) and G2/G3"),
    ("G1 X1 F60\nM1 M30", 2, 4, r"two stopping M-codes on one line"),
    ("G1 X1 F60\nG4 X1.5", 2, 1, r"G4 \(dwell\) without P"),  # Fanuc's G4 X<seconds>: not read as a move
])
def test_bad_dwells_and_stops_name_line_and_column(text, line, column, match):
    with pytest.raises(GCodeError, match=rf"<string>:{line}:{column}: {match}"):
        parse_gcode(text)


def test_fanuc_post_with_safety_line_and_incremental_g28():
    """fanuc_post.ngc (G20), read with home = start = (0, 0, 2 in), by hand in mm (x 25.4): the safety
    line's G80 / G98 change nothing; G0 to (1, 0) in, G43 Z.1 a rapid to z = 2.54; the cut at F10 in/min
    (4.2333 mm/s) to z = -1.27, x = 50.8, the G3 about (2, 1) in to (3, 1) in, Y2.; G0 Z.1; ``G91 G28 Z0.``
    goes via the current point (no move, line 16) to z = 50.8, and ``G28 X0. Y0.``, still under G91,
    via the current point (line 17) to x = y = 0."""
    prog = read("fanuc_post.ngc", **PROGRAM_ARGS["fanuc_post.ngc"])
    b = prog.blocks
    ends = [[25.4, 0, 50.8], [25.4, 0, 2.54], [25.4, 0, -1.27], [50.8, 0, -1.27], [76.2, 25.4, -1.27],
            [76.2, 50.8, -1.27], [76.2, 50.8, 2.54], [76.2, 50.8, 50.8], [0, 0, 50.8]]
    np.testing.assert_allclose(b.ends, ends, atol=1e-12)
    assert prog.block_lines.tolist() == [6, 7, 9, 10, 11, 12, 13, 16, 17]
    assert prog.block_rapid.tolist() == [True, True] + [False] * 4 + [True] * 3
    np.testing.assert_allclose(prog.block_feeds[~prog.block_rapid], 10 * 25.4 / 60, rtol=1e-12)
    np.testing.assert_allclose(b.centers[b.is_arc], [[50.8, 25.4, -1.27]], atol=1e-12)
    assert prog.no_motion_lines == (16, 17)
    check_consistent(prog)


def test_g28_without_home_returns_to_the_machine_origin():
    """mill_post.ngc without ``home``, from (0, 0, 50): its ``G28`` lines return to LinuxCNC's default
    home, the machine origin, here the program's (0, 0, 0) (no ``machine_origin`` either), noted in
    ``assumed`` at line 8, the first. By hand as the test above with home z = 0: line 8 a rapid down
    to (0, 0, 0), line 21 from (25, 20, 15) to (25, 20, 0), line 23 via (30, 20, 0) to (0, 0, 0)."""
    prog = read("mill_post.ngc", start=(0.0, 0.0, 50.0))
    ends = [[0, 0, 0], [10, 5, 0], [10, 5, 15], [10, 5, 5], [10, 5, -1], [20, 5, -1], [25, 10, -1], [25, 20, -1],
            [25, 20, 15], [25, 20, 0], [30, 20, 0], [0, 0, 0]]
    np.testing.assert_allclose(prog.blocks.ends, ends, atol=1e-12)
    assert prog.block_lines.tolist() == [8, 13, 14, 15, 16, 17, 18, 19, 20, 21, 23, 23]
    assert [a.split(":")[0] for a in prog.assumed] == ["line 8", "line 8"]


def test_spiral_beyond_tolerance_names_both_radii():
    """40 um at r = 10 exceeds LinuxCNC's 0.0283 mm and 0.1 % of the radius: refused, with both radii
    in the message."""
    with pytest.raises(GCodeError, match=r"<string>:2:14: G3 end point is not on the arc: start radius 10 mm and "
                                         r"end radius 10.04 mm"):
        parse_gcode("G0 X10\nG3 X0 Y10.04 I-10 J0 F60")


def test_g20_arc_tolerance_is_linuxcnc_inch_value():
    """Under G20 LinuxCNC's absolute tolerance is 2 * 0.001 * sqrt(2) in = 0.0718 mm: at r = 1 in an
    end radius 0.002 in (0.0508 mm, 0.2 %) off passes, 0.003 in (0.0762 mm, 0.3 %) does not."""
    parse_gcode("G20 G0 X1\nG3 X0 Y1.002 I-1 F10")
    with pytest.raises(GCodeError, match="not on the arc"):
        parse_gcode("G20 G0 X1\nG3 X0 Y1.003 I-1 F10")


def test_hand_built_program_gets_line_blocks():
    poly = Polyline([[0, 0, 0], [1, 0, 0], [1, 1, 0]])
    prog = GCodeProgram(poly, [1.0, 2.0], [False, True], [1, 2])
    assert prog.n_blocks == 2 and not prog.blocks.is_arc.any()
    np.testing.assert_array_equal(prog.segment_block, [0, 1])
    assert np.isnan(prog.block_tolerance).all()
    with pytest.raises(PathError):
        GCodeProgram(poly, [1.0, 2.0], [False, True], [1, 2], blocks=prog.blocks)  # block arrays missing


@pytest.mark.parametrize("name", sorted(p.name for p in PROGRAMS.glob("*.ngc")))
def test_programs_round_trip_through_to_gcode_with_arcs(name):
    """to_gcode(program) writes the blocks (arcs as G2/G3 with G91.1 offsets, P turns, G64 P changes);
    reading it back gives the same ends (exactly), tolerances, feeds, rapid flags, and sweeps/centres
    within float rounding of the offset."""
    prog = read(name, **PROGRAM_ARGS.get(name, {}))
    again = parse_gcode(to_gcode(prog), start=prog.blocks.start)
    a, b = prog.blocks, again.blocks
    np.testing.assert_array_equal(b.ends, a.ends)
    np.testing.assert_allclose(b.sweeps, a.sweeps, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(b.centers[b.is_arc], a.centers[a.is_arc], atol=1e-12)
    np.testing.assert_array_equal(b.normals[b.is_arc], a.normals[a.is_arc])
    np.testing.assert_array_equal(again.block_tolerance, prog.block_tolerance)
    np.testing.assert_array_equal(again.block_pauses, prog.block_pauses)
    np.testing.assert_array_equal(again.block_rapid, prog.block_rapid)
    np.testing.assert_array_equal(again.block_feeds, prog.block_feeds)


def test_block_delete_lines_are_read_with_the_switch_off_and_skipped_with_it_on():
    """block_delete.ngc (comments of the file give each block): with the switch off (LinuxCNC's
    default) the '/' lines are read as if the '/' were not there, with it on they are skipped."""
    off = read("block_delete.ngc")
    np.testing.assert_allclose(off.blocks.ends[:, :2], [[10, 0], [10, 10], [0, 10], [-10, 10]], atol=1e-12)
    np.testing.assert_array_equal(off.block_lines, [5, 7, 8, 11])
    np.testing.assert_array_equal(off.block_tolerance, [NAN, 0.0, 0.0, 0.01])
    np.testing.assert_allclose(off.blocks.centers[3, :2], [-5, 10], atol=1e-12)
    on = read("block_delete.ngc", block_delete=True)
    np.testing.assert_allclose(on.blocks.ends[:, :2], [[10, 0], [0, 0], [-10, 0]], atol=1e-12)
    np.testing.assert_array_equal(on.block_lines, [5, 8, 11])
    np.testing.assert_array_equal(on.block_tolerance, [NAN, NAN, 0.01])
    np.testing.assert_allclose(on.blocks.centers[2, :2], [-5, 0], atol=1e-12)
    for prog in (off, on):
        np.testing.assert_allclose(prog.blocks.sweeps[-1], PI, rtol=1e-12)
        check_consistent(prog)
