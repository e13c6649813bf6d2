"""G-code reader and writer: RS274/NGC-style CAM output to a :class:`Polyline` with per-segment feeds.

The reader turns a program into the straight segments the interpolators work on: ``G0``/``G1``
moves become one segment each, ``G2``/``G3`` arcs (``G17`` plane, ``I``/``J`` centre or ``R``
radius, optionally helical) become chords whose chord error is at most ``chord_tolerance``. All
lengths inside are mm and feeds mm/s; ``F`` words are read as mm/min (in/min under ``G20``).

Tokenizing is one regular expression over the whole text (no per-character Python loop), so
ordinary CAM output with 10^5 short ``G1`` lines is read in well under a second.

Accepted words (anything else is a :class:`~research.errors.GCodeError` naming line and column):

* ``G0 G1 G2 G3`` motion (modal: a line with only coordinates continues the last motion mode),
  ``G80`` (cancel motion mode / canned cycle);
* ``G17`` (XY plane), ``G20``/``G21`` (inch / mm), ``G90``/``G91`` (absolute / incremental
  ``X Y Z``), ``G90.1``/``G91.1`` (absolute / incremental ``I J``; incremental is the default);
* harmless modal codes that do not change the geometry this reader produces: ``G40`` (cutter
  compensation off), ``G49`` (tool length offset off), ``G54``-``G59`` (work offsets: the program
  frame is taken as the work frame), ``G61``, ``G61.1``, ``G64`` (path-control mode without ``P``/``Q``),
  ``G94`` (feed per minute, the only feed mode supported);
* ``M2 M30`` (program end: motion after them is an error), ``M3 M4 M5`` (spindle), ``M6``
  (tool change), ``M7 M8 M9`` (coolant);
* ``N`` (line number, must be a non-negative integer, otherwise ignored), ``O`` (program number,
  ignored), ``S`` (spindle speed >= 0, ignored), ``T`` (tool number, non-negative integer, ignored),
  ``F`` (feed > 0, modal), ``X Y Z I J R``;
* comments ``( ... )`` (not nested, closed on the same line) and ``; ...`` to the end of the line,
  ``%`` delimiter lines, blank lines, upper or lower case, words with or without spaces
  (``G1X10Y5F600``).

Refused with a specific message: ``G18``/``G19`` (arcs only in G17), ``G41``/``G42`` (cutter
compensation), ``G43`` (tool length offset), ``G4`` (dwell: the program model has no pauses),
``G28``/``G30``/``G53``/``G92`` (machine / coordinate-system moves), ``G73``, ``G76``, ``G81``-``G89``
(canned cycles), ``G93``/``G95`` (inverse-time / per-revolution feed), every other G or M code, the
letters ``A B C U V W`` (extra axes), ``K`` (only used in G18/G19), ``D H`` (tool offsets),
``P Q L`` (dwell / cycle parameters), every other letter; two G-codes of one modal group on one
line (e.g. two motion codes), a letter given twice on one line, a malformed number (``X1.2.3``,
``X``), an unclosed or nested ``(``, a stray character (``/`` block delete, ``#`` parameters ...).
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from os import PathLike, fspath

import numpy as np

from research.errors import GCodeError, ParameterError, PathError
from research.paths._gcode_constants import (  # noqa: F401  (public constants)
    MAX_CHORD_ANGLE,
    MAX_CHORDS_PER_ARC,
    MM_PER_INCH,
    ZERO_LENGTH_MM,
)
from research.paths._gcode_interpreter import (
    _check_positive,
    _Interpreter,
    _LineError,
)
from research.paths._gcode_writer import to_gcode
from research.paths.polyline import Polyline

__all__ = ["GCodeProgram", "parse_gcode", "read_gcode", "to_gcode"]

# One token per match. Groups: 1 letter, 2 number (a word), 3 newline, 4 '%', 5 anything illegal.
# Whitespace and well-formed comments match with all groups empty and are skipped. A word whose
# number is followed by another digit or '.' ("X1.2.3") does not match the word branch, so its
# letter falls through to group 5 and is diagnosed there.
_TOKEN = re.compile(
    r"[ \t]*([A-Za-z])[ \t]*([-+]?(?:[0-9]+\.?[0-9]*|\.[0-9]+))(?![0-9.])"
    r"|(\n)"
    r"|[ \t]+|\([^()\n]*\)|;[^\n]*"
    r"|(%)"
    r"|(.)"
)



@dataclass(frozen=True, eq=False)
class GCodeProgram:
    """A G-code program as straight segments with feeds.

    Attributes:
        polyline: ``(M + 1, 3)`` vertices [mm], axes ``x, y, z``; the first vertex is the start
            position, arcs are already broken into chords.
        feeds: ``(M,)`` feed of each segment [mm/s] (``F`` words are mm/min, or in/min under
            ``G20``, converted; ``G0`` segments get ``rapid_feed / 60``).
        rapid: ``(M,)`` bool, True for ``G0`` segments.
        lines: ``(M,)`` 1-based source line of each segment (all chords of an arc share its line).
        source: file name or ``"<string>"``.
        no_motion_lines: 1-based lines whose axis words left the position unchanged (moves shorter
            than :data:`ZERO_LENGTH_MM`); they produce no segment.

    Example:
        >>> prog = parse_gcode("G21 G90\\nG1 X10 F600\\nY5\\nG0 Z2")
        >>> prog.polyline.points.tolist()
        [[0.0, 0.0, 0.0], [10.0, 0.0, 0.0], [10.0, 5.0, 0.0], [10.0, 5.0, 2.0]]
        >>> prog.feeds.tolist(), prog.rapid.tolist(), prog.lines.tolist()
        ([10.0, 10.0, 250.0], [False, False, True], [2, 3, 4])
    """

    polyline: Polyline
    feeds: np.ndarray
    rapid: np.ndarray
    lines: np.ndarray
    source: str = "<string>"
    no_motion_lines: tuple[int, ...] = ()

    def __post_init__(self):
        m = self.polyline.n_segments
        for name, dtype in (("feeds", np.float64), ("rapid", bool), ("lines", np.int64)):
            a = np.array(getattr(self, name), dtype=dtype)
            if a.shape != (m,):
                raise PathError(f"GCodeProgram.{name} must have shape ({m},) (one per segment), got {a.shape}")
            a.setflags(write=False)
            object.__setattr__(self, name, a)
        object.__setattr__(self, "no_motion_lines", tuple(int(i) for i in self.no_motion_lines))

    @property
    def n_segments(self) -> int:
        """Number of segments ``M``."""
        return self.polyline.n_segments

    @property
    def nominal_durations(self) -> np.ndarray:
        """Time of each segment at its programmed feed [s], ``lengths / feeds``, shape ``(M,)``.

        Example:
            >>> parse_gcode("G1 X10 F600").nominal_durations.tolist()
            [1.0]
        """
        return self.polyline.lengths / self.feeds



def _diagnose_bad_char(line_text: str, column: int) -> str:
    """Explain the illegal character at 1-based ``column`` of ``line_text``."""
    c = line_text[column - 1]
    rest = line_text[column:]
    if c.isascii() and c.isalpha():
        m = re.match(r"[ \t]*([-+0-9.]*)", rest)
        got = m.group(1) if m else ""
        return (f"word {c}{got!s} has no valid number: expected a number after {c} like 12, -0.5 or .25"
                if got else f"letter {c!r} is not followed by a number; expected e.g. {c.upper()}10")
    if c == "(":
        if "(" in rest.split(")", 1)[0]:
            return "nested '(' inside a comment; expected comments without parentheses inside"
        return "comment '(' is not closed on this line; expected ')'"
    if c == ")":
        return "')' without an opening '('; expected a comment like (text)"
    return f"unexpected character {c!r}; expected a word (letter and number), a comment or a line end"


def _word_column(line_text: str, word: int) -> int:
    """1-based column of the ``word``-th word (0-based) of a line, as the tokenizer sees it."""
    k = 0
    for m in _TOKEN.finditer(line_text):
        if m.group(1):
            if k == word:
                return m.start(1) + 1
            k += 1
    return 1


def parse_gcode(
    text: str,
    *,
    source: str = "<string>",
    chord_tolerance: float = 1e-3,
    rapid_feed: float = 15000.0,
    initial_feed: float | None = None,
    start=(0.0, 0.0, 0.0),
    arc_radius_tolerance: float = 1e-3,
) -> GCodeProgram:
    """Read a G-code program into straight segments with feeds.

    Args:
        text: the program.
        source: name used in error messages and stored in the result.
        chord_tolerance: largest chord error (sagitta) of the chords replacing an arc [mm]. An arc
            of radius ``r`` is cut into equal chords of angle at most
            ``2 acos(1 - tol / r)`` (computed as ``4 asin(sqrt(tol / (2 r)))``) and at most 90 deg.
        rapid_feed: feed given to ``G0`` segments [mm/min].
        initial_feed: feed in effect before the first ``F`` word [mm/min]; ``None`` makes a
            ``G1``/``G2``/``G3`` before any ``F`` an error.
        start: start position ``(x, y, z)`` [mm] (first vertex of the polyline).
        arc_radius_tolerance: an arc whose start and end radii (from the centre) differ by more than
            ``max(arc_radius_tolerance, 1e-6 r)`` [mm] is an error (with ``R``: ``|R|`` shorter than
            half the chord by more than that). Within it, the radius is blended linearly along the
            arc so the arc ends exactly at the programmed point.

    Semantics worth knowing:

    * Within one line the units word applies first, then ``F``, then ``G90``/``G91``, then motion
      (so ``G20 F10 G1 X1`` is 10 in/min). An ``F`` value is converted to mm/s when it is read; a
      later ``G20``/``G21`` without a new ``F`` keeps that physical feed.
    * ``I``/``J`` are offsets from the arc start (``G91.1``, the default) or absolute centre
      coordinates under ``G90.1``; ``G91`` does not affect them. ``R < 0`` selects the arc > 180 deg.
      ``G2``/``G3`` with ``I``/``J`` and the end equal to the start in XY is a full circle (a helix
      if ``Z`` changes).
    * A move ending within :data:`ZERO_LENGTH_MM` of the last polyline vertex produces no segment;
      its line goes to ``no_motion_lines``. The commanded position still follows the program
      exactly, so the next real move ends where the program says.
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
    arc_tol = _check_positive("arc_radius_tolerance", arc_radius_tolerance)
    rapid = _check_positive("rapid_feed", rapid_feed) / 60.0
    feed0 = None if initial_feed is None else _check_positive("initial_feed", initial_feed) / 60.0
    st = np.asarray(start, dtype=np.float64).reshape(-1)
    if st.shape != (3,) or not np.all(np.isfinite(st)):
        raise ParameterError(f"parse_gcode: start must be 3 finite numbers (x, y, z) [mm], got {start!r}")
    if not isinstance(text, str):
        raise GCodeError(f"expected the program as str, got {type(text).__name__}", source=source, line=0, column=0)
    if "\r" in text:
        text = text.replace("\r\n", "\n").replace("\r", "\n")

    it = _Interpreter(tol, rapid, feed0, tuple(st.tolist()), arc_tol)
    line_fn = it.line
    lineno = 1
    words: list[tuple[str, str]] = []
    pct = False

    def fail(message, word=None, group=None):
        line_text = text.split("\n")[lineno - 1]
        if group is not None:
            column = next(m.start(group) + 1 for m in _TOKEN.finditer(line_text) if m.group(group))
            message = message or _diagnose_bad_char(line_text, column)
        else:
            column = _word_column(line_text, word)
        raise GCodeError(message, source=source, line=lineno, column=column) from None

    def block():
        if pct and words:
            fail("'%' program delimiter must be alone on its line; expected no words with it", group=4)
        if words:
            try:
                line_fn(words, lineno)
            except _LineError as e:
                fail(e.message, e.word)

    for letter, num, nl, percent, bad in _TOKEN.findall(text):
        if letter:
            words.append((letter, num))
        elif nl:
            if words:
                block()
                words = []
            pct = False
            lineno += 1
        elif bad:
            fail("", group=5)
        elif percent:
            pct = True
            if words:
                block()
    if words:
        block()

    if len(it.points) < 2:
        raise GCodeError(
            f"program has no motion ({len(it.no_motion)} line(s) with axis words left the position unchanged); "
            "expected at least one G0/G1/G2/G3 move", source=source, line=lineno, column=1)
    pts = np.asarray(it.points, dtype=np.float64)
    lines = np.asarray(it.lines, dtype=np.int64)
    try:
        poly = Polyline(pts)
    except PathError as e:
        # only for extreme coordinates: Polyline's zero-length test scales with max |coordinate|
        lengths = np.linalg.norm(np.diff(pts, axis=0), axis=1)
        bad = int(np.argmin(lengths)) if np.all(np.isfinite(pts)) else int(np.argwhere(~np.isfinite(pts))[0, 0]) - 1
        raise GCodeError(f"segment from this line is unusable: {e}", source=source,
                         line=int(lines[max(bad, 0)]), column=1) from None
    return GCodeProgram(poly, np.asarray(it.feeds), np.asarray(it.rapid, dtype=bool), lines, source,
                        tuple(it.no_motion))


def read_gcode(path: str | PathLike, **kwargs) -> GCodeProgram:
    """Read a G-code file (UTF-8, undecodable bytes replaced) with :func:`parse_gcode`.

    Args:
        path: file to read; its path string becomes ``source`` in messages and the result.
        **kwargs: as :func:`parse_gcode` (``chord_tolerance`` [mm], ``rapid_feed`` [mm/min],
            ``initial_feed`` [mm/min], ``start`` [mm]).

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
