"""The G-code interpreter: modal state, accepted and refused codes, arcs to chords.

Private to :mod:`research.paths.gcode`; see its docstring for the accepted language.
"""

from __future__ import annotations

import math

import numpy as np

from research.errors import ParameterError
from research.paths._gcode_constants import (
    MAX_CHORD_ANGLE,
    MAX_CHORDS_PER_ARC,
    MM_PER_INCH,
    ZERO_LENGTH_MM,
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
