"""``G53`` (move in machine coordinates) as LinuxCNC runs it, on programs written as CAM posts
(Fusion 360, Mastercam) write their tool-change and end-of-program retracts.

The reader has no work-offset table: ``machine_origin`` is the machine origin in the program frame
(minus the work offset), and ``G53 X Y Z`` goes to ``machine_origin + (X, Y, Z)``. Expected block
ends below are worked out by hand from the origin each test passes, not taken from the reader.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from research.errors import GCodeError, ParameterError
from research.paths.gcode import parse_gcode, read_gcode

#: a work offset G54 = (-350, -250, -400) mm with a 100 mm tool length folded into z (the program's
#: coordinates are tool-tip coordinates): the machine origin in the program frame
ORIGIN = (350.0, 250.0, 300.0)

#: a two-tool program as a Fusion 360 Fanuc/Haas post writes it: G53 G0 Z0. before each tool change,
#: G53 G0 Z0. and G53 G0 X0. Y0. at the end (line numbers in the comments of the test below)
FUSION_POST = """%
O1001
(T1  D=6. CR=0. - ZMIN=-1. - FLAT END MILL)
G90 G94 G17 G49 G40 G80
G21
G53 G0 Z0.
(2D CONTOUR1)
T1 M6
S8000 M3
G54
G0 X10. Y5.
G43 Z15. H1
G1 Z-1. F600.
X30. F1200.
G0 Z15.
G53 G0 Z0.
T2 M6
S6000 M3
G0 X40. Y5.
G43 Z15. H2
G1 Z-1. F600.
Y25.
G0 Z15.
G53 G0 Z0.
G53 G0 X0. Y0.
M30
%
"""


def test_fusion_post_retracts_and_tool_change():
    """FUSION_POST from the machine origin (start = ORIGIN, the machine homed at machine 0, 0, 0), by
    hand with ORIGIN = (350, 250, 300): line 6 ``G53 G0 Z0.`` goes to z = 300 + 0, where the tool
    already is (no move); lines 11-15 cut in the program frame; line 16 retracts to (30, 5, 300);
    after the tool change lines 19-23 cut again from (40, 5, 300); line 24 retracts to (40, 25, 300)
    and line 25 moves X and Y to the machine origin (350, 250), Z unchanged. G0 blocks at the rapid
    feed (15000 mm/min = 250 mm/s), F600 = 10 mm/s, F1200 = 20 mm/s."""
    prog = parse_gcode(FUSION_POST, machine_origin=ORIGIN, start=ORIGIN)
    ends = [[10, 5, 300], [10, 5, 15], [10, 5, -1], [30, 5, -1], [30, 5, 15], [30, 5, 300],
            [40, 5, 300], [40, 5, 15], [40, 5, -1], [40, 25, -1], [40, 25, 15], [40, 25, 300], [350, 250, 300]]
    np.testing.assert_allclose(prog.blocks.ends, ends, rtol=0, atol=1e-12)
    assert prog.block_lines.tolist() == [11, 12, 13, 14, 15, 16, 19, 20, 21, 22, 23, 24, 25]
    rapid = [True, True, False, False, True, True, True, True, False, False, True, True, True]
    assert prog.block_rapid.tolist() == rapid
    np.testing.assert_allclose(prog.block_feeds, np.where(rapid, 250.0, [0, 0, 10, 20, 0, 0, 0, 0, 10, 10, 0, 0, 0]),
                               rtol=1e-15)
    assert prog.no_motion_lines == (6,)
    assert not prog.blocks.is_arc.any() and prog.end_line == 26


def test_g53_from_another_start_moves_line_6():
    """The same program from (0, 0, 0) in the program frame: line 6 is now a rapid of 300 mm up to
    z = 300, the first block."""
    prog = parse_gcode(FUSION_POST, machine_origin=ORIGIN)
    np.testing.assert_allclose(prog.blocks.ends[:2], [[0, 0, 300], [10, 5, 300]], rtol=0, atol=1e-12)
    assert prog.block_lines[:2].tolist() == [6, 11] and prog.block_rapid[0] and prog.no_motion_lines == ()
    assert prog.blocks.lengths[0] == pytest.approx(300.0, rel=1e-15)


def test_g53_in_inches_and_only_some_axes():
    """Under G20 the words are inches (x 25.4) added to the origin in mm; the axes not given keep their
    position. ORIGIN2 = (100, 50, 200) mm: G0 to (25.4, 25.4, 12.7); G1 Z-.1 at F20 in/min
    (20 * 25.4 / 60 = 8.4667 mm/s) to z = -2.54; ``G53 G0 Z0.`` to z = 200 (x, y kept);
    ``G53 X-2. Y3.`` (G0 modal) to (100 - 50.8, 50 + 76.2) = (49.2, 126.2), z kept at 200;
    ``G53 G0 Z1.5`` to z = 200 + 38.1 = 238.1."""
    origin = (100.0, 50.0, 200.0)
    text = "G20 G90\nG0 X1. Y1. Z.5\nG1 Z-.1 F20.\nG53 G0 Z0.\nG53 X-2. Y3.\nG53 G0 Z1.5\n"
    prog = parse_gcode(text, machine_origin=origin)
    np.testing.assert_allclose(prog.blocks.ends, [[25.4, 25.4, 12.7], [25.4, 25.4, -2.54], [25.4, 25.4, 200],
                                                  [49.2, 126.2, 200], [49.2, 126.2, 238.1]], rtol=1e-14, atol=1e-12)
    assert prog.block_lines.tolist() == [2, 3, 4, 5, 6]
    assert prog.block_rapid.tolist() == [True, False, True, True, True]
    assert prog.block_feeds[1] == pytest.approx(20 * 25.4 / 60, rel=1e-15)


def test_g53_is_not_modal_and_g1_may_be_modal():
    """``G53`` with G1 in effect but not on its line is a feed move (10 mm/s, F600) to the machine
    coordinates; the next line without G53 is in the program frame again. Origin (-5, 2, 20):
    X5 -> (5, 0, 0); ``G53 Z10`` -> (5, 0, 30) at the feed; ``X7`` -> (7, 0, 30) (not -5 + 7);
    ``G53 G1 Y-1 F300`` -> (7, 1, 30) at 5 mm/s."""
    prog = parse_gcode("G1 X5 F600\nG53 Z10\nX7\nG53 G1 Y-1 F300\n", machine_origin=(-5.0, 2.0, 20.0))
    np.testing.assert_allclose(prog.blocks.ends, [[5, 0, 0], [5, 0, 30], [7, 0, 30], [7, 1, 30]], rtol=0, atol=1e-12)
    assert not prog.block_rapid.any()
    np.testing.assert_allclose(prog.block_feeds, [10, 10, 10, 5], rtol=1e-15)


def test_g53_g0_without_axis_words_only_sets_the_motion_mode():
    """LinuxCNC accepts ``G53 G0`` alone (G0 needs no axis words): it sets G0 and moves nothing, so
    the following ``X8`` is a rapid; the line is not a no-motion line (it has no axis words)."""
    prog = parse_gcode("G1 X5 F600\nG53 G0\nX8\n", machine_origin=(0.0, 0.0, 0.0))
    np.testing.assert_allclose(prog.blocks.ends, [[5, 0, 0], [8, 0, 0]], rtol=0, atol=1e-12)
    assert prog.block_rapid.tolist() == [False, True] and prog.no_motion_lines == ()


def test_g90_on_the_g53_line_lifts_a_modal_g91():
    """A post's ``G28 G91 Z0.`` leaves G91 in effect; ``G90 G53 G0 Z0.`` (G90 on the line, applied
    before the move) is accepted, as in LinuxCNC. home (0, 0, 50), origin (0, 0, 80): G28 G91 Z0 goes
    via the current point to z = 50; G53 to z = 80."""
    prog = parse_gcode("G0 X10 Z5\nG28 G91 Z0.\nG90 G53 G0 Z0.\n", home=(0.0, 0.0, 50.0), machine_origin=(0.0, 0.0, 80.0))
    np.testing.assert_allclose(prog.blocks.ends, [[10, 0, 5], [10, 0, 50], [10, 0, 80]], rtol=0, atol=1e-12)
    assert prog.block_lines.tolist() == [1, 2, 3]


def test_g53_and_g28_without_machine_origin_or_home_take_linuxcncs_defaults(tmp_path, caplog):
    """Without ``machine_origin`` the reader takes LinuxCNC's default configuration: a work offset
    of 0, so ``G53 Z0.`` goes to the program's z = 0; without ``home`` too, ``G28`` returns to the
    machine origin (its position parameters 5161-5163 at 0), here (0, 0, 0). By hand from (0, 0,
    0): line 2 to (10, 0, 5), line 3 to z = 0, line 4 up to z = 7 (G91), line 5 ``G28 Z0.`` (G91,
    intermediate point its own position) to z = 0, line 6 to (10, 3, 0). Each default is noted in
    ``assumed`` with its first line and the argument that sets it, and logged as a warning."""
    f = tmp_path / "part.nc"
    f.write_text("G21 G90\nG0 X10 Z5\nN60 G53 G0 Z0.\nG91 G0 Z7\nG28 Z0.\nG90 G1 Y3 F600\n")
    with caplog.at_level("WARNING", logger="research.paths.gcode"):
        prog = read_gcode(f)
    np.testing.assert_allclose(prog.blocks.ends, [[10, 0, 5], [10, 0, 0], [10, 0, 7], [10, 0, 0], [10, 3, 0]],
                               atol=1e-12)
    assert len(prog.assumed) == 2
    assert prog.assumed[0].startswith("line 3: the machine origin of G53/G28 taken as (0, 0, 0) mm")
    assert "machine_origin_mm" in prog.assumed[0]
    assert prog.assumed[1].startswith("line 5: G28 returned to (0.0, 0.0, 0.0) mm") and "home_mm" in prog.assumed[1]
    assert sum(r.levelname == "WARNING" and str(f) in r.getMessage() for r in caplog.records) == 2
    given = read_gcode(f, machine_origin=(1.0, 2.0, 50.0))  # G28 returns to the given origin
    assert len(given.assumed) == 1 and given.assumed[0].startswith("line 5: G28 returned to (1.0, 2.0, 50.0) mm")
    np.testing.assert_allclose(given.blocks.ends[3], [10, 0, 50], atol=1e-12)
    assert read_gcode(f, machine_origin=(1.0, 2.0, 50.0), home=(0.0, 0.0, 9.0)).assumed == ()


@pytest.mark.parametrize("text, line, column, match", [
    # an arc mode in effect (G2 from the line before) or on the G53 line
    ("G0 X10\nG2 X0 Y10 R10 F600\nG53 Z0", 3, 1, r"G53 with the arc motion mode G2 in effect; expected G0 or G1"),
    ("G0 X10\nG53 G3 X0 Y10 R10 F600", 2, 1, r"G53 with the arc motion mode G3 in effect"),
    # no motion mode: none yet, or cancelled by G80
    ("G53 X1", 1, 1, r"G53 with no motion mode in effect \(none yet, or cancelled by G80\)"),
    ("G0 X1\nG80\nG53 X1", 3, 1, r"G53 with no motion mode in effect"),
    # G53 alone (LinuxCNC: "must use G0 or G1 with G53"), even with G0 in effect
    ("G0 X1\nG53", 2, 1, r"G53 without G0/G1 on the line and without X, Y or Z; expected G53 G0 or G53 G1"),
    # incremental (LinuxCNC: "cannot use G53 incremental"), modal or on the line
    ("G0 X1\nG91\nG53 G0 Z0", 3, 1, r"G53 under G91 \(incremental distance mode\); expected G90"),
    ("G0 X1\nG0 G91 G53 Z0", 2, 8, r"G53 under G91"),
    # two of one group, and two group-0 codes
    ("G0 X1\nG53 G53 G0 Z0", 2, 5, r"two G-codes of the machine coordinates group on one line \(G53 and G53\)"),
    ("G0 X1\nG28 G53 G0 Z0", 2, 5, r"G53 and G28 on one line; expected at most one of G4, G28, G53"),
    ("G0 X1\nG4 P1 G53 G0 Z0", 2, 7, r"G53 and G4 on one line"),
    # arc words with a straight G53 move; a target beyond the coordinate bound
    ("G0 X1\nG53 G0 X2 I1", 2, 11, r"I is only used with G2/G3 arcs"),
    ("G0 X1\nG53 G0 X999999", 2, 8, r"G53 X999999: expected a finite machine coordinate .* inside \+-1e\+06 mm"),
    # a feed move before any F word
    ("G0 X1\nG53 G1 Z5", 2, 5, r"G1 motion before any F word"),
])
def test_bad_g53_names_line_and_column(text, line, column, match):
    with pytest.raises(GCodeError, match=rf"^<string>:{line}:{column}: {match}"):
        parse_gcode(text, machine_origin=(10.0, 0.0, 0.0), home=(0.0, 0.0, 0.0))


@pytest.mark.parametrize("origin", [(1.0, 2.0), (0.0, math.nan, 0.0), (2e6, 0.0, 0.0), "abc"])
def test_bad_machine_origin_is_a_parameter_error(origin):
    with pytest.raises(ParameterError, match=r"parse_gcode: machine_origin must be 3 finite numbers"):
        parse_gcode("G0 X1", machine_origin=origin)
