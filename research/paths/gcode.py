"""G-code reader and writer: the plain RS274/NGC subset of CAM post-processors and LinuxCNC's own
trajectory-planner tests, read into tool-path blocks (lines and arcs kept as arcs) and chords.

The reader gives both views of a program: :attr:`GCodeProgram.blocks`, a
:class:`~research.paths.toolpath.ToolPath` with one block per ``G0``/``G1`` move and per ``G2``/``G3``
arc (circular, helical or spiral, in the G17, G18 or G19 plane, with per-block feed, rapid flag,
source line and ``G64 P`` tolerance), and :attr:`GCodeProgram.polyline`, the straight segments the
polyline interpolators work on (arcs as chords whose chord error is at most ``chord_tolerance``,
``segment_block`` maps each chord to its block). All lengths inside are mm and feeds mm/s; ``F``
words are read as mm/min (in/min under ``G20``).

Plain ``[N] [G0|G1] [X] [Y] [Z] [F]`` lines are matched whole by one regular expression and executed
directly; every other line is tokenized by one regular expression (no per-character Python loop), so
ordinary CAM output with 10^5 short ``G1`` lines is read in well under a second.

Accepted words (anything else is a :class:`~research.errors.GCodeError` naming file, line and column):

* ``G0 G1 G2 G3`` motion (modal: a line with only coordinates continues the last motion mode),
  ``G80`` (cancel motion mode; on a line with a motion code it is ignored, as LinuxCNC does);
* ``G17 G18 G19`` (XY, ZX, YZ arc planes, centre words ``I J`` / ``K I`` / ``J K``),
  ``G20``/``G21`` (inch / mm), ``G90``/``G91`` (absolute / incremental ``X Y Z``),
  ``G90.1``/``G91.1`` (absolute / incremental arc centres; incremental is the default);
* path control: ``G64 P<tol>`` (blend tolerance of the following blocks, ``block_tolerance``;
  ``P0`` is no tolerance, as ``G64`` alone: LinuxCNC's planner reads a zero tolerance so),
  ``G64 P<tol> Q<tol>`` (Q, LinuxCNC's naive-CAM tolerance, is accepted and ignored), ``G64``
  without ``P`` (no tolerance given: NaN), ``G61``/``G61.1`` (exact path / exact stop: tolerance 0);
* harmless modal codes that do not change the geometry: ``G40`` (cutter compensation off), ``G43``
  ``[H<n>]`` / ``G49`` (tool length offset on / off: the program coordinates are taken as tool-tip
  coordinates, so the offset moves only the machine's Z, as the work offsets move its frame),
  ``G54``-``G59`` (work offsets: the program frame is taken as the work frame, one frame for all six,
  whose machine origin is ``machine_origin``), ``G94`` (feed per minute, the only feed mode supported),
  ``G98``/``G99`` (canned-cycle retract mode, written in the safety line of Fanuc-style posts: with the
  canned cycles refused it changes nothing);
* ``G28 [X] [Y] [Z]`` (return to home, LinuxCNC: a rapid to the point of the axis words, then a
  rapid of those axes, or of all three when none is given, to the home position ``home``; without
  it LinuxCNC's default, the machine origin (noted in ``GCodeProgram.assumed`` and logged);
* ``G53 [G0|G1] [X] [Y] [Z]`` (move in machine coordinates, LinuxCNC; not modal: on each line that
  uses it): a straight ``G0`` or ``G1`` block to ``machine_origin`` plus the axis words (absolute, in
  the current units; axes not given keep their position); without ``machine_origin`` LinuxCNC's
  default of a work offset of 0, the program's origin (noted and logged). As LinuxCNC it needs ``G0`` or ``G1`` on its line or
  in effect (an arc mode, ``G80`` or a lone ``G53`` is an error), and ``G90``: ``G53`` under ``G91`` is
  an error (LinuxCNC's "cannot use G53 incremental"); ``G53 G0`` without axis words only sets the
  motion mode;
* ``G4 P<seconds>`` (dwell; P in seconds whatever the units, as LinuxCNC: Fanuc's milliseconds are
  not read) and ``M0 M1 M60`` (program stop, optional stop, pallet-change pause: a stop of 0 s, the
  operator's wait not counted): the motion stops at the vertex and waits (``block_pauses``; the FIR
  planner takes them as exact stops held that long). G4 runs before the motion of its line, the
  stops after it (RS274/NGC order of execution);
* ``M2 M30`` (program end: the lines after it are not read, as LinuxCNC, and are listed in
  ``GCodeProgram.unread_lines``; so are those after a closing ``%``), ``M3 M4 M5``
  (spindle), ``M6`` (tool change), ``M7 M8 M9`` (coolant);
* ``N`` (line number), ``O`` (program number; both non-negative integers of at most 15 digits,
  ignored), ``S`` (spindle speed >= 0, ignored), ``T`` (tool number, non-negative integer, ignored),
  ``H`` (tool length offset number, non-negative integer, only with ``G43``, ignored),
  ``F`` (feed > 0, modal), ``X Y Z``, ``I J K R`` (arc centre / radius), ``P`` (``G64`` tolerance,
  ``G4`` dwell, or number of turns of ``G2``/``G3``: an integer >= 1, P1 the plain arc, as LinuxCNC), ``Q`` (with
  ``G64`` only);
* comments ``( ... )`` (not nested, closed on the same line) and ``; ...`` to the end of the line,
  ``%`` delimiter lines (a file whose first non-blank line is a lone ``%`` ends at the next ``%``
  line, as LinuxCNC), a UTF-8 byte-order mark, blank lines, upper or lower case, words with or without spaces
  (``G1X10Y5F600``).

Arc end radius: as LinuxCNC (its G2/G3 documentation, "It is an error if ... [the two radii differ]
by more than (.05 inch/.5 mm) OR ((.0005 inch/.005mm) AND .1% of radius)", with the absolute
tolerance of ``interp_internal.hh``): start and end radius may differ by up to
``CENTER_ARC_RADIUS_TOLERANCE_MM = 2 * 0.01 * sqrt(2) = 0.0283`` mm whatever the radius (G21; under
G20 ``2 * 0.001 * sqrt(2)`` in = 0.0718 mm), so the small arcs of programs written to 3 decimals of mm
are read; beyond that by up to 0.1 % (``SPIRAL_RELATIVE_TOLERANCE``) of the larger radius, and never
by more than 100 times the absolute tolerance (2.83 mm; ``SPIRAL_HARD_LIMIT_FACTOR``). Such arcs
become spiral blocks. Radii below ``RADIUS_TOLERANCE_MM`` = 0.00127 mm are zero-radius arcs (refused).

Refused with a message naming the feature: O-word subroutines and control flow (``o100 sub``,
``o<name> call``, ``if``, ``while`` ...), ``M98``/``M99``, ``#`` parameters (``#1``, ``#<name>``),
expressions ``[...]`` and functions (``sin[30]``), ``/`` anywhere but first on its line (block
delete, read as LinuxCNC with its switch off, or skipped with ``block_delete=True``), ``/1``-``/9``
skip levels; ``G17.1 G18.1 G19.1`` (UVW
planes), ``G41 G42 G41.1 G42.1`` (cutter compensation), ``G43.1 G43.2`` (dynamic / additional tool length
offsets), ``G4`` without ``P``, ``G5 G5.1 G5.2`` (splines),
``G53`` with an arc mode or ``G80`` in effect,
without ``G0``/``G1`` and axis words, under ``G91``, or with ``G4``/``G28`` on its line, ``G30 G92``
(secondary home, coordinate-system offset), ``G73 G76 G81``-``G89`` (canned
cycles), ``G93 G95`` (inverse-time / per-revolution feed), every other G or M code (a code with more
than one decimal digit such as ``G1.00000001`` is not read as ``G1``); an extra axis ``A B C U V W``
that moves (its first word, under ``G90`` on a rapid or a line without motion, puts it in place,
and every later word must repeat that position; under ``G91`` only 0: a 4-axis post's ``A0.`` on a
3-axis job is read, X, Y, Z alone are planned), ``D`` (cutter radius offset), ``H`` without
``G43``, ``L``, every other letter; a nonzero off-plane centre word (``K`` in
G17, ``J`` in G18, ``I`` in G19), ``P`` or ``Q`` with nothing to use them; two G-codes of one modal
group on one line (e.g. two motion codes), a letter given twice on one line, a malformed number
(``X1.2.3``, ``X``), a number that is not finite or beyond the bounds (coordinates, centres, radii
and tolerances within :data:`MAX_COORDINATE_MM` = 1e6 mm after scaling, feeds at most
:data:`MAX_FEED_MM_PER_MIN`), an arc beyond the radius tolerance (naming both radii), a full circle
with ``R``, an unclosed or nested ``(``, any other stray character.
"""

from __future__ import annotations

import gc
import logging
import re
from dataclasses import dataclass
from os import PathLike, fspath

import numpy as np

from research.errors import GCodeError, ParameterError, PathError
from research.paths._gcode_constants import (  # noqa: F401  (public constants)
    CENTER_ARC_RADIUS_TOLERANCE_INCH,
    CENTER_ARC_RADIUS_TOLERANCE_MM,
    MAX_ARC_TURNS,
    MAX_CHORD_ANGLE,
    MAX_CHORDS_PER_ARC,
    MAX_COORDINATE_MM,
    MAX_FEED_MM_PER_MIN,
    MM_PER_INCH,
    RADIUS_TOLERANCE_MM,
    SPIRAL_RELATIVE_TOLERANCE,
    ZERO_LENGTH_MM,
)
from research.paths._gcode_interpreter import (
    _check_positive,
    _Interpreter,
    _LineError,
)
from research.paths._gcode_writer import to_gcode
from research.paths.polyline import Polyline
from research.paths.toolpath import ToolPath

__all__ = ["GCodeProgram", "parse_gcode", "read_gcode", "to_gcode"]

# One token per match within a line. Groups: 1 letter, 2 number (a word), 3 '%', 4 anything illegal.
# Whitespace and well-formed comments match with all groups empty and are skipped. A word whose
# number is followed by another digit or '.' ("X1.2.3") does not match the word branch, so its
# letter falls through to group 4 and is diagnosed there.
_TOKEN = re.compile(
    r"[ \t]*([A-Za-z])[ \t]*([-+]?(?:[0-9]+\.?[0-9]*|\.[0-9]+))(?![0-9.])"
    r"|[ \t]+|\([^()\n]*\)|;[^\n]*"
    r"|(%)"
    r"|(.)"
)
# The commonest CAM line, "[N..] [G0|G1] [X..] [Y..] [Z..] [F..]" without comments, is matched whole
# and executed without tokenizing (_Interpreter.simple); anything else goes through _TOKEN.
_NUM = r"([-+]?(?:[0-9]+\.?[0-9]*|\.[0-9]+))[ \t]*"
_SIMPLE = re.compile(
    r"[ \t]*(?:[Nn][ \t]*[0-9]{1,15}[ \t]*)?(?:[Gg][ \t]*0*([01])(?:\.0*)?[ \t]*)?"
    rf"(?:[Xx][ \t]*{_NUM})?(?:[Yy][ \t]*{_NUM})?(?:[Zz][ \t]*{_NUM})?(?:[Ff][ \t]*{_NUM})?"
)
_BLOCK_DELETE = re.compile(r"[ \t]*/([0-9])?")  # the block delete character, first on its line
_OWORD = re.compile(r"[ \t]*(?:[Nn][ \t]*[0-9]+[ \t]*)?([Oo])[ \t]*(<[^>\n]*>?|[0-9]+)[ \t]*([A-Za-z]*)")
_OWORD_KEYWORDS = frozenset("sub endsub call return if elseif else endif do while endwhile repeat endrepeat "
                            "break continue".split())


@dataclass(frozen=True, eq=False)
class GCodeProgram:
    """A G-code program as blocks (lines and arcs kept as arcs) and as straight chords with feeds.

    Attributes:
        polyline: ``(M + 1, 3)`` vertices [mm], axes ``x, y, z``; the first vertex is the start
            position, arcs are broken into chords (chord error at most ``chord_tolerance``).
        feeds: ``(M,)`` feed of each chord [mm/s] (``F`` words are mm/min, or in/min under
            ``G20``, converted; ``G0`` segments get ``rapid_feed / 60``).
        rapid: ``(M,)`` bool, True for ``G0`` segments.
        lines: ``(M,)`` 1-based source line of each segment (all chords of an arc share its line).
        source: file name or ``"<string>"``.
        no_motion_lines: 1-based lines whose axis words left the position unchanged (moves shorter
            than :data:`ZERO_LENGTH_MM`); they produce no segment and no block.
        blocks: :class:`~research.paths.toolpath.ToolPath` with one block per ``G0``/``G1`` move and
            per ``G2``/``G3`` arc (circular, helical or spiral, in any of the G17/G18/G19 planes, arcs
            counter-clockwise about ``blocks.normals[k]``: ``G3`` has ``+z`` in G17, ``+y`` in G18,
            ``+x`` in G19, ``G2`` the opposite); ``blocks.start`` is ``polyline.points[0]``.
        block_feeds: ``(B,)`` feed of each block [mm/s].
        block_rapid: ``(B,)`` bool, True for ``G0`` blocks.
        block_lines: ``(B,)`` 1-based source line of each block.
        block_tolerance: ``(B,)`` path tolerance in force for the block [mm]: the ``G64 P`` value,
            0 under ``G61``/``G61.1``, NaN where none was given (``G64`` without ``P``, or no
            path-control word yet).
        segment_block: ``(M,)`` block of every chord of ``polyline``.
        block_pauses: ``(B + 1,)`` pause at each block vertex [s] (index 0 the start, ``k`` the
            end of block ``k - 1``, ``B`` the end): the sum of the ``G4 P`` dwells there, 0 for an
            ``M0``/``M1``/``M60`` stop without a dwell, NaN where the motion does not stop.
        end_line: 1-based line where reading stopped: the ``M2``/``M30`` line or the closing ``%``
            line (LinuxCNC reads nothing after either); 0 when the program ran to the end of the text.
        unread_lines: 1-based lines after ``end_line`` that hold anything but blanks or a lone
            ``%`` (not read, as LinuxCNC; listed so that nothing is dropped unseen).
        assumed: what the reader took from LinuxCNC's default configuration because the program
            needed it and it was not given, one sentence each naming the first line that used it
            and the argument that sets it: the machine origin of ``G53`` (and of ``G28``) where
            ``machine_origin`` is None, the home of ``G28`` where ``home`` is None (also logged as
            a warning).

    ``blocks`` and the ``block_*`` arrays may be left out (``None``) when building a program by hand:
    they are then one line block per polyline segment with NaN tolerance.

    Example:
        >>> prog = parse_gcode("G21 G90\\nG1 X10 F600\\nY5\\nG0 Z2")
        >>> prog.polyline.points.tolist()
        [[0.0, 0.0, 0.0], [10.0, 0.0, 0.0], [10.0, 5.0, 0.0], [10.0, 5.0, 2.0]]
        >>> prog.feeds.tolist(), prog.rapid.tolist(), prog.lines.tolist()
        ([10.0, 10.0, 250.0], [False, False, True], [2, 3, 4])
        >>> arc = parse_gcode("G64 P0.01\\nG1 X10 F600\\nG3 X0 Y10 I-10")
        >>> arc.blocks.is_arc.tolist(), arc.block_lines.tolist(), arc.block_tolerance.tolist()
        ([False, True], [2, 3], [0.01, 0.01])
        >>> round(float(arc.blocks.lengths[1]), 9), arc.blocks.normals[1].tolist()
        (15.707963268, [0.0, 0.0, 1.0])
    """

    polyline: Polyline
    feeds: np.ndarray
    rapid: np.ndarray
    lines: np.ndarray
    source: str = "<string>"
    no_motion_lines: tuple[int, ...] = ()
    blocks: ToolPath | None = None
    block_feeds: np.ndarray | None = None
    block_rapid: np.ndarray | None = None
    block_lines: np.ndarray | None = None
    block_tolerance: np.ndarray | None = None
    segment_block: np.ndarray | None = None
    block_pauses: np.ndarray | None = None
    end_line: int = 0
    unread_lines: tuple[int, ...] = ()
    assumed: tuple[str, ...] = ()

    def __post_init__(self):
        m = self.polyline.n_segments
        for name, dtype in (("feeds", np.float64), ("rapid", bool), ("lines", np.int64)):
            a = np.array(getattr(self, name), dtype=dtype)
            if a.shape != (m,):
                raise PathError(f"GCodeProgram.{name} must have shape ({m},) (one per segment), got {a.shape}")
            a.setflags(write=False)
            object.__setattr__(self, name, a)
        object.__setattr__(self, "no_motion_lines", tuple(int(i) for i in self.no_motion_lines))
        if self.blocks is None:
            object.__setattr__(self, "blocks", ToolPath.from_polyline(self.polyline))
            defaults = dict(block_feeds=self.feeds, block_rapid=self.rapid, block_lines=self.lines,
                            block_tolerance=np.full(m, np.nan), segment_block=np.arange(m))
            for name, value in defaults.items():
                if getattr(self, name) is None:
                    object.__setattr__(self, name, value)
        nb = self.blocks.n_blocks
        for name, dtype, shape in (("block_feeds", np.float64, nb), ("block_rapid", bool, nb),
                                   ("block_lines", np.int64, nb), ("block_tolerance", np.float64, nb),
                                   ("segment_block", np.int64, m)):
            if getattr(self, name) is None:
                raise PathError(f"GCodeProgram.{name} is required with blocks")
            a = np.array(getattr(self, name), dtype=dtype)
            if a.shape != (shape,):
                raise PathError(f"GCodeProgram.{name} must have shape ({shape},), got {a.shape}")
            a.setflags(write=False)
            object.__setattr__(self, name, a)
        pauses = np.full(nb + 1, np.nan) if self.block_pauses is None else \
            checked_pauses(self.block_pauses, nb, "GCodeProgram.block_pauses", PathError).copy()
        pauses.setflags(write=False)
        object.__setattr__(self, "block_pauses", pauses)
        sb = self.segment_block
        if m and (sb[0] != 0 or sb[-1] != nb - 1 or np.any(np.diff(sb) < 0) or np.any(np.diff(sb) > 1)):
            raise PathError("GCodeProgram.segment_block must run from block 0 to the last block in order")

    @property
    def n_segments(self) -> int:
        """Number of segments ``M``."""
        return self.polyline.n_segments

    @property
    def n_blocks(self) -> int:
        """Number of blocks ``B`` (moves and arcs)."""
        return self.blocks.n_blocks

    @property
    def pauses(self) -> np.ndarray:
        """``(M + 1,)`` :attr:`block_pauses` on the polyline's vertices [s] (NaN inside arcs and
        wherever the motion does not stop).

        Example:
            >>> parse_gcode("G1 X10 F600\\nG4 P2\\nG1 Y5").pauses.tolist()
            [nan, 2.0, nan]
        """
        out = np.full(self.n_segments + 1, np.nan)
        ends = np.concatenate([[0], np.flatnonzero(np.diff(self.segment_block)) + 1, [self.n_segments]])
        out[ends] = self.block_pauses
        return out

    @property
    def nominal_durations(self) -> np.ndarray:
        """Time of each segment at its programmed feed [s], ``lengths / feeds``, shape ``(M,)``.

        Example:
            >>> parse_gcode("G1 X10 F600").nominal_durations.tolist()
            [1.0]
        """
        return self.polyline.lengths / self.feeds


def _diagnose_bad_char(line_text: str, column: int) -> tuple[str, int]:
    """Explain the illegal character at 1-based ``column`` of ``line_text``; returns (message, column)."""
    o = _OWORD.match(line_text)
    if o is not None and (o.group(2).startswith("<") or o.group(3).lower() in _OWORD_KEYWORDS) \
            and o.start(1) < column + len(o.group(3)):
        what = f"{o.group(1)}{o.group(2)} {o.group(3)}".strip()
        return (f"O-word subroutines/control flow ({what}) are not supported; expected plain G-code "
                "(expand subroutines, loops and conditions in the CAM post-processor)", o.start(1) + 1)
    c = line_text[column - 1]
    rest = line_text[column:]
    if c.isascii() and c.isalpha():
        inner = re.match(r"[ \t]*[-+]?[ \t]*", rest)
        at = column + inner.end()
        nxt = line_text[at:at + 1]
        if nxt in ("#", "[") or re.match(r"[A-Za-z]+[ \t]*\[", line_text[at:]):
            return _diagnose_bad_char(line_text, at + 1 + (0 if nxt in ("#", "[") else line_text[at:].index("[")))
        m = re.match(r"[ \t]*([-+0-9.]*)", rest)
        got = m.group(1) if m else ""
        return ((f"word {c}{got!s} has no valid number: expected a number after {c} like 12, -0.5 or .25"
                 if got else f"letter {c!r} is not followed by a number; expected e.g. {c.upper()}10"), column)
    if c == "#":
        m = re.match(r"#[ \t]*(?:<[^>]*>?|[0-9]*)", line_text[column - 1:])
        return (f"parameters ({m.group(0)[:24]}) are not supported; expected plain numbers (no # parameters "
                "or expressions)", column)
    if c == "[":
        depth, end = 0, len(line_text)
        for i in range(column - 1, len(line_text)):
            depth += {"[": 1, "]": -1}.get(line_text[i], 0)
            if depth == 0:
                end = i + 1
                break
        begin = column - 1
        while begin > 0 and line_text[begin - 1].isascii() and line_text[begin - 1].isalpha():
            begin -= 1  # include a function name: sin[30]
        snippet = line_text[begin if begin < column - 1 and column - 1 - begin > 1 else column - 1:end]
        snippet = snippet if len(snippet) <= 24 else snippet[:21] + "..."
        return f"expressions [..] are not supported (found {snippet}); expected plain numbers", column
    if c == "/":
        return ("'/' after the start of the line; expected block delete '/' only as the line's first character "
                "(expressions such as [1/2] are not supported)"), column
    if c == "(":
        if "(" in rest.split(")", 1)[0]:  # at the inner '('
            return "nested '(' inside a comment; expected comments without parentheses inside", column + 1 + rest.index("(")
        return "comment '(' is not closed on this line; expected ')'", column
    if c == ")":
        return "')' without an opening '('; expected a comment like (text)", column
    return f"unexpected character {c!r}; expected a word (letter and number), a comment or a line end", column


def _word_column(line_text: str, word: int) -> int:
    """1-based column of the ``word``-th word (0-based) of a line, as the tokenizer sees it."""
    k = 0
    for m in _TOKEN.finditer(line_text):
        if m.group(1):
            if k == word:
                return m.start(1) + 1
            k += 1
    return 1


def checked_pauses(pauses, n_blocks: int, name: str = "pauses", error=ParameterError) -> np.ndarray:
    """``pauses`` as a float array ``(M + 1,)`` [s], one per vertex of ``n_blocks`` blocks (start and
    end included): NaN where the motion does not pause, else a dwell ``>= 0`` (0: a stop without a
    dwell, e.g. ``M0``), as :attr:`GCodeProgram.block_pauses` and the planners' ``pauses`` take them.

    Raises:
        ``error`` (ParameterError by default): a wrong shape, or a value neither NaN nor finite
        ``>= 0``, naming ``name`` and the vertex.
    """
    p = np.asarray(pauses, dtype=np.float64)
    if p.shape != (n_blocks + 1,):
        raise error(f"{name} must have shape (M + 1,) = ({n_blocks + 1},) (one per vertex, start and end "
                    f"included), got {p.shape}")
    bad = ~np.isnan(p) & ~(np.isfinite(p) & (p >= 0.0))
    if bad.any():
        k = int(np.flatnonzero(bad)[0])
        raise error(f"{name}[{k}] = {float(p[k])!r}: expected NaN (no pause) or a finite dwell >= 0 s")
    return p


def _point(name: str, value) -> tuple[float, float, float]:
    """``value`` as 3 finite coordinates (x, y, z) within +-MAX_COORDINATE_MM [mm], else a ParameterError."""
    try:
        p = np.asarray(value, dtype=np.float64).reshape(-1)
    except (TypeError, ValueError):
        raise ParameterError(f"parse_gcode: {name} must be 3 finite numbers (x, y, z) [mm], got {value!r}") from None
    if p.shape != (3,) or not np.all(np.abs(p) <= MAX_COORDINATE_MM):
        raise ParameterError(f"parse_gcode: {name} must be 3 finite numbers (x, y, z) within +-{MAX_COORDINATE_MM:g} "
                             f"mm, got {value!r}")
    return tuple(p.tolist())


def parse_gcode(
    text: str,
    *,
    source: str = "<string>",
    chord_tolerance: float = 1e-3,
    rapid_feed: float = 15000.0,
    initial_feed: float | None = None,
    start=(0.0, 0.0, 0.0),
    arc_radius_tolerance: float | None = None,
    arc_relative_tolerance: float = SPIRAL_RELATIVE_TOLERANCE,
    home=None,
    machine_origin=None,
    block_delete: bool = False,
) -> GCodeProgram:
    """Read a G-code program into blocks (lines and arcs) and straight chords with feeds.

    Args:
        text: the program.
        source: name used in error messages and stored in the result.
        chord_tolerance: largest chord error (sagitta) of the chords replacing an arc in
            ``polyline`` [mm]. An arc of radius ``r`` is cut into equal chords of angle at most
            ``2 acos(1 - tol / r)`` (computed as ``4 asin(sqrt(tol / (2 r)))``) and at most 90 deg.
            ``blocks`` keeps the arcs exact.
        rapid_feed: feed given to ``G0`` segments [mm/min].
        initial_feed: feed in effect before the first ``F`` word [mm/min]; ``None`` makes a
            ``G1``/``G2``/``G3`` before any ``F`` an error.
        start: start position ``(x, y, z)`` [mm] (first vertex of the polyline).
        arc_radius_tolerance: absolute tolerance on the difference of the start and end radius of a
            centre-format arc [mm]. ``None`` (default) uses LinuxCNC's default (rs274ngc
            ``interp_internal.hh``): ``CENTER_ARC_RADIUS_TOLERANCE_MM = 2 * 0.01 * sqrt(2) = 0.0283`` mm
            under G21 and ``CENTER_ARC_RADIUS_TOLERANCE_INCH = 2 * 0.001 * sqrt(2) = 0.00283`` in
            (0.0718 mm) under G20.
        arc_relative_tolerance: a difference above ``arc_radius_tolerance`` is still accepted while
            it is at most this fraction of the larger radius (LinuxCNC ``SPIRAL_RELATIVE_TOLERANCE =
            0.001``, 0.1 %), up to 100 times ``arc_radius_tolerance`` (LinuxCNC's rule, module
            docstring). An arc beyond is a :class:`GCodeError` naming both radii; an accepted one
            has its radius blended linearly along the arc (a spiral, as LinuxCNC does), so it ends
            exactly at the programmed point. For an absolute limit alone pass a tiny relative one.
        home: the machine home position ``(x, y, z)`` [mm] in the program frame, the target of ``G28``;
            ``None`` (default): LinuxCNC's with its G28 position parameters (5161-5163, machine
            coordinates) at 0, i.e. the machine origin, noted in ``GCodeProgram.assumed`` and
            logged (a CAM post's ``G28 G91 Z0.`` is a retract to the machine's Z home, which the
            program cannot tell: give it where the path of those rapids matters).
        machine_origin: the origin of the machine coordinate system ``(x, y, z)`` [mm] in the program
            frame, i.e. minus the active work offset (a work offset ``G54 X-100 Y-50 Z-200`` puts the
            machine origin at ``(100, 50, 200)`` in the program frame): ``G53 X Y Z`` goes to
            ``machine_origin + (X, Y, Z)``. One origin for the whole program: ``G54``-``G59`` are all
            taken as this one frame (the reader keeps no offset table). The program's coordinates are
            tool-tip coordinates, while LinuxCNC's ``G53`` words are the machine axis positions (the
            tool tip ends the tool length below them under ``G43``): give ``z`` less that length
            when a tool length offset is in force at the ``G53`` moves. ``None`` (default):
            LinuxCNC's with a work offset of 0, the program's origin ``(0, 0, 0)``, noted in
            ``GCodeProgram.assumed`` and logged.
        block_delete: the block delete switch. A line whose first character (after blanks) is
            ``/`` is skipped when True and read as if the ``/`` were not there when False (the
            default, LinuxCNC's switch off: "when block delete is on, lines starting with / are
            skipped"). A ``/`` followed by a digit (Fanuc's skip levels ``/1``-``/9``) is an error.

    Semantics worth knowing:

    * Within one line the units word applies first, then ``F``, then ``G61``/``G64``, then
      ``G90``/``G91``, the plane, then motion (so ``G20 F10 G1 X1`` is 10 in/min and
      ``G20 G64 P0.001`` is 0.0254 mm). An ``F`` value is converted to mm/s when it is read; a
      later ``G20``/``G21`` without a new ``F`` keeps that physical feed.
    * Arcs: in G17 the centre words are ``I``/``J`` (X/Y), in G18 ``K``/``I`` (Z/X), in G19
      ``J``/``K`` (Y/Z); the off-plane centre word (``K`` in G17, ``J`` in G18, ``I`` in G19) is an
      error, as in LinuxCNC, unless it is 0 (GRBL posts write ``K0`` on every G17 arc; GRBL ignores
      it). The words are offsets from the arc start (``G91.1``, the default) or
      absolute centre coordinates under ``G90.1``; ``G91`` does not affect them. ``R < 0`` selects
      the arc > 180 deg; ``R`` may be up to ``RADIUS_TOLERANCE_MM`` = 0.00127 mm (LinuxCNC's
      ``RADIUS_TOLERANCE_INCH * 25.4``) shorter than half the chord. A radius below 0.00127 mm is
      a zero-radius arc (an error). The axis normal to the plane moves linearly with the angle
      (a helix). ``G2``/``G3`` with the end equal to the start in the plane and a centre is a full
      circle; with ``R`` it is an error. ``P<n>`` (an integer >= 1, LinuxCNC semantics) is the
      number of turns: P1 is the plain arc, each further unit one more full turn (at most
      :data:`MAX_ARC_TURNS` = 10^4).
    * ``G64 P<tol>`` sets the blend tolerance (``block_tolerance``) of the following blocks, in
      program units; a ``Q`` with it (LinuxCNC's naive-CAM tolerance) is accepted and ignored.
      ``G61``/``G61.1`` (exact path / exact stop) set it to 0, ``G64`` without ``P`` to NaN (no
      tolerance given), and so does ``G64 P0``: LinuxCNC's planner reads a zero tolerance as none
      (``tcFindBlendTolerance``: "Detect zero tolerance = no tolerance").
    * ``G80`` on a line with a motion code is ignored (the motion code wins, as in LinuxCNC); alone
      it cancels the motion mode.
    * A move ending within :data:`ZERO_LENGTH_MM` of the last polyline vertex produces no segment;
      its line goes to ``no_motion_lines``. The commanded position still follows the program
      exactly, so the next real move ends where the program says. An arc starts at the last
      vertex (which may differ from the commanded position by less than ``ZERO_LENGTH_MM``).
    * Every number is checked after scaling: coordinates, centres, radii and tolerances must be
      finite and within :data:`MAX_COORDINATE_MM` (1e6 mm), feeds finite, > 0 and at most
      :data:`MAX_FEED_MM_PER_MIN`. A segment shorter than ``1e-12 * max |coordinate|`` (the
      resolution of :class:`Polyline`) is an error naming its line.
    * Columns in error messages are 1-based character positions in the line.

    Returns:
        :class:`GCodeProgram`.

    Raises:
        GCodeError: malformed or unsupported input (message ``source:line:column: what was
            expected``), or a program without any motion.
        ParameterError: a non-positive tolerance or feed argument.

    Example:
        >>> p = parse_gcode("G17 G21 G90 F1200\\nG1 X10\\nG3 X0 Y10 R10 ; quarter circle", chord_tolerance=1e-3)
        >>> p.polyline.points[-1].tolist(), p.lines[-1].item(), p.feeds[0].item()
        ([0.0, 10.0, 0.0], 3, 20.0)
    """
    tol = _check_positive("chord_tolerance", chord_tolerance)
    arc_tol = None if arc_radius_tolerance is None else _check_positive("arc_radius_tolerance", arc_radius_tolerance)
    arc_rel = _check_positive("arc_relative_tolerance", arc_relative_tolerance)
    rapid = _check_positive("rapid_feed", rapid_feed) / 60.0
    feed0 = None if initial_feed is None else _check_positive("initial_feed", initial_feed) / 60.0
    st = _point("start", start)
    home_t = None if home is None else _point("home", home)
    origin_t = None if machine_origin is None else _point("machine_origin", machine_origin)
    if not isinstance(block_delete, (bool, np.bool_)):
        raise ParameterError(f"parse_gcode: block_delete must be True or False (the block delete switch), got "
                             f"{block_delete!r}")
    if not isinstance(text, str):
        raise GCodeError(f"expected the program as str, got {type(text).__name__}", source=source, line=0, column=0)
    if text.startswith("\ufeff"):  # a byte-order mark written by some Windows editors
        text = text[1:]
    if "\r" in text:
        text = text.replace("\r\n", "\n").replace("\r", "\n")

    it = _Interpreter(tol, rapid, feed0, st, arc_tol, arc_rel, home_t, origin_t)
    line_fn = it.line
    simple_fn = it.simple
    simple_match = _SIMPLE.fullmatch
    tokens = _TOKEN.findall
    all_lines = text.split("\n")
    # LinuxCNC: a file whose first non-blank line is a lone '%' ends at the next '%' line
    first = next((k for k, t in enumerate(all_lines, 1) if t.strip()), 0)
    opening = first if first and all_lines[first - 1].strip() == "%" else 0
    end_line = 0

    def fail(lineno, message, column):
        raise GCodeError(message, source=source, line=lineno, column=column) from None

    # the interpreter appends 10^5..10^6 small tuples and lists: the cyclic GC would rescan them over and
    # over (quadratic time); nothing here makes reference cycles
    gc_enabled = gc.isenabled()
    gc.disable()
    try:
        for lineno, line_text in enumerate(all_lines, 1):
            if "/" in line_text:
                slash = _BLOCK_DELETE.match(line_text)
                if slash is not None:
                    if slash.group(1):
                        fail(lineno, f"block delete with a skip level (/{slash.group(1)}) is not supported; "
                             "expected a plain '/' (LinuxCNC's block delete switch, parse_gcode's block_delete)",
                             slash.start(1))
                    if block_delete:
                        continue  # the switch is on: the line is skipped
                    line_text = line_text[: slash.end() - 1] + " " + line_text[slash.end():]  # read without it
            m = simple_match(line_text)
            if m is not None and simple_fn(*m.groups(), lineno):
                continue
            words = []
            pct = 0
            for letter, num, percent, bad in tokens(line_text):
                if letter:
                    words.append((letter, num))
                elif bad:
                    column = next(t.start(4) + 1 for t in _TOKEN.finditer(line_text) if t.group(4))
                    if pct:  # a '%' line with text after it (a post's "% vfd enable")
                        fail(lineno, "'%' program delimiter must be alone on its line; expected no text with it "
                             f"(found {line_text[column - 1:].strip()[:24]!r})", column)
                    fail(lineno, *_diagnose_bad_char(line_text, column))
                elif percent:
                    pct = pct or 1
            if pct and words:
                column = next(t.start(3) + 1 for t in _TOKEN.finditer(line_text) if t.group(3))
                fail(lineno, "'%' program delimiter must be alone on its line; expected no words with it", column)
            if pct and opening and lineno > opening:
                end_line = lineno  # the closing '%': nothing after it is read
                break
            if words:
                try:
                    line_fn(words, lineno)
                except _LineError as e:
                    fail(lineno, e.message, _word_column(line_text, e.word))
                if it.ended:  # M2/M30: LinuxCNC does not read the lines after it
                    end_line = lineno
                    break
    finally:
        if gc_enabled:
            gc.enable()

    lineno = len(all_lines)
    if len(it.points) < 6:
        raise GCodeError(
            f"program has no motion ({len(it.no_motion)} line(s) with axis words left the position unchanged); "
            "expected at least one G0/G1/G2/G3 move", source=source, line=lineno, column=1)
    pts = np.frombuffer(it.points, dtype=np.float64).reshape(-1, 3).copy()
    meta = np.asarray(it.meta, dtype=np.float64).reshape(-1, 4)
    counts = np.frombuffer(it.counts, dtype=np.int64)
    seg_block = np.repeat(np.arange(counts.size), counts)
    b_feeds, b_rapid, b_lines, b_tols = meta[:, 0], meta[:, 1] != 0, meta[:, 2].astype(np.int64), meta[:, 3]
    feeds, rap, lines = b_feeds[seg_block], b_rapid[seg_block], b_lines[seg_block]
    # Polyline's zero-length rule is relative (1e-12 * max |coordinate|); name the line it rejects
    lengths = np.linalg.norm(np.diff(pts, axis=0), axis=1)
    scale = max(1.0, float(np.max(np.abs(pts))))
    short = np.flatnonzero(lengths <= 1e-12 * scale)
    if short.size:
        k = int(short[0])
        raise GCodeError(f"move of {lengths[k]:.3g} mm is below the path resolution 1e-12 * {scale:.6g} mm "
                         f"(the largest coordinate of the program) = {1e-12 * scale:.3g} mm; expected a longer "
                         "move or smaller coordinates", source=source, line=int(lines[k]), column=1)
    poly = Polyline(pts)
    nb = counts.size
    last = np.cumsum(counts) - 1
    centers = np.full((nb, 3), np.nan)
    normals = np.full((nb, 3), np.nan)
    sweeps = np.zeros(nb)
    for k, centre, normal, sweep in it.arcs:
        centers[k], normals[k], sweeps[k] = centre, normal, sweep
    try:
        blocks = ToolPath(pts[0], pts[last + 1], centers, normals, sweeps)
    except PathError as e:  # not expected: the interpreter checks arcs first
        m = re.search(r"block (\d+)", str(e))
        bad = int(m.group(1)) if m else 0
        raise GCodeError(f"block from this line is unusable: {e}", source=source,
                         line=int(b_lines[min(bad, nb - 1)]), column=1) from None
    pauses = np.full(nb + 1, np.nan)
    for k, p in it.pauses.items():
        pauses[k] = p
    unread = tuple(k for k in range(end_line + 1, len(all_lines) + 1)
                   if all_lines[k - 1].strip() not in ("", "%")) if end_line else ()
    assumed = []
    if "machine_origin" in it.assumed:
        assumed.append(f"line {it.assumed['machine_origin']}: the machine origin of G53/G28 taken as (0, 0, 0) mm in "
                       "the program frame, LinuxCNC's with a work offset of 0 (give machine_origin, [path] "
                       "machine_origin_mm in a config, for your machine's)")
    if "home" in it.assumed:
        home_at = origin_t or (0.0, 0.0, 0.0)
        assumed.append(f"line {it.assumed['home']}: G28 returned to {tuple(float(v) for v in home_at)} mm in the "
                       "program frame, the machine origin: LinuxCNC's home with its G28 position parameters "
                       "5161-5163 at 0 (give home, [path] home_mm in a config, for your machine's)")
    for what in assumed:
        logging.getLogger(__name__).warning("%s: %s", source, what)
    return GCodeProgram(poly, feeds, rap, lines, source, tuple(it.no_motion), blocks, b_feeds, b_rapid,
                        b_lines, b_tols, seg_block, pauses, end_line, unread, tuple(assumed))


def read_gcode(path: str | PathLike, **kwargs) -> GCodeProgram:
    """Read a G-code file (UTF-8, undecodable bytes replaced) with :func:`parse_gcode`.

    Args:
        path: file to read; its path string becomes ``source`` in messages and the result.
        **kwargs: as :func:`parse_gcode` (``chord_tolerance`` [mm], ``rapid_feed`` [mm/min],
            ``initial_feed`` [mm/min], ``start`` [mm], ``arc_radius_tolerance`` [mm],
            ``arc_relative_tolerance``, ``home`` [mm], ``machine_origin`` [mm], ``block_delete``).

    Raises:
        GCodeError: the file cannot be read (line 0), or as :func:`parse_gcode`.

    Example:
        >>> import pathlib, tempfile
        >>> f = pathlib.Path(tempfile.mkdtemp()) / "part.nc"
        >>> _ = f.write_text("G21 G90\\nG1 X5 F300\\n")
        >>> read_gcode(f).polyline.points[-1].tolist()
        [5.0, 0.0, 0.0]
    """
    name = fspath(path)
    name = name.decode(errors="replace") if isinstance(name, bytes) else name
    try:
        with open(path, encoding="utf-8", errors="replace", newline="") as fh:
            text = fh.read()
    except OSError as e:
        raise GCodeError(f"cannot read the file: {e.strerror or e}; expected a readable G-code file",
                         source=name, line=0, column=0) from e
    return parse_gcode(text, source=name, **kwargs)
