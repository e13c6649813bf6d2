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

import math
import re
from dataclasses import dataclass
from os import PathLike, fspath

import numpy as np

from research.errors import GCodeError, ParameterError, PathError
from research.paths.polyline import Polyline

__all__ = ["GCodeProgram", "parse_gcode", "read_gcode", "to_gcode"]

MM_PER_INCH = 25.4
#: Moves shorter than this [mm] (from the last emitted vertex) produce no segment and are recorded
#: in ``GCodeProgram.no_motion_lines``.
ZERO_LENGTH_MM = 1e-9
#: Largest angle one arc chord may span [rad], whatever ``chord_tolerance`` allows.
MAX_CHORD_ANGLE = 0.5 * math.pi
#: An arc needing more chords than this is refused (the tolerance is unreasonably small for it).
MAX_CHORDS_PER_ARC = 1_000_000

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

# key = round(10 * code): G1 -> 10, G90.1 -> 901
_MOTION = {0: 0, 10: 1, 20: 2, 30: 3, 800: None}
_G_ACCEPT = {
    **{k: "motion" for k in _MOTION},
    170: "plane",
    200: "units", 210: "units",
    900: "distance", 910: "distance",
    901: "arc_distance", 911: "arc_distance",
    400: "cutter_comp",
    490: "tool_length",
    **{k: "work_offset" for k in (540, 550, 560, 570, 580, 590)},
    610: "path_mode", 611: "path_mode", 640: "path_mode",
    940: "feed_mode",
}
_G_REFUSE = {
    40: "G4 (dwell) is not supported: the program model has no pauses",
    180: "G18 (XZ plane) is not supported: arcs only in the G17 (XY) plane",
    190: "G19 (YZ plane) is not supported: arcs only in the G17 (XY) plane",
    280: "G28 (return to home) is not supported: the machine home position is unknown",
    300: "G30 (return to secondary home) is not supported",
    410: "G41 (cutter compensation left) is not supported: post-process with compensation off (G40)",
    420: "G42 (cutter compensation right) is not supported: post-process with compensation off (G40)",
    430: "G43 (tool length offset) is not supported: only G49 (offset off) is accepted",
    530: "G53 (machine coordinates) is not supported",
    730: "canned cycle G73 is not supported: expand the cycle into G0/G1 moves",
    760: "canned cycle G76 is not supported: expand the cycle into G0/G1 moves",
    **{10 * c: f"canned cycle G{c} is not supported: expand the cycle into G0/G1 moves" for c in range(81, 90)},
    920: "G92 (coordinate system offset) is not supported",
    930: "G93 (inverse-time feed) is not supported: only G94 (feed per minute)",
    950: "G95 (feed per revolution) is not supported: only G94 (feed per minute)",
}
_M_ACCEPT = {2: "end", 30: "end", 3: "spindle", 4: "spindle", 5: "spindle", 6: "tool_change",
             7: "coolant", 8: "coolant", 9: "coolant"}
_LETTER_REFUSE = {
    **{c: f"{c} (extra axis) is not supported: only X, Y, Z" for c in "ABCUVW"},
    "K": "K (Z centre offset) is only used in the G18/G19 planes, which are not supported",
    "D": "D (cutter radius offset) is not supported: G41/G42 are refused",
    "H": "H (tool length offset) is not supported: G43 is refused",
    "P": "P (dwell / cycle parameter) is not supported: G4, G64 P and canned cycles are refused",
    "Q": "Q (cycle parameter) is not supported: canned cycles are refused",
    "L": "L (repeat count / G10 parameter) is not supported",
}
_ACCEPTED_LETTERS = frozenset("GMNOFSTXYZIJR")
_ACCEPTED_G_TEXT = "G0 G1 G2 G3 G80 G17 G20 G21 G40 G49 G54-G59 G61 G61.1 G64 G90 G91 G90.1 G91.1 G94"
_ACCEPTED_M_TEXT = "M2 M3 M4 M5 M6 M7 M8 M9 M30"


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


class _LineError(Exception):
    """Raised inside the interpreter; carries the index of the offending word on its line."""

    def __init__(self, message: str, word: int = 0):
        super().__init__(message)
        self.message, self.word = message, word


def _check_positive(name: str, value) -> float:
    v = float(value)
    if not (math.isfinite(v) and v > 0):
        raise ParameterError(f"parse_gcode: {name} must be a finite number > 0, got {value!r}")
    return v


class _Interpreter:
    """Modal state machine; ``line(words, lineno)`` executes one block."""

    def __init__(self, chord_tolerance, rapid_feed_mm_s, initial_feed_mm_s, start, arc_radius_tolerance):
        self.tol = chord_tolerance
        self.arc_tol = arc_radius_tolerance
        self.rapid_feed = rapid_feed_mm_s
        self.feed = initial_feed_mm_s  # mm/s or None
        self.pos = list(start)  # commanded position [mm]
        self.last = tuple(start)  # last emitted vertex [mm]
        self.scale = 1.0  # mm per program unit
        self.absolute = True
        self.arc_absolute = False
        self.motion = None  # 0, 1, 2, 3 or None
        self.ended = 0  # line of M2/M30, 0 while running
        # output
        self.points = [tuple(start)]
        self.feeds: list[float] = []
        self.rapid: list[bool] = []
        self.lines: list[int] = []
        self.no_motion: list[int] = []
        self._keys: dict[str, int | None] = {}  # G-code number text -> _code_key

    # -- one block ---------------------------------------------------------------------------
    def line(self, words, lineno):
        gs = []
        ms = []
        vals = {}
        refused = None
        for k, (letter, num) in enumerate(words):
            if letter.islower():
                letter = letter.upper()
            if letter == "G":
                gs.append((num, k))
            elif letter == "M":
                ms.append((num, k))
            elif letter in _ACCEPTED_LETTERS:
                if letter in vals:
                    raise _LineError(f"{letter} given twice on one line (first at word {vals[letter][1] + 1}); "
                                     f"expected each letter at most once", k)
                vals[letter] = (num, k)
            elif refused is None:  # reported after the G-codes: "G4 P1" names G4, not P
                refused = _LineError(_LETTER_REFUSE[letter], k) if letter in _LETTER_REFUSE else _LineError(
                    f"unknown word letter {letter!r}; expected one of G M N O F S T X Y Z I J R", k)

        # G codes, at most one per modal group
        groups = {}
        motion_word = None
        keys = self._keys
        for num, k in gs:
            key = keys.get(num, -1)
            if key == -1:
                key = keys[num] = _code_key(num)
            kind = _G_ACCEPT.get(key) if key is not None else None
            if kind is None:
                if key in _G_REFUSE:
                    raise _LineError(_G_REFUSE[key], k)
                raise _LineError(f"unsupported G-code G{num}; expected one of {_ACCEPTED_G_TEXT}", k)
            if kind in groups:
                other = groups[kind][0]
                what = "two motion G-codes" if kind == "motion" else f"two G-codes of the {kind.replace('_', ' ')} group"
                raise _LineError(f"{what} on one line (G{_fmt_key(other)} and G{num}); expected at most one", k)
            groups[kind] = (key, k)
            if kind == "motion":
                motion_word = k
        if refused is not None:
            raise refused
        m_end = False
        m_groups = {}
        for num, k in ms:
            key = _code_key(num)
            kind = _M_ACCEPT.get(key // 10) if key is not None and key % 10 == 0 else None
            if kind is None:
                raise _LineError(f"unsupported M-code M{num}; expected one of {_ACCEPTED_M_TEXT}", k)
            if kind in m_groups:
                raise _LineError(f"two {kind.replace('_', ' ')} M-codes on one line; expected at most one", k)
            m_groups[kind] = k
            m_end = m_end or kind == "end"

        if vals:
            for letter in "NT":
                if letter in vals:
                    num, k = vals[letter]
                    v = float(num)
                    if not (v >= 0 and v == int(v) and "." not in num):
                        raise _LineError(f"{letter}{num}: expected a non-negative integer", k)
            if "O" in vals:
                num, k = vals["O"]
                if "." in num or float(num) < 0:
                    raise _LineError(f"O{num}: expected a non-negative integer program number", k)
            if "S" in vals:
                num, k = vals["S"]
                if float(num) < 0:
                    raise _LineError(f"S{num}: expected a spindle speed >= 0", k)

        # modes, in RS274/NGC order: units, then feed, then distance modes, then motion
        if "units" in groups:
            self.scale = MM_PER_INCH if groups["units"][0] == 200 else 1.0
        if "F" in vals:
            num, k = vals["F"]
            f = float(num)
            if not f > 0:
                raise _LineError(f"F{num}: expected a feed > 0 (per minute)", k)
            self.feed = f * self.scale / 60.0
        if "distance" in groups:
            self.absolute = groups["distance"][0] == 900
        if "arc_distance" in groups:
            self.arc_absolute = groups["arc_distance"][0] == 901
        if "motion" in groups:
            self.motion = _MOTION[groups["motion"][0]]

        if not _AXIS_LETTERS.isdisjoint(vals):
            if self.ended:
                raise _LineError(f"motion after the program end (M2/M30 on line {self.ended}); "
                                 "expected no axis words after it", _first_axis(vals))
            if "motion" in groups and groups["motion"][0] == 800:
                raise _LineError("axis words with G80 (motion cancelled); expected G0/G1/G2/G3", _first_axis(vals))
            if self.motion is None:
                raise _LineError("axis words but no motion mode in effect; expected G0, G1, G2 or G3 first",
                                 _first_axis(vals))
            if self.motion < 2:
                if not _ARC_LETTERS.isdisjoint(vals):
                    letter = min(_ARC_LETTERS.intersection(vals), key=lambda c: vals[c][1])
                    raise _LineError(f"{letter} is only used with G2/G3 arcs but the motion mode is G{self.motion}; "
                                     "expected G2 or G3 on this line or before it",
                                     vals[letter][1])
                self._linear(vals, lineno, motion_word)
            else:
                self._arc(vals, lineno, motion_word)
        if m_end:
            self.ended = lineno

    # -- motion ------------------------------------------------------------------------------
    def _target(self, vals):
        s = self.scale
        t = list(self.pos)
        for i, letter in enumerate("XYZ"):
            if letter in vals:
                num, k = vals[letter]
                v = float(num) * s
                t[i] = v if self.absolute else t[i] + v
                if not math.isfinite(t[i]):
                    raise _LineError(f"{letter}{num[:20]}: expected a finite coordinate", k)
        return t

    def _feed_for(self, rapid, vals, motion_word):
        if rapid:
            return self.rapid_feed
        if self.feed is None:
            raise _LineError(f"G{self.motion} motion before any F word (and no initial_feed given); "
                             "expected an F word (feed per minute) on this or an earlier line",
                             _first_axis(vals) if motion_word is None else motion_word)
        return self.feed

    def _linear(self, vals, lineno, where):
        target = self._target(vals)
        rapid = self.motion == 0
        feed = self._feed_for(rapid, vals, where)
        self.pos = target
        last = self.last
        dx, dy, dz = target[0] - last[0], target[1] - last[1], target[2] - last[2]
        if dx * dx + dy * dy + dz * dz <= ZERO_LENGTH_MM * ZERO_LENGTH_MM:
            self.no_motion.append(lineno)
            return
        t = (target[0], target[1], target[2])
        self.points.append(t)
        self.last = t
        self.feeds.append(feed)
        self.rapid.append(rapid)
        self.lines.append(lineno)

    def _arc(self, vals, lineno, motion_word):
        where = _first_axis(vals) if motion_word is None else motion_word
        cw = self.motion == 2
        name = "G2" if cw else "G3"
        has_ij = "I" in vals or "J" in vals
        if has_ij and "R" in vals:
            raise _LineError(f"{name} with both I/J and R; expected either the centre (I, J) or the radius R",
                             vals["R"][1])
        if not has_ij and "R" not in vals:
            raise _LineError(f"{name} without I/J or R; expected the arc centre (I, J) or radius (R)", where)
        feed = self._feed_for(False, vals, where)
        s = self.scale
        sx, sy, sz = self.pos
        ex, ey, ez = self._target(vals)
        chord = math.hypot(ex - sx, ey - sy)
        if has_ij:
            ij_word = vals["I"][1] if "I" in vals else vals["J"][1]
            if self.arc_absolute and not ("I" in vals and "J" in vals):
                raise _LineError(f"{name} under G90.1 (absolute arc centre) without both I and J; expected both "
                                 "centre coordinates I and J", ij_word)
            i = float(vals["I"][0]) * s if "I" in vals else 0.0
            j = float(vals["J"][0]) * s if "J" in vals else 0.0
            cx, cy = (i, j) if self.arc_absolute else (sx + i, sy + j)
            if not (math.isfinite(cx) and math.isfinite(cy)):
                raise _LineError(f"{name} centre is not finite; expected finite I and J", ij_word)
            r0 = math.hypot(sx - cx, sy - cy)
            r1 = math.hypot(ex - cx, ey - cy)
            if r0 <= ZERO_LENGTH_MM:
                raise _LineError(f"{name} centre coincides with the start point (radius 0); expected I/J "
                                 "pointing from the start to the centre", ij_word)
            allowed = max(self.arc_tol, 1e-6 * r0)
            if abs(r1 - r0) > allowed:
                raise _LineError(
                    f"{name} end point is not on the arc: start radius {r0:.6g} mm, end radius {r1:.6g} mm "
                    f"differ by {abs(r1 - r0):.3g} mm > {allowed:.3g} mm; expected consistent X/Y and I/J", ij_word)
            full = chord <= ZERO_LENGTH_MM
        else:
            rnum, rk = vals["R"]
            r = float(rnum) * s
            if not math.isfinite(r):
                raise _LineError(f"{name} R{rnum[:20]}: expected a finite radius", rk)
            if chord <= ZERO_LENGTH_MM:
                raise _LineError(f"{name} with R and end point == start point (in XY) is undefined; "
                                 "expected I/J for a full circle", rk)
            if abs(r) <= ZERO_LENGTH_MM:
                raise _LineError(f"{name} R{rnum}: expected a non-zero radius", rk)
            half = 0.5 * chord
            allowed = max(self.arc_tol, 1e-6 * abs(r))
            if half > abs(r) + allowed:
                raise _LineError(f"{name} R{rnum}: radius {abs(r):.6g} mm is smaller than half the chord "
                                 f"{half:.6g} mm; expected |R| >= half the distance start-end", rk)
            h = math.sqrt(max(r * r - half * half, 0.0))
            ux, uy = (ex - sx) / chord, (ey - sy) / chord
            # centre left of the chord for a CCW arc <= 180 deg, right for CW; R < 0 flips it
            side = (1.0 if not cw else -1.0) * (1.0 if r > 0 else -1.0)
            cx = 0.5 * (sx + ex) - side * h * uy
            cy = 0.5 * (sy + ey) + side * h * ux
            r0 = math.hypot(sx - cx, sy - cy)
            r1 = math.hypot(ex - cx, ey - cy)
            full = False
        a0 = math.atan2(sy - cy, sx - cx)
        a1 = math.atan2(ey - cy, ex - cx)
        two_pi = 2.0 * math.pi
        if full:
            sweep = two_pi
        else:
            sweep = (a0 - a1) % two_pi if cw else (a1 - a0) % two_pi
            if sweep <= 0.0:  # same ray, radii within tolerance: treat as a full turn
                sweep = two_pi
        # sagitta r (1 - cos(dtheta / 2)) <= tol  <=>  dtheta <= 2 acos(1 - tol / r) = 4 asin(sqrt(tol / (2 r)))
        rmax = max(r0, r1)
        dmax = 4.0 * math.asin(math.sqrt(min(self.tol / (2.0 * rmax), 1.0)))
        dmax = min(dmax, MAX_CHORD_ANGLE)
        n = max(1, math.ceil(sweep / dmax)) if dmax > 0.0 else math.inf
        if n > MAX_CHORDS_PER_ARC:
            raise _LineError(f"{name} of radius {rmax:.6g} mm would need {n} chords at chord_tolerance "
                             f"{self.tol:g} mm (limit {MAX_CHORDS_PER_ARC}); expected a larger chord_tolerance", where)
        k = np.arange(1, n + 1, dtype=np.float64) / n
        ang = a0 + (-sweep if cw else sweep) * k
        rad = r0 + (r1 - r0) * k
        pts = np.empty((n, 3))
        pts[:, 0] = cx + rad * np.cos(ang)
        pts[:, 1] = cy + rad * np.sin(ang)
        pts[:, 2] = sz + (ez - sz) * k
        pts[-1] = (ex, ey, ez)
        self.pos = [ex, ey, ez]
        seg = np.diff(np.vstack([self.last, pts]), axis=0)
        short = np.einsum("ij,ij->i", seg, seg) <= ZERO_LENGTH_MM * ZERO_LENGTH_MM
        if short.any():  # tiny arcs only: merge chords shorter than ZERO_LENGTH_MM
            keep, prev = [], np.asarray(self.last)
            for p in pts:
                if np.sum((p - prev) ** 2) > ZERO_LENGTH_MM * ZERO_LENGTH_MM:
                    keep.append(p)
                    prev = p
            if keep and (keep[-1] != pts[-1]).any():
                keep[-1] = pts[-1]
            pts = np.asarray(keep).reshape(-1, 3)
            if len(pts) == 0:
                self.no_motion.append(lineno)
                return
        self.points.extend(map(tuple, pts.tolist()))
        self.last = tuple(pts[-1].tolist())
        n = len(pts)
        self.feeds.extend([feed] * n)
        self.rapid.extend([False] * n)
        self.lines.extend([lineno] * n)


_AXIS_LETTERS = frozenset("XYZIJR")
_ARC_LETTERS = frozenset("IJR")


def _first_axis(vals) -> int:
    """Word index of the first axis word of a block."""
    return min(vals[c][1] for c in _AXIS_LETTERS.intersection(vals))


def _code_key(num: str):
    """round(10 * code) for codes with at most one decimal (G1, G01, G90.1), else None."""
    v = float(num) * 10.0
    key = round(v)
    return key if abs(v - key) < 1e-6 and key >= 0 else None


def _fmt_key(key: int) -> str:
    return str(key // 10) if key % 10 == 0 else f"{key // 10}.{key % 10}"


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


def _num(v: float) -> str:
    """Shortest decimal (no exponent) that reads back as exactly ``v``."""
    return np.format_float_positional(v, unique=True, trim="-")


def to_gcode(polyline, feeds_mm_per_min, rapid=None, *, line_numbers: bool = False) -> str:
    """Write a polyline as a G21/G90 program of ``G1`` (and ``G0``) lines, one segment per line.

    Coordinates are written with the shortest decimal that reads back as the same float, so
    ``parse_gcode(text, start=P0)`` returns exactly the same vertices (``P0`` = first vertex padded
    to 3-D; the program itself does not move to ``P0``, its header comment states it). Only axes
    that change are written; ``F`` only when the feed changes; ``G0``/``G1`` only when the motion
    mode changes.

    Args:
        polyline: :class:`Polyline` (or ``(M + 1, d)`` points) [mm]; axes named ``x``, ``y``, ``z``.
        feeds_mm_per_min: feed [mm/min], a scalar or one per segment ``(M,)``; ignored for rapid
            segments. Note :attr:`GCodeProgram.feeds` is mm/s: pass ``prog.feeds * 60``.
        rapid: ``(M,)`` bool, True writes the segment as ``G0``; default all ``G1``.
        line_numbers: prefix lines with ``N10, N20, ...``.

    Returns:
        the program text, ending with ``M30`` and ``%``.

    Raises:
        ParameterError: feeds not finite and > 0 on the G1 segments, wrong shapes, unknown axis names,
            a segment shorter than :data:`ZERO_LENGTH_MM` (it would read back as no motion).

    Example:
        >>> from research.paths.polyline import Polyline
        >>> print(to_gcode(Polyline([[0, 0], [10, 0], [10, 5]]), 600), end="")
        %
        (research.paths.gcode.to_gcode: start X0 Y0 Z0)
        G21 G90 G17 G94
        G1 X10 F600
        Y5
        M30
        %
    """
    poly = polyline if isinstance(polyline, Polyline) else Polyline(np.asarray(polyline, dtype=np.float64))
    m = poly.n_segments
    idx = []
    for a in poly.axes:
        if a.lower() not in ("x", "y", "z"):
            raise ParameterError(f"to_gcode: axis {a!r} cannot be written; expected axes named x, y, z")
        idx.append("xyz".index(a.lower()))
    if len(set(idx)) != len(idx):
        raise ParameterError(f"to_gcode: repeated axis names {poly.axes}")
    pts = np.zeros((m + 1, 3))
    pts[:, idx] = poly.points
    feeds = np.broadcast_to(np.asarray(feeds_mm_per_min, dtype=np.float64), (m,)) \
        if np.ndim(feeds_mm_per_min) == 0 else np.asarray(feeds_mm_per_min, dtype=np.float64)
    if feeds.shape != (m,):
        raise ParameterError(f"to_gcode: feeds_mm_per_min must be a scalar or shape ({m},), got {feeds.shape}")
    rap = np.zeros(m, dtype=bool) if rapid is None else np.asarray(rapid, dtype=bool)
    if rap.shape != (m,):
        raise ParameterError(f"to_gcode: rapid must have shape ({m},), got {rap.shape}")
    cut = feeds[~rap]
    if not np.all(np.isfinite(cut) & (cut > 0)):
        k = int(np.flatnonzero(~rap)[np.flatnonzero(~(np.isfinite(cut) & (cut > 0)))[0]])
        raise ParameterError(f"to_gcode: feed of segment {k} must be finite and > 0 [mm/min], got {feeds[k]}")

    short = np.flatnonzero(np.linalg.norm(np.diff(pts, axis=0), axis=1) <= ZERO_LENGTH_MM)
    if short.size:
        k = int(short[0])
        raise ParameterError(f"to_gcode: segment {k} is shorter than ZERO_LENGTH_MM = {ZERO_LENGTH_MM:g} mm; "
                             "parse_gcode would read it as no motion, so it cannot round-trip")

    p0 = pts[0]
    out = ["%", f"(research.paths.gcode.to_gcode: start X{_num(p0[0])} Y{_num(p0[1])} Z{_num(p0[2])})",
           "G21 G90 G17 G94"]
    mode = None
    feed = None
    prev = p0
    for k in range(m):
        p = pts[k + 1]
        words = []
        g = 0 if rap[k] else 1
        if g != mode:
            words.append(f"G{g}")
            mode = g
        for i, letter in enumerate("XYZ"):
            if p[i] != prev[i]:
                words.append(f"{letter}{_num(p[i])}")
        if g == 1 and feeds[k] != feed:
            feed = feeds[k]
            words.append(f"F{_num(feed)}")
        prev = p
        out.append(" ".join(words))
    out += ["M30", "%"]
    if line_numbers:
        n = 0
        for i, line in enumerate(out):
            if line != "%" and not line.startswith("("):
                n += 10
                out[i] = f"N{n} {line}"
    return "\n".join(out) + "\n"
