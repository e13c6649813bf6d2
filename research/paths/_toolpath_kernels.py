"""Compiled (Numba) kernels of ``ToolPath``: distances to lines and arcs, read by row from the arc
geometry (centre ``c``, normal ``n``, in-plane frame ``e1, e2``, end radii ``r0, r1``, end axial
offsets ``a0, a1``, sweep), and the direction changes of an arc's chords. Each states the NumPy
arithmetic it repeats where its results must equal ``ToolPath``'s vectorised ones."""

from __future__ import annotations

import math

import numba
import numpy as np


@numba.njit(cache=True, nogil=True, error_model="numpy")
def _nearest_line(q, blocks, starts, ends):
    """``min_c`` of :meth:`ToolPath._block_distance` (line blocks) from ``q[i]`` to ``blocks[i, c]``:
    the same projection, clamp and norm, summed in axis order as NumPy's reductions."""
    N, C, d = q.shape[0], blocks.shape[1], q.shape[1]
    out = np.empty(N)
    for i in range(N):
        best = np.inf
        for c in range(C):
            k = blocks[i, c]
            ab2, dot = 0.0, 0.0
            for a in range(d):
                ab = ends[k, a] - starts[k, a]
                ab2 += ab * ab
                dot += (q[i, a] - starts[k, a]) * ab
            u = min(max(dot / (ab2 if ab2 > 0 else 1.0), 0.0), 1.0)
            acc = 0.0
            for a in range(d):
                ab = ends[k, a] - starts[k, a]
                r = q[i, a] - (starts[k, a] + u * ab)
                acc += r * r
            best = min(best, math.sqrt(acc))
        out[i] = best
    return out


@numba.njit(cache=True, nogil=True, error_model="numpy")
def _arc_projection(q, rows, c, e1, e2):
    """In-plane coordinates ``(y, x)`` of ``q[i] - c`` on the frame ``e2, e1`` of arc row
    ``rows[i]``: the arithmetic of NumPy's ``np.sum((q - c) * e, axis=1)``, term by term."""
    N = q.shape[0]
    y, x = np.empty(N), np.empty(N)
    for i in range(N):
        j = rows[i]
        sy, sx = 0.0, 0.0
        for a in range(3):
            rel = q[i, a] - c[j, a]
            if a == 0:
                sy, sx = rel * e2[j, a], rel * e1[j, a]
            else:
                sy += rel * e2[j, a]
                sx += rel * e1[j, a]
        y[i], x[i] = sy, sx
    return y, x


@numba.njit(cache=True, nogil=True, error_model="numpy")
def _arc_points(c, n, e1, e2, r0, dr, a0, da, phi, order, p, d1, d2):
    """``P``, and with ``order`` 2 its first and second derivatives in ``phi``, of one arc at
    ``phi`` into ``p``, ``d1``, ``d2`` (3,): the arithmetic of :func:`_arc_eval`, term by term in
    its order, with one cosine and sine for the three."""
    co, si = math.cos(phi), math.sin(phi)
    r = r0 + dr * phi
    for a in range(3):
        p[a] = (c[a] + (a0 + da * phi) * n[a]) + r * (co * e1[a] + si * e2[a])
        if order == 2:
            d1[a] = (r * (-si * e1[a] + co * e2[a]) + dr * (co * e1[a] + si * e2[a])) + da * n[a]
            d2[a] = r * (-co * e1[a] + -si * e2[a]) + (2.0 * dr) * (-si * e1[a] + co * e2[a])


@numba.njit(cache=True, nogil=True, error_model="numpy")
def _chord_turns(rows, counts, starts, ends, t_in, t_out, c, n, e1, e2, r0, r1, a0, a1, sweep, total):
    """``(total, 3)`` turns of ``counts[i]`` equal-angle chords of arc row ``rows[i]`` from
    ``starts[i]`` to ``ends[i]`` with end tangents ``t_in[i]``, ``t_out[i]``: first chord less
    ``t_in``, the chords' direction changes, ``t_out`` less the last chord (:meth:`ToolPath.arc_chord_turns`)."""
    out = np.empty((total, 3))
    p, q, u, v, d1, d2 = np.empty(3), np.empty(3), np.empty(3), np.empty(3), np.empty(3), np.empty(3)
    o = 0
    for i in range(rows.size):
        j, m = rows[i], counts[i]
        sw = sweep[j]
        dr, da = (r1[j] - r0[j]) / sw, (a1[j] - a0[j]) / sw
        for a in range(3):
            p[a] = starts[i, a]
            u[a] = t_in[i, a]
        for k in range(1, m + 1):
            if k < m:
                _arc_points(c[j], n[j], e1[j], e2[j], r0[j], dr, a0[j], da, sw * k / m, 0, q, d1, d2)
            else:
                for a in range(3):
                    q[a] = ends[i, a]
            acc = 0.0
            for a in range(3):
                v[a] = q[a] - p[a]
                acc += v[a] * v[a]
            norm = math.sqrt(acc)
            for a in range(3):
                v[a] = v[a] / norm if norm > 0 else 0.0
                out[o, a] = v[a] - u[a]
                u[a] = v[a]
                p[a] = q[a]
            o += 1
        for a in range(3):
            out[o, a] = t_out[i, a] - u[a]
        o += 1
    return out


@numba.njit(cache=True, nogil=True, error_model="numpy")
def _newton_steps(qi, c, n, e1, e2, r0, dr, a0, da, sw, phi, p, d1, d2):
    """At most three safeguarded Newton steps on ``|P(phi) - qi|^2`` over an arc (row geometry as
    :func:`_nearest_arc`), each clamped to ``[0, sw]``, from ``phi``: ``(phi, at)``, ``at`` True when
    a step left ``phi`` where it was (``p`` then holds ``P(phi)``, evaluated by that step)."""
    for _ in range(3):
        _arc_points(c, n, e1, e2, r0, dr, a0, da, phi, 2, p, d1, d2)
        slope, dd, ed = 0.0, 0.0, 0.0
        for a in range(3):
            e = p[a] - qi[a]
            slope += e * d1[a]
            dd += d1[a] * d1[a]
            ed += e * d2[a]
        curv = dd + ed
        new = phi - slope / curv if curv > 0 else phi
        new = min(max(new, 0.0), sw)
        if new == phi:
            return phi, True
        phi = new
    return phi, False


@numba.njit(cache=True, nogil=True, error_model="numpy")
def _nearest_arc(q, rows, base, c, n, e1, e2, r0, r1, a0, a1, sweep):
    """Distance from ``q[i]`` to arc row ``rows[i]``: the least over the candidate angles, the two
    ends as they are and every turn of the projection angle ``base[i]`` [rad, in [0, 2 pi)] inside
    the sweep (clamped) after at most three safeguarded Newton steps on ``|P(phi) - q|^2``. A
    candidate angle equal to an earlier one, the steps after one that leaves the angle where it
    was, and the point's evaluation after such a step (which computed it) would repeat the same
    arithmetic: they are skipped (the result is the same). No Newton steps start from the ends as
    such: one there only walks towards the stationary point near a turn of ``base``, which the
    steps from that turn reach (on a circular arc in one step). But a turn of ``base`` clamped to
    an end takes its steps from there: on a steep helix (a small sweep over a long axial travel)
    the nearest point lies near the end its projection angle clamps to, at the query's axial
    height (skipped, a point 1e-4 mm from a helix of 0.01 rad over 10 mm read 0.1 mm: the distance
    to its start). Measured: the same plans on bench_adaptive's programs and the fuzz programs of
    ``tests/fuzz/test_fuzz_fir_programs.py``, 44 % less time in this kernel (before the clamped
    turns took their steps).

    A planar arc (no axial travel) of less than a turn whose projection angle lies inside its
    sweep takes no steps from its end: ``|P - q|^2 = (r - rho)^2 + 2 r rho (1 - cos(phi - base))
    + z^2``, ``r`` linear in ``phi`` at slope ``r'``, is stationary only where ``r rho |sin(phi -
    base)| <= |r'| (|r - rho| + 2 rho)``: near ``base`` (the minimum the steps from ``base``
    reach) or near ``base + pi`` (a maximum) wherever ``rho`` is well above ``|r'|``, as for every
    point near a circular or nearly circular arc. Near a spiral's centre neither start need reach
    an inner minimum (a point 0.47 mm from the centre of an R 7.6 mm spiral read 7.1228 mm
    against 7.1210 mm): where that band reaches :data:`SPIRAL_SCAN` the sweep is also scanned
    (:func:`_scanned_arc`). Measured on a real program of 691 arcs (spirals within 2.3 um of circles): 32 % less time in
    this kernel, the same plans to 1e-15.

    A planar arc of less than a turn whose projection angle lies outside its sweep has no minimum
    inside it where the band around ``base`` misses the sweep (more than twice the band's bound
    away, ``asin(x) <= 2 x``) and the band is below :data:`OUTSIDE_BAND`: the stationary points near
    ``base + pi`` are then maxima (``f'' <= 2 r'^2 + 4 |r'| rho - 2 r rho cos 30 deg < 0`` there,
    with ``|r'| <= r_min rho / (2 (r_max + 3 rho))``), so the ends hold the least distance and the
    steps from the end the angle clamps to are skipped (they could only find a point no nearer).
    Measured on the mirror's samples of a real inch program (2,204 sub-arcs, 78 % of the points
    projecting outside): 155 -> 67 ns a point, every distance the same bits."""
    N = q.shape[0]
    out = np.empty(N)
    p, d1, d2 = np.empty(3), np.empty(3), np.empty(3)
    two_pi = 2.0 * np.pi
    most = 0
    for i in range(N):
        most = max(most, int(np.ceil(sweep[rows[i]] / two_pi)) + 1)
    starts = np.empty(most + 2)
    for i in range(N):
        j = rows[i]
        sw = sweep[j]
        dr, da = (r1[j] - r0[j]) / sw, (a1[j] - a0[j]) / sw
        turns = int(np.ceil(sw / two_pi)) + 1
        best = np.inf
        # a planar arc's stationary band about the projection angle: |sin(phi - base)| <= band / (r_lo rho)
        band, rho, r_lo = 0.0, 0.0, min(r0[j], r1[j])
        if da == 0.0:
            x, y = 0.0, 0.0
            for a in range(3):
                x += (q[i, a] - c[j, a]) * e1[j, a]
                y += (q[i, a] - c[j, a]) * e2[j, a]
            rho = math.sqrt(x * x + y * y)
            band = abs(dr) * (max(r0[j], r1[j]) + 3.0 * rho)
        outside = False  # a planar arc of less than a turn whose band near base misses the sweep
        if da == 0.0 and sw < two_pi and base[i] > sw and band < OUTSIDE_BAND * r_lo * rho:
            gap = min(base[i] - sw, two_pi - base[i])  # angle from base to the sweep [0, sw]
            outside = gap > 2.0 * band / (r_lo * rho)
        for m in range(turns + 2):
            if m == 0:
                phi = 0.0
            elif m == 1:
                phi = sw
            else:
                phi = min(max(base[i] + two_pi * (m - 2), 0.0), sw)
                if m >= 3 and da == 0.0 and sw < two_pi and base[i] <= sw:
                    break  # a planar arc of less than a turn: its end is no start (docstring)
                if m == 2 and outside:
                    break  # no minimum inside the sweep: the ends hold the least distance (docstring)
            starts[m] = phi
            seen = False
            for k in range(2 if m >= 2 else 0, m):  # a turn clamped to an end still takes its steps
                seen = seen or starts[k] == phi
            if seen:
                continue
            at_phi = False  # p holds P(phi) already (the step that left phi unchanged evaluated it)
            if m >= 2:
                phi, at_phi = _newton_steps(q[i], c[j], n[j], e1[j], e2[j], r0[j], dr, a0[j], da, sw, phi, p, d1, d2)
            if not at_phi:
                _arc_points(c[j], n[j], e1[j], e2[j], r0[j], dr, a0[j], da, phi, 0, p, d1, d2)
            acc = 0.0
            for a in range(3):
                e = p[a] - q[i, a]
                acc += e * e
            best = min(best, math.sqrt(acc))
        if da == 0.0 and dr != 0.0 and band >= SPIRAL_SCAN * r_lo * rho:
            # a planar spiral near its centre: minima away from the starts
            best = min(best, _scanned_arc(q[i], c[j], n[j], e1[j], e2[j], r0[j], dr, a0[j], sw, p, d1, d2))
        out[i] = best
    return out


#: a planar arc (or spiral) whose projection angle lies outside its sweep takes no Newton steps from
#: the end it clamps to where its stationary band ``|sin(phi - base)| <= |r'| (r_max + 3 rho) /
#: (r_min rho)`` (:func:`_nearest_arc`) is below this and the angle from ``base`` to the sweep is
#: above twice the band (``asin(x) <= 2 x`` for ``x <= 0.5``)
OUTSIDE_BAND = 0.5
#: a planar spiral arc whose stationary band ``|sin(phi - base)| <= |r'| (r_max + 3 rho) / (r_min
#: rho)`` (:func:`_nearest_arc`'s docstring, with ``|r - rho| <= r_max + rho``) reaches this is also
#: scanned (:func:`_scanned_arc`): below it every stationary point lies within 6 deg of the
#: projection angle or of its opposite
SPIRAL_SCAN = 0.1
#: the scan's angle step [rad] (``tests/paths/test_toolpath_distance.py`` holds the result to a
#: brute-force search over 20,001 angles, points near the centre included)
SCAN_STEP = 0.05


@numba.njit(cache=True, nogil=True, error_model="numpy")
def _scanned_arc(qi, c, n, e1, e2, r0, dr, a0, sw, p, d1, d2):
    """Distance from ``qi`` to a planar arc (row geometry as :func:`_nearest_arc`): the least over
    angles ``SCAN_STEP`` apart across the sweep, then :func:`_newton_steps` from the best of them."""
    m = int(math.ceil(sw / SCAN_STEP)) + 1
    best, at = np.inf, 0.0
    for k in range(m):
        phi = sw * k / (m - 1)
        _arc_points(c, n, e1, e2, r0, dr, a0, 0.0, phi, 0, p, d1, d2)
        acc = 0.0
        for a in range(3):
            e = p[a] - qi[a]
            acc += e * e
        if acc < best:
            best, at = acc, phi
    phi, at_phi = _newton_steps(qi, c, n, e1, e2, r0, dr, a0, 0.0, sw, at, p, d1, d2)
    if not at_phi:
        _arc_points(c, n, e1, e2, r0, dr, a0, 0.0, phi, 0, p, d1, d2)
    acc = 0.0
    for a in range(3):
        e = p[a] - qi[a]
        acc += e * e
    return math.sqrt(min(acc, best))
