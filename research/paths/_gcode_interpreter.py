"""The G-code interpreter: modal state, accepted and refused codes, arcs to chords and arc blocks.

Private to :mod:`research.paths.gcode`; see its docstring for the accepted language.
"""

from __future__ import annotations

import math
import re
from array import array

import numpy as np

from research.errors import ParameterError
from research.paths._gcode_constants import (
    CENTER_ARC_RADIUS_TOLERANCE_INCH,
    CENTER_ARC_RADIUS_TOLERANCE_MM,
    MAX_CHORD_ANGLE,
    MAX_ARC_TURNS,
    MAX_CHORDS_PER_ARC,
    MAX_COORDINATE_MM,
    MAX_FEED_MM_PER_MIN,
    MM_PER_INCH,
    RADIUS_TOLERANCE_MM,
    SPIRAL_HARD_LIMIT_FACTOR,
    ZERO_LENGTH_MM,
)

_MAXC = MAX_COORDINATE_MM
_NAN = float("nan")
_MAXF = MAX_FEED_MM_PER_MIN * (1 + 1e-12)  # a feed written back by to_gcode (x 60 / 60) may gain an ulp
_ZERO2 = ZERO_LENGTH_MM * ZERO_LENGTH_MM

# key = 10 * code: G1 -> 10, G90.1 -> 901 (see _code_key)
_MOTION = {0: 0, 10: 1, 20: 2, 30: 3, 800: None}
_G_ACCEPT = {
    **{k: "motion" for k in _MOTION},
    40: "dwell",
    170: "plane", 180: "plane", 190: "plane",
    200: "units", 210: "units",
    900: "distance", 910: "distance",
    901: "arc_distance", 911: "arc_distance",
    400: "cutter_comp",
    430: "tool_length", 490: "tool_length",
    280: "home",
    530: "machine_coordinates",
    **{k: "work_offset" for k in (540, 550, 560, 570, 580, 590)},
    610: "path_mode", 611: "path_mode", 640: "path_mode",
    940: "feed_mode",
    980: "retract_mode", 990: "retract_mode",
}
# plane key -> (first axis, second axis, normal axis) indices into (x, y, z); G3 is counter-clockwise
# from the first towards the second axis, i.e. about +normal axis (RS274/NGC: G17 XY about +Z,
# G18 ZX about +Y, G19 YZ about +X)
_PLANES = {170: (0, 1, 2), 180: (2, 0, 1), 190: (1, 2, 0)}
_PLANE_NAME = {170: "G17 (XY)", 180: "G18 (ZX)", 190: "G19 (YZ)"}
_CUT = "expand the cycle into G0/G1 moves"
_G_REFUSE = {
    50: "G5 (cubic spline) is not supported: only lines and circular arcs",
    51: "G5.1 (quadratic spline) is not supported: only lines and circular arcs",
    52: "G5.2 (NURBS) is not supported: only lines and circular arcs",
    70: "G7 (lathe diameter mode) is not supported",
    80: "G8 (lathe radius mode) is not supported",
    100: "G10 (set offsets / tool table) is not supported",
    171: "G17.1 (UV plane) is not supported: only the G17, G18, G19 planes",
    181: "G18.1 (WU plane) is not supported: only the G17, G18, G19 planes",
    191: "G19.1 (VW plane) is not supported: only the G17, G18, G19 planes",
    300: "G30 (return to secondary home) is not supported",
    700: "G70 (LinuxCNC's lathe finishing cycle; inch units in Mach3 and old Fanuc) is not supported: for inch "
         "units write G20",
    710: "G71 (LinuxCNC's lathe roughing cycle; metric units in Mach3 and old Fanuc) is not supported: for mm "
         "units write G21",
    330: "G33 (spindle-synchronized motion) is not supported",
    410: "G41 (cutter compensation left) is not supported: post-process with compensation off (G40)",
    411: "G41.1 (dynamic cutter compensation left) is not supported: post-process with compensation off (G40)",
    420: "G42 (cutter compensation right) is not supported: post-process with compensation off (G40)",
    421: "G42.1 (dynamic cutter compensation right) is not supported: post-process with compensation off (G40)",
    431: "G43.1 (dynamic tool length compensation) is not supported: only G43 H<n> and G49",
    432: "G43.2 (additional tool length offset) is not supported: only G43 H<n> and G49",
    730: f"canned cycle G73 is not supported: {_CUT}",
    760: f"canned cycle G76 is not supported: {_CUT}",
    **{10 * c: f"canned cycle G{c} is not supported: {_CUT}" for c in range(81, 90)},
    920: "G92 (coordinate system offset) is not supported",
    930: "G93 (inverse-time feed) is not supported: only G94 (feed per minute)",
    950: "G95 (feed per revolution) is not supported: only G94 (feed per minute)",
}
# M0 M1 M2 M30 M60 are one modal group (RS274/NGC "stopping"); M0 M1 M60 pause, M2 M30 end
_M_ACCEPT = {0: "stopping", 1: "stopping", 2: "stopping", 30: "stopping", 60: "stopping", 3: "spindle",
             4: "spindle", 5: "spindle", 6: "tool_change", 7: "coolant", 8: "coolant", 9: "coolant"}
_M_END, _M_PAUSE = {2, 30}, {0, 1, 60}
_M_REFUSE = {
    98: "unsupported M-code M98 (subroutine call); expected plain G-code (expand subroutines in the CAM post-processor)",
    99: "unsupported M-code M99 (subroutine return); expected plain G-code (expand subroutines in the CAM post-processor)",
}
#: extra axes: accepted where they never move (a 4- or 5-axis post writes ``A0.`` on a 3-axis job);
#: U, V, W are linear (program units), A, B, C rotary (degrees)
_EXTRA_AXES = frozenset("ABCUVW")
_LETTER_REFUSE = {
    "D": "D (cutter radius offset) is not supported: cutter compensation G41/G42 is refused",
    "L": "L (repeat count / G10 parameter) is not supported",
}
_ACCEPTED_LETTERS = frozenset("GMNOFSTXYZIJKRPQH")
_ACCEPTED_G_TEXT = ("G0 G1 G2 G3 G4 G80 G17 G18 G19 G20 G21 G28 G40 G43 G49 G53 G54-G59 G61 G61.1 G64 G90 G91 "
                    "G90.1 G91.1 G94 G98 G99")
_ACCEPTED_M_TEXT = "M0 M1 M2 M3 M4 M5 M6 M7 M8 M9 M30 M60"
# code text: optional '+', leading zeros, 1-4 digits, optionally '.' and one digit (trailing zeros ok)
_CODE_TEXT = re.compile(r"\+?0*([0-9]{1,4})(?:\.([0-9]?)0*)?")
_INT_TEXT = re.compile(r"\+?[0-9]{1,15}")


class _LineError(Exception):
    """Raised inside the interpreter; carries the index of the offending word on its line."""

    def __init__(self, message: str, word: int = 0):
        super().__init__(message)
        self.message, self.word = message, word


def _check_positive(name: str, value) -> float:
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise ParameterError(f"parse_gcode: {name} must be a finite number > 0, got {value!r}") from None
    if not (math.isfinite(v) and v > 0):
        raise ParameterError(f"parse_gcode: {name} must be a finite number > 0, got {value!r}")
    return v


def _short(num: str) -> str:
    return num if len(num) <= 24 else f"{num[:12]}...({len(num)} characters)"


def _value(letter: str, num: str, k: int, scale: float = 1.0, bound: float = _MAXC, what: str = "coordinate") -> float:
    """``float(num) * scale``, refused unless finite with ``|value| <= bound`` [mm]."""
    v = float(num) * scale
    if not -bound <= v <= bound:
        raise _LineError(f"{letter}{_short(num)}: expected a finite {what} of at most {bound:g} mm in size", k)
    return v


class _Interpreter:
    """Modal state machine; ``line(words, lineno)`` executes one block, ``simple(...)`` a plain move."""

    def __init__(self, chord_tolerance, rapid_feed_mm_s, initial_feed_mm_s, start, arc_radius_tolerance,
                 arc_relative_tolerance, home=None, machine_origin=None):
        self.tol = chord_tolerance
        # G53's frame origin and G28's target (x, y, z) [mm, program frame]; None: LinuxCNC's defaults
        # (work offset 0: the origin at the program's; G28 position parameters 5161-5163 = 0: home at
        # the machine origin), each noted in ``assumed`` with the first line that used it
        self.home = home
        self.machine_origin = machine_origin
        self.assumed: dict[str, int] = {}
        self.arc_tol = arc_radius_tolerance  # mm, or None: LinuxCNC's (unit dependent)
        self.arc_rel = arc_relative_tolerance
        self.rapid_feed = rapid_feed_mm_s
        self.feed = initial_feed_mm_s  # mm/s or None
        self.pos = tuple(start)  # commanded position [mm]
        self.last = tuple(start)  # last emitted vertex [mm]
        self.scale = 1.0  # mm per program unit
        self.absolute = True
        self.arc_absolute = False
        self.plane = 170
        self.path_tol = _NAN  # G64 P tolerance [mm] in force (NaN: none given, 0 under G61/G61.1)
        self.motion = None  # 0, 1, 2, 3 or None
        self.extra: dict[str, float] = {}  # where each extra axis was put (it never moves) [deg or mm]
        self.ended = 0  # line of M2/M30, 0 while running (the reader stops after that line)
        # output: the vertices (flat x, y, z), one (feed, rapid, line, tolerance) row and one chord count
        # per block
        self.points = array("d", start)
        self.meta: list[tuple] = []
        self.counts = array("q")
        self.nblocks = 0
        self.arcs: list[tuple] = []  # (block, centre (3,), normal (3,), sweep)
        self.no_motion: list[int] = []
        self.pauses: dict[int, float] = {}  # vertex (blocks emitted before it) -> dwell [s]
        self._keys: dict[str, int | None] = {}  # code number text -> _code_key

    # -- a plain G0/G1 line (fast path) -------------------------------------------------------
    def simple(self, g, x, y, z, f, lineno) -> bool:
        """Execute ``[N] [G0|G1] [X] [Y] [Z] [F]`` (already matched as text); False: let ``line`` do it
        (anything unusual, including every error, goes through the general path)."""
        motion = self.motion if g is None else (1 if g == "1" else 0)
        if f is not None:
            fv = float(f) * self.scale
            if not 0.0 < fv <= _MAXF:
                return False
        if x is None and y is None and z is None:
            if g is not None:
                self.motion = motion
            if f is not None:
                self.feed = fv / 60.0
            return True
        if motion is None or motion > 1:
            return False
        s = self.scale
        px, py, pz = self.pos
        if self.absolute:
            if x is not None:
                px = float(x) * s
            if y is not None:
                py = float(y) * s
            if z is not None:
                pz = float(z) * s
        else:
            if x is not None:
                px += float(x) * s
            if y is not None:
                py += float(y) * s
            if z is not None:
                pz += float(z) * s
        if not (-_MAXC <= px <= _MAXC and -_MAXC <= py <= _MAXC and -_MAXC <= pz <= _MAXC):
            return False
        if motion == 1 and f is None and self.feed is None:
            return False
        self.motion = motion
        if f is not None:
            self.feed = fv / 60.0
        t = self.pos = (px, py, pz)
        lx, ly, lz = self.last
        dx, dy, dz = px - lx, py - ly, pz - lz
        if dx * dx + dy * dy + dz * dz <= _ZERO2:
            self.no_motion.append(lineno)
            return True
        self.points.extend(t)
        self.last = t
        self.meta.append((self.feed if motion else self.rapid_feed, motion == 0, lineno, self.path_tol))
        self.counts.append(1)
        self.nblocks += 1
        return True

    def _extra_axis(self, letter, num, k):
        """An A, B, C, U, V or W word: accepted where the axis stays where it was first put (only X,
        Y and Z are planned). The first word of an axis positions it, under G90 on a rapid or a line
        without motion; later words must repeat that position (under G91: move it by 0)."""
        v = float(num) * (self.scale if letter in "UVW" else 1.0)
        if not math.isfinite(v):
            raise _LineError(f"{letter}{_short(num)}: expected a finite axis position", k)
        unit = "mm" if letter in "UVW" else "deg"
        held = self.extra.get(letter)
        if not self.absolute:
            if v != 0.0:
                raise _LineError(f"{letter}{_short(num)} under G91 moves the {letter} axis; only X, Y, Z move here "
                                 f"(expected {letter}0 or no {letter} word)", k)
            return
        if held is None:
            if self.motion not in (None, 0):
                raise _LineError(f"{letter}{_short(num)} first given on a G{self.motion} feed move: the {letter} axis "
                                 f"would move while cutting; only X, Y, Z move here (expected it put in place by a "
                                 f"G0 or a line without motion, and kept)", k)
            self.extra[letter] = v
        elif v != held:
            raise _LineError(f"{letter}{_short(num)} moves the {letter} axis from {held:g} to {v:g} {unit}; only X, "
                             f"Y, Z move here (expected {letter} to stay where it was first put)", k)

    # -- one block ---------------------------------------------------------------------------
    def line(self, words, lineno):
        gs = []
        ms = []
        vals = {}
        refused = None
        extra = []
        for k, (letter, num) in enumerate(words):
            if letter.islower():
                letter = letter.upper()
            if letter == "G":
                gs.append((num, k))
            elif letter == "M":
                ms.append((num, k))
            elif letter in _EXTRA_AXES:
                if any(e[0] == letter for e in extra):
                    raise _LineError(f"{letter} given twice on one line; expected each letter at most once", k)
                extra.append((letter, num, k))
            elif letter in _ACCEPTED_LETTERS:
                if letter in vals:
                    raise _LineError(f"{letter} given twice on one line (first at word {vals[letter][1] + 1}); "
                                     f"expected each letter at most once", k)
                vals[letter] = (num, k)
            elif refused is None:  # reported after the G-codes: "G41 D1" names G41, not D
                refused = _LineError(_LETTER_REFUSE[letter], k) if letter in _LETTER_REFUSE else _LineError(
                    f"unknown word letter {letter!r}; expected one of G M N O F S T X Y Z I J K R P Q H", k)

        # G codes, at most one per modal group; G80 with a motion code: the motion code wins (LinuxCNC)
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
                raise _LineError(f"unsupported G-code G{_short(num)}; expected one of {_ACCEPTED_G_TEXT}", k)
            if kind in groups:
                other = groups[kind][0]
                if kind == "motion" and 800 in (key, other) and key != other:
                    if key == 800:
                        continue
                else:
                    what = "two motion G-codes" if kind == "motion" else \
                        f"two G-codes of the {kind.replace('_', ' ')} group"
                    raise _LineError(f"{what} on one line (G{_fmt_key(other)} and G{num}); expected at most one", k)
            groups[kind] = (key, k)
            if kind == "motion":
                motion_word = k
        if refused is not None:
            raise refused
        m_end = m_pause = False
        m_groups = {}
        for num, k in ms:
            key = _code_key(num)
            kind = _M_ACCEPT.get(key // 10) if key is not None and key % 10 == 0 else None
            if kind is None:
                if key is not None and key % 10 == 0 and key // 10 in _M_REFUSE:
                    raise _LineError(_M_REFUSE[key // 10], k)
                raise _LineError(f"unsupported M-code M{_short(num)}; expected one of {_ACCEPTED_M_TEXT}", k)
            if kind in m_groups:
                raise _LineError(f"two {kind.replace('_', ' ')} M-codes on one line; expected at most one", k)
            m_groups[kind] = k
            m_end, m_pause = m_end or key // 10 in _M_END, m_pause or key // 10 in _M_PAUSE

        if vals:
            for letter, what in (("N", "line number"), ("T", "tool number"), ("O", "program number"),
                                 ("H", "tool length offset number")):
                if letter in vals:
                    num, k = vals[letter]
                    if not _INT_TEXT.fullmatch(num):
                        raise _LineError(f"{letter}{_short(num)}: expected a non-negative integer {what} "
                                         "(at most 15 digits)", k)
            if "S" in vals:
                num, k = vals["S"]
                v = float(num)
                if not 0.0 <= v < math.inf:
                    raise _LineError(f"S{_short(num)}: expected a finite spindle speed >= 0", k)

        if "H" in vals and groups.get("tool_length", (None,))[0] != 430:
            raise _LineError("H word with no G43 to use it; expected H (tool length offset number) only with G43",
                             vals["H"][1])

        # modes, in RS274/NGC order: units, feed, path control, distance modes, plane, motion
        if "units" in groups:
            self.scale = MM_PER_INCH if groups["units"][0] == 200 else 1.0
        if "F" in vals:
            num, k = vals["F"]
            f = float(num) * self.scale
            if not 0.0 < f <= _MAXF:
                raise _LineError(f"F{_short(num)}: expected a feed > 0 (per minute) of at most "
                                 f"{MAX_FEED_MM_PER_MIN:g} mm/min", k)
            self.feed = f / 60.0
        g64 = "path_mode" in groups and groups["path_mode"][0] == 640
        if "Q" in vals:
            num, k = vals["Q"]
            if not g64:
                raise _LineError("Q word with no G64 to use it: Q (naive-CAM tolerance) is only read with G64 "
                                 "(canned cycles and other Q uses are not supported)", k)
            _value("Q", num, k, self.scale, what="tolerance")
            if float(num) < 0:
                raise _LineError(f"G64 Q{_short(num)}: expected a tolerance >= 0", k)
        if "path_mode" in groups:
            key = groups["path_mode"][0]
            if key != 640:
                self.path_tol = 0.0
            elif "P" in vals:
                num, k = vals["P"]
                p = _value("P", num, k, self.scale, what="tolerance")
                if p < 0:
                    raise _LineError(f"G64 P{_short(num)}: expected a blend tolerance >= 0", k)
                # P0 is no tolerance, as a bare G64 (LinuxCNC's tcFindBlendTolerance: "Detect zero
                # tolerance = no tolerance"), not the exact path of G61
                self.path_tol = p if p > 0 else _NAN
            else:
                self.path_tol = _NAN
        if "distance" in groups:
            self.absolute = groups["distance"][0] == 900
        if "arc_distance" in groups:
            self.arc_absolute = groups["arc_distance"][0] == 901
        if "plane" in groups:
            self.plane = groups["plane"][0]
        if "motion" in groups:
            self.motion = _MOTION[groups["motion"][0]]
        for letter, num, k in extra:
            self._extra_axis(letter, num, k)

        if "machine_coordinates" in groups:  # RS274/NGC modal group 0: G4, G28, G53 (G92, G10 refused)
            other = next((kind for kind in ("home", "dwell") if kind in groups), None)
            if other is not None:
                raise _LineError(f"G53 and G{_fmt_key(groups[other][0])} on one line; expected at most one of G4, "
                                 "G28, G53 per line (RS274/NGC modal group 0)", groups["machine_coordinates"][1])
        if "dwell" in groups:
            self._dwell(vals, groups, g64)
        if "home" in groups:
            self._home(vals, lineno, groups)
            vals = {k: v for k, v in vals.items() if k not in "XYZ"}  # G28's axis words are its own
        if "machine_coordinates" in groups:
            self._machine(vals, lineno, groups, motion_word)
            vals = {k: v for k, v in vals.items() if k not in "XYZ"}  # G53's axis words are its own
        moves = not _AXIS_LETTERS.isdisjoint(vals)
        if "P" in vals and not g64 and "dwell" not in groups and not (moves and self.motion in (2, 3)):
            raise _LineError("P word with no G2/G3, G4 or G64 to use it; expected P only as G64 P<tolerance>, "
                             "G4 P<seconds> or G2/G3 P<turns> (canned cycles are not supported)", vals["P"][1])
        if moves:
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
                if (g64 or "dwell" in groups) and "P" in vals:
                    what = "G64 (tolerance)" if g64 else "G4 (dwell)"
                    raise _LineError(f"P used by both {what} and G2/G3 (turns) on one line; expected "
                                     f"{what.split()[0]} P on a line of its own", vals["P"][1])
                self._arc(vals, lineno, motion_word)
        if m_pause:  # after the line's motion (RS274/NGC order of execution: stopping codes last)
            self.pauses[self.nblocks] = self.pauses.get(self.nblocks, 0.0)
        if m_end:
            self.ended = lineno

    def _dwell(self, vals, groups, g64):
        """``G4 P<seconds>`` (LinuxCNC: P in seconds, any units mode): the motion stops at the current
        vertex and waits; several dwells at one vertex add up."""
        k = groups["dwell"][1]
        if "P" not in vals:
            raise _LineError("G4 (dwell) without P; expected G4 P<seconds>", k)
        if g64:
            raise _LineError("P used by both G64 (tolerance) and G4 (dwell) on one line; expected G64 P on a "
                             "line of its own", vals["P"][1])
        num, kp = vals["P"]
        p = float(num)
        if not 0.0 <= p < math.inf:
            raise _LineError(f"G4 P{_short(num)}: expected a finite dwell >= 0 s (P is in seconds, as in LinuxCNC)", kp)
        self.pauses[self.nblocks] = self.pauses.get(self.nblocks, 0.0) + p

    # -- motion ------------------------------------------------------------------------------
    def _home(self, vals, lineno, groups):
        """``G28 [X] [Y] [Z]`` (LinuxCNC): a rapid to the point of the axis words (G90/G91 as usual),
        then a rapid of those axes (of every axis when none is given) to ``home``; other axes stay."""
        k = groups["home"][1]
        if "motion" in groups and not _AXIS_LETTERS.isdisjoint(vals):
            raise _LineError(f"G28 and G{_fmt_key(groups['motion'][0])} on one line with axis words; expected "
                             "the motion code on a line of its own (both would use the axis words)", k)
        if not _ARC_LETTERS.isdisjoint(vals):
            letter = min(_ARC_LETTERS.intersection(vals), key=lambda c: vals[c][1])
            raise _LineError(f"{letter} with G28; expected only X, Y, Z (the intermediate point)", vals[letter][1])
        named = [i for i, letter in enumerate("XYZ") if letter in vals]
        via = self._target(vals)
        self._move(via, self.rapid_feed, True, lineno)
        home = self.home
        if home is None:  # LinuxCNC's G28 position parameters left at 0: the machine origin
            self.assumed.setdefault("home", lineno)
            home = self._origin(lineno)
        self._move([home[i] if (i in named or not named) else via[i] for i in range(3)], self.rapid_feed, True, lineno)

    def _origin(self, lineno):
        """The machine origin [mm, program frame]: ``machine_origin``, or LinuxCNC's work offset of 0
        (the program's origin), noted in ``assumed``."""
        if self.machine_origin is not None:
            return self.machine_origin
        self.assumed.setdefault("machine_origin", lineno)
        return (0.0, 0.0, 0.0)

    def _machine(self, vals, lineno, groups, motion_word):
        """``G53 [G0|G1] [X] [Y] [Z]`` (LinuxCNC): a straight move, rapid or at the feed of the motion mode
        in effect, to ``machine_origin + words`` (words in the current units, absolute); axes not given
        keep their position. Errors as LinuxCNC: G53 without G0/G1 in effect (none, G80, or an arc
        mode), under G91 (``interp_check.cc``: "Cannot use G53 incremental"); G4/G28 on its line are refused
        by ``line``."""
        k = groups["machine_coordinates"][1]
        named = [i for i, letter in enumerate("XYZ") if letter in vals]
        if "motion" not in groups and not named:
            raise _LineError("G53 without G0/G1 on the line and without X, Y or Z; expected G53 G0 or G53 G1 with "
                             "the machine coordinates to move to (LinuxCNC: must use G0 or G1 with G53)", k)
        if self.motion not in (0, 1):
            mode = "no motion mode in effect (none yet, or cancelled by G80)" if self.motion is None else \
                f"the arc motion mode G{self.motion} in effect"
            raise _LineError(f"G53 with {mode}; expected G0 or G1 on this line or in effect (LinuxCNC: G53 "
                             "moves in a straight line only)", k)
        if not self.absolute:
            raise _LineError("G53 under G91 (incremental distance mode); expected G90: the machine coordinates of "
                             "G53 are absolute (LinuxCNC: cannot use G53 incremental)", k)
        if not named:  # "G53 G0" alone: LinuxCNC sets the motion mode and moves nothing
            return
        s = self.scale
        t = list(self.pos)
        origin = self._origin(lineno)
        for i in named:
            num, kw = vals["XYZ"[i]]
            v = origin[i] + float(num) * s
            if not -_MAXC <= v <= _MAXC:
                raise _LineError(f"G53 {'XYZ'[i]}{_short(num)}: expected a finite machine coordinate with the position "
                                 f"(machine_origin + {'XYZ'[i]}) inside +-{_MAXC:g} mm", kw)
            t[i] = v
        rapid = self.motion == 0
        self._move(t, self._feed_for(rapid, vals, motion_word), rapid, lineno)

    def _target(self, vals):
        s = self.scale
        t = list(self.pos)
        for i, letter in enumerate("XYZ"):
            if letter in vals:
                num, k = vals[letter]
                v = float(num) * s
                v = v if self.absolute else t[i] + v
                if not -_MAXC <= v <= _MAXC:
                    raise _LineError(f"{letter}{_short(num)}: expected a finite coordinate with the position "
                                     f"inside +-{_MAXC:g} mm", k)
                t[i] = v
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
        self._move(target, self._feed_for(rapid, vals, where), rapid, lineno)

    def _move(self, target, feed, rapid, lineno):
        """A straight block to ``target`` [mm] at ``feed`` [mm/s]; none (a no-motion line) when it
        ends within ZERO_LENGTH_MM of the last vertex."""
        self.pos = target
        last = self.last
        dx, dy, dz = target[0] - last[0], target[1] - last[1], target[2] - last[2]
        if dx * dx + dy * dy + dz * dz <= ZERO_LENGTH_MM * ZERO_LENGTH_MM:
            self.no_motion.append(lineno)
            return
        t = (target[0], target[1], target[2])
        self.points.extend(t)
        self.last = t
        self.meta.append((feed, rapid, lineno, self.path_tol))
        self.counts.append(1)
        self.nblocks += 1

    def _arc(self, vals, lineno, motion_word):
        where = _first_axis(vals) if motion_word is None else motion_word
        cw = self.motion == 2
        name = "G2" if cw else "G3"
        a, b, c = _PLANES[self.plane]
        pname = _PLANE_NAME[self.plane]
        la, lb, lc = "IJK"[a], "IJK"[b], "IJK"[c]
        # the off-plane centre word: LinuxCNC refuses it; GRBL (FreeCAD's and other GRBL posts write
        # K0 on every G17 arc) ignores it. Read where it is 0, which moves no centre
        if lc in vals and float(vals[lc][0]) != 0.0:
            raise _LineError(f"{lc} given for an arc in the {pname} plane; expected the centre words {la} and "
                             f"{lb} (or R; an {lc} of 0 is read)", vals[lc][1])
        has_ij = la in vals or lb in vals
        if has_ij and "R" in vals:
            raise _LineError(f"{name} with both {la}/{lb} and R; expected either the centre ({la}, {lb}) or the "
                             "radius R", vals["R"][1])
        if not has_ij and "R" not in vals:
            raise _LineError(f"{name} without {la}/{lb} or R; expected the arc centre ({la}, {lb}) or radius (R) "
                             f"in the {pname} plane", where)
        turns = 1
        if "P" in vals:
            num, k = vals["P"]
            p = float(num)
            if not (math.isfinite(p) and abs(p - round(p)) <= 1e-3 and 1 <= round(p) <= MAX_ARC_TURNS):
                raise _LineError(f"{name} P{_short(num)}: expected the number of turns, an integer >= 1 "
                                 f"and <= {MAX_ARC_TURNS} (LinuxCNC: P1 is the plain arc, P2 one extra full turn)", k)
            turns = int(round(p))
        feed = self._feed_for(False, vals, where)
        s = self.scale
        st = self.last  # the arc starts at the last emitted vertex (within ZERO_LENGTH_MM of the position)
        su, sv = st[a], st[b]
        e = self._target(vals)
        eu, ev = e[a], e[b]
        chord = math.hypot(eu - su, ev - sv)
        rtol = RADIUS_TOLERANCE_MM
        if has_ij:
            ij_word = vals[la][1] if la in vals else vals[lb][1]
            if self.arc_absolute and not (la in vals and lb in vals):
                raise _LineError(f"{name} under G90.1 (absolute arc centre) without both {la} and {lb}; expected "
                                 f"both centre coordinates {la} and {lb}", ij_word)
            i = _value(la, vals[la][0], vals[la][1], s, what="centre") if la in vals else 0.0
            j = _value(lb, vals[lb][0], vals[lb][1], s, what="centre") if lb in vals else 0.0
            cu, cv = (i, j) if self.arc_absolute else (self.pos[a] + i, self.pos[b] + j)
            if not (abs(cu) <= 2 * _MAXC and abs(cv) <= 2 * _MAXC):
                raise _LineError(f"{name} centre ({cu:.6g}, {cv:.6g}) mm is not finite or too far away; expected "
                                 f"a centre inside +-{_MAXC:g} mm", ij_word)
            r0 = math.hypot(su - cu, sv - cv)
            r1 = math.hypot(eu - cu, ev - cv)
            if r0 < rtol or r1 < rtol:
                raise _LineError(f"{name} is a zero-radius arc (radius 0): start radius {r0:.6g} mm, end radius "
                                 f"{r1:.6g} mm, below {rtol:g} mm (LinuxCNC RADIUS_TOLERANCE); expected "
                                 f"{la}/{lb} pointing from the start to the centre", ij_word)
            err = abs(r1 - r0)
            if self.arc_tol is not None:
                allowed = self.arc_tol
            else:
                allowed = CENTER_ARC_RADIUS_TOLERANCE_INCH * MM_PER_INCH if s != 1.0 else CENTER_ARC_RADIUS_TOLERANCE_MM
            # LinuxCNC's rule (SPIRAL_HARD_LIMIT_FACTOR): refused above 100x the absolute tolerance, or
            # above it and above the relative tolerance of the larger radius; else a spiral
            hard = SPIRAL_HARD_LIMIT_FACTOR * allowed
            if err > hard or (err > allowed and err > self.arc_rel * max(r0, r1)):
                raise _LineError(
                    f"{name} end point is not on the arc: start radius {r0:.6g} mm and end radius {r1:.6g} mm "
                    f"differ by {err:.3g} mm, more than {allowed:.3g} mm and {100 * self.arc_rel:g} % of the "
                    f"radius (or more than {hard:.3g} mm); expected consistent end point and {la}/{lb}", ij_word)
            full = chord <= ZERO_LENGTH_MM
        else:
            rnum, rk = vals["R"]
            r = _value("R", rnum, rk, s, what="radius")
            if chord <= ZERO_LENGTH_MM:
                raise _LineError(f"{name} with R and end point == start point (in the {pname} plane) is "
                                 f"undefined; expected {la}/{lb} for a full circle", rk)
            if abs(r) < rtol:
                raise _LineError(f"{name} R{_short(rnum)}: a zero-radius arc; expected |R| >= {rtol:g} mm", rk)
            half = 0.5 * chord
            if half > abs(r) + rtol:
                raise _LineError(f"{name} R{_short(rnum)}: radius {abs(r):.6g} mm is smaller than half the chord "
                                 f"{half:.6g} mm (by more than {rtol:g} mm); expected |R| >= half the distance "
                                 "start-end", rk)
            # LinuxCNC arc_data_r: a half chord within 1e-12 of |R| is a semicircle (no sqrt of rounding noise)
            h = 0.0 if half >= abs(r) * (1.0 - 1e-12) else math.sqrt(r * r - half * half)
            ux, uy = (eu - su) / chord, (ev - sv) / chord
            # centre left of the chord for a CCW arc <= 180 deg, right for CW; R < 0 flips it
            side = (1.0 if not cw else -1.0) * (1.0 if r > 0 else -1.0)
            cu = 0.5 * (su + eu) - side * h * uy
            cv = 0.5 * (sv + ev) + side * h * ux
            r0 = math.hypot(su - cu, sv - cv)
            r1 = math.hypot(eu - cu, ev - cv)
            full = False
        a0 = math.atan2(sv - cv, su - cu)
        a1 = math.atan2(ev - cv, eu - cu)
        two_pi = 2.0 * math.pi
        if full:
            sweep = two_pi
        else:
            sweep = (a0 - a1) % two_pi if cw else (a1 - a0) % two_pi
            if sweep <= 0.0:  # same ray, radii within tolerance: treat as a full turn
                sweep = two_pi
        sweep += two_pi * (turns - 1)
        # sagitta r (1 - cos(dtheta / 2)) <= tol  <=>  dtheta <= 2 acos(1 - tol / r) = 4 asin(sqrt(tol / (2 r)))
        rmax = max(r0, r1)
        dmax = 4.0 * math.asin(math.sqrt(min(self.tol / (2.0 * rmax), 1.0)))
        dmax = min(dmax, MAX_CHORD_ANGLE)
        n = max(1, math.ceil(sweep / dmax)) if dmax > 0.0 else math.inf
        if n > MAX_CHORDS_PER_ARC:
            raise _LineError(f"{name} of radius {rmax:.6g} mm would need {n} chords at chord_tolerance "
                             f"{self.tol:g} mm (limit {MAX_CHORDS_PER_ARC}); expected a larger chord_tolerance", where)
        sw, ew = st[c], e[c]
        self.pos = e
        # shortest chord: 2 rmin sin(step / 2) in the plane (a helix only lengthens it)
        k = np.arange(1, n + 1, dtype=np.float64) / n
        ang = a0 + (-sweep if cw else sweep) * k
        rad = r0 + (r1 - r0) * k
        arr = np.empty((n, 3))
        arr[:, a] = cu + rad * np.cos(ang)
        arr[:, b] = cv + rad * np.sin(ang)
        arr[:, c] = sw + (ew - sw) * k
        arr[-1] = e
        if 2.0 * min(r0, r1) * math.sin(0.5 * sweep / n) <= 4.0 * ZERO_LENGTH_MM:
            # tiny arcs only: merge chords shorter than ZERO_LENGTH_MM
            keep, prev = [], np.asarray(self.last)
            for p in arr:
                if np.sum((p - prev) ** 2) > ZERO_LENGTH_MM * ZERO_LENGTH_MM:
                    keep.append(p)
                    prev = p
            if not keep:
                self.no_motion.append(lineno)
                return
            keep[-1] = arr[-1]
            arr = np.asarray(keep)
        self.points.frombytes(arr.tobytes())
        self.last = tuple(arr[-1].tolist())
        centre = [0.0, 0.0, 0.0]
        centre[a], centre[b], centre[c] = cu, cv, sw
        normal = [0.0, 0.0, 0.0]
        normal[c] = -1.0 if cw else 1.0
        self.arcs.append((self.nblocks, centre, normal, sweep))
        self.meta.append((feed, False, lineno, self.path_tol))
        self.counts.append(len(arr))
        self.nblocks += 1


_AXIS_LETTERS = frozenset("XYZIJKR")
_ARC_LETTERS = frozenset("IJKR")


def _first_axis(vals) -> int:
    """Word index of the first axis word of a block."""
    return min(vals[c][1] for c in _AXIS_LETTERS.intersection(vals))


def _code_key(num: str):
    """``10 * code`` for a G/M number written with at most one decimal digit (G1, G01, G90.1, G1.0; trailing
    zeros are fine, ``G1.00000001`` is not), from the text alone (no float rounding); else None."""
    m = _CODE_TEXT.fullmatch(num)
    if m is None:
        return None
    return int(m.group(1)) * 10 + int(m.group(2) or 0)


def _fmt_key(key: int) -> str:
    return str(key // 10) if key % 10 == 0 else f"{key // 10}.{key % 10}"
