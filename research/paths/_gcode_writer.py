"""G-code writer: a polyline, or a program's blocks with its arcs, as a G21/G90 program that
:func:`parse_gcode` reads back (polylines bit-exactly)."""

from __future__ import annotations

import numpy as np

from research.errors import ParameterError
from research.paths._gcode_constants import ZERO_LENGTH_MM
from research.paths.polyline import Polyline


def _num(v: float) -> str:
    """Shortest decimal (no exponent) that reads back as exactly ``v``."""
    return np.format_float_positional(v, unique=True, trim="-")


def to_gcode(polyline, feeds_mm_per_min=None, rapid=None, *, line_numbers: bool = False) -> str:
    """Write a polyline as a G21/G90 program of ``G1`` (and ``G0``) lines, one segment per line.

    Given a :class:`~research.paths.gcode.GCodeProgram` instead (and no feeds or rapid flags),
    writes its blocks: lines as ``G0``/``G1``, arcs as ``G2``/``G3`` in the G17/G18/G19 plane of
    their axis with ``G91.1`` centre offsets and ``P`` for extra turns, ``F`` from ``block_feeds``,
    ``G64 P`` / ``G64`` / ``G61`` whenever ``block_tolerance`` changes, and ``G4 P`` for each of its
    ``block_pauses`` (an ``M0``/``M1`` stop as ``G4 P0``, the same stop of 0 s). Reading it back gives the
    same block ends (exactly), feeds, rapid flags, tolerances and pauses, and centres and sweeps within
    float rounding (the centre is written as an offset from the start).

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
    if hasattr(polyline, "blocks") and hasattr(polyline, "block_tolerance"):
        if feeds_mm_per_min is not None or rapid is not None:
            raise ParameterError("to_gcode: a GCodeProgram carries its own feeds and rapid flags; pass neither")
        return _blocks_to_gcode(polyline, line_numbers)
    if feeds_mm_per_min is None:
        raise ParameterError("to_gcode: feeds_mm_per_min is required for a polyline")
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
        words += _axis_words(p, prev)
        if g == 1 and feeds[k] != feed:
            feed = feeds[k]
            words.append(f"F{_num(feed)}")
        prev = p
        out.append(" ".join(words))
    return _finish(out, line_numbers)


def _finish(out: list[str], line_numbers: bool) -> str:
    out += ["M30", "%"]
    if line_numbers:
        n = 0
        for i, line in enumerate(out):
            if line != "%" and not line.startswith("("):
                n += 10
                out[i] = f"N{n} {line}"
    return "\n".join(out) + "\n"


# normal axis -> (plane word, first axis, second axis)
_PLANE_OF = {2: ("G17", 0, 1), 1: ("G18", 2, 0), 0: ("G19", 1, 2)}


def _blocks_to_gcode(prog, line_numbers: bool) -> str:
    b = prog.blocks
    if b.dim != 3 or tuple(a.lower() for a in b.axes) != ("x", "y", "z"):
        raise ParameterError(f"to_gcode: blocks with axes {b.axes} cannot be written; expected x, y, z")
    p0 = b.start
    out = ["%", f"(research.paths.gcode.to_gcode: start X{_num(p0[0])} Y{_num(p0[1])} Z{_num(p0[2])})",
           "G21 G90 G91.1 G94"]
    mode = plane = feed = None
    tol = "unset"
    prev = p0
    pauses = getattr(prog, "block_pauses", None)
    for k in range(b.n_blocks):
        if pauses is not None and not np.isnan(pauses[k]):
            out.append(f"G4 P{_num(pauses[k])}")
        e = b.ends[k]
        words = []
        t = prog.block_tolerance[k]
        t_key = "nan" if np.isnan(t) else float(t)
        if t_key != tol:
            # a tolerance of 0 is G61's (exact path): G64 P0 reads as no tolerance, as in LinuxCNC
            out.append("G64" if t_key == "nan" else "G61" if t == 0.0 else f"G64 P{_num(t)}")
            tol = t_key
        if b.sweeps[k] > 0:
            n = b.normals[k]
            axis = int(np.argmax(np.abs(n)))
            if abs(abs(n[axis]) - 1.0) > 1e-12:
                raise ParameterError(f"to_gcode: arc block {k} turns about {n.tolist()}; only arcs about the x, "
                                     "y or z axis (G17/G18/G19) can be written")
            g_plane, a, c2 = _PLANE_OF[axis]
            if g_plane != plane:
                words.append(g_plane)
                plane = g_plane
            g = 3 if n[axis] > 0 else 2
            turns = max(1, int(np.ceil(b.sweeps[k] / (2 * np.pi) - 1e-9)))
            centre = b.centers[k]
            words.append(f"G{g}")
            mode = g
            words += _axis_words(e, prev)
            for i in (a, c2):
                words.append(f"{'IJK'[i]}{_num(centre[i] - prev[i])}")
            if turns > 1:
                words.append(f"P{turns}")
        else:
            g = 0 if prog.block_rapid[k] else 1
            if g != mode:
                words.append(f"G{g}")
                mode = g
            words += _axis_words(e, prev)
        if not prog.block_rapid[k]:
            f = float(prog.block_feeds[k]) * 60.0
            if f != feed:
                words.append(f"F{_num(f)}")
                feed = f
        prev = e
        out.append(" ".join(words))
    if pauses is not None and not np.isnan(pauses[-1]):
        out.append(f"G4 P{_num(pauses[-1])}")
    return _finish(out, line_numbers)


def _axis_words(end, prev) -> list[str]:
    """``X Y Z`` words of the coordinates of ``end`` that differ from ``prev`` (modal axes)."""
    return [f"{letter}{_num(end[i])}" for i, letter in enumerate("XYZ") if end[i] != prev[i]]
