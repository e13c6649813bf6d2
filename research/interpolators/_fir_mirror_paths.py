"""The paths ``plan_fir_mirror``'s search plans and checks: arcs as chords, fillets as corners.

The search times and moves the vertices of a path of lines (the *planned* path) and checks the
filtered result against the program (the *checked* path, block for block the same count, so that
each checked vertex has the planned corner's instant).

* :func:`chorded`: every arc as chords of equal angle, checked as the arc's own pieces.
* :func:`cornered`: besides, every *fillet* shorter than the filters' reach is planned as the
  corner ``V`` where the lines either side of it meet (an arc too far inside that corner as the
  polygon of its tangents, with a few corners), and checked as the fillet. A fillet is a short
  arc tangent to its neighbours (CAM corner smoothing, a tool-radius arc), or a run of short
  chords between two long blocks that turns one way (the same written as ``G1`` chords).
  The FIR's window averages such a fillet whole, so ``plan_fir`` cannot follow it as a curve; it
  slows it to its eq 8 feed (an arc) or to its chords' window feeds, as if it were a long curve.
  As a corner, eq 13/14 rounds it at a tolerance :func:`planned_tolerance` that the search
  bisects (:func:`bisect_rounding`) until the rounding passes within eps of the fillet.

The search keeps whichever of the two planned paths verifies faster (``_fir_mirror``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from research.paths.polyline import Polyline
from research.paths.toolpath import ToolPath
from research.interpolators._fir_verify import nearest_instants

#: sagitta of the chords the search plans for arcs, as a share of the least arc tolerance
#: (:func:`chorded`). Swept (``benchmarks/fir_mirror.py --sweep-chords``) at 0.01 / 0.02 / 0.05 /
#: 0.1 / 0.2 / 0.35 / 0.5 on eleven programs with arcs under bench_cam's setting and envelope: cycles
#: summed 20.20 / 20.12 / 19.71 / 19.60 / 19.62 / 19.94 / 19.78 s, planning 11.7 / 9.8 / 8.9 / 8.1 /
#: 7.7 / 7.8 / 8.3 s
CHORD_SHARE = 0.1
#: a fillet up to this share of the filters' reach at its feed (``F T_d``) is short (:func:`cornered`): the
#: window averages it whole. Swept with the tangent polygons (CORNER_OFFSET's cases and a ring of
#: R 15 mm fillets, 23.6 mm long) at 0.5 / 1 / 2 / 3: cycle times summed 56.0554 / 55.3997 / 55.2559 /
#: 55.2559 s (at 0.5 the ring of R 10 mm fillets 1.6213 against 1.1191 s; at 2 the R 15 mm ring
#: 1.1355 against 1.2518 s, and the 40-arc chain 4.8478 against 4.8016 s); 1, the reach itself, is
#: kept: within 0.3 % of the best; at 0 (no fillets) the pocket 10.8623 s against 8.3186 s
SHORT_REACH = 1.0
#: the largest turn [rad] of one corner a fillet is planned as (:func:`cornered`); a fillet that turns
#: more is planned as at least ``ceil(turn / CORNER_TURN)`` corners. Fillets of R 0.3 / 1 mm between
#: 50 mm lines turning 60-170 deg (bench_cam's setting) verify as one corner up to 120 deg (R 0.3 mm:
#: 0.7439 -> 0.6431 s) and never beyond (150, 170 deg). Swept as the turn of one corner at 90 / 120 /
#: 135 / 150 deg: the 120 fuzz contours of ``tests/fuzz/test_fuzz_fir_fillets.py`` summed 669.6232 /
#: 668.7790 / 669.5255 / 669.2328 s (681.4362 s plain), fillets of 90-165 deg and slots of R 0.3-6 mm
#: (25 programs, with and without the envelope's limits) 42.0482 / 42.0482 / 42.1319 / 42.1586 s
CORNER_TURN = 2.0 * math.pi / 3.0
#: a turn [rad] up to which an arc's start or end counts as tangent (:func:`cornered`): 4-decimal
#: coordinates of a fillet of R >= 0.1 mm turn by less than 1e-3 rad where it is tangent
TANGENT_TURN = 1e-3
#: the bracket width on a fillet's rounding below which its bisection stops (:func:`bisect_rounding`).
#: Swept 1/8, 1/16, 1/64, 1/256 on SHORT_REACH's cases: the pocket 9.1704 / 9.0866 / 9.0319 / 9.0319 s
#: (limits) and 8.3700 / 8.3407 / 8.3186 / 8.3186 s, the others the same
SHORT_LEAST = 1.0 / 64.0
#: the shortest piece [mm] from a fillet's end to its corner (:func:`cornered`): below it the fillet
#: barely turns and is left as it is
SHORT_LEG = 1e-6
#: the largest offset of a fillet's corner from the arc, in tolerances (:func:`_arc_fillets`): the
#: first search's corner count; spent fillets get more. Swept 8 / 10 / 12 / 16 / 20 / 24 / 32 on
#: bench_cam's setting (the 8-ring pocket, rings with fillets of R 1-10 mm, single fillets of R
#: 0.3-5 mm, the arc chains; with and without the envelope's limits): cycle times summed 55.3077 /
#: 53.4566 / 53.3731 / 53.2339 / 52.9522 / 52.9522 / 52.9984 s, planning 16.6-21.8 s (8: a fillet
#: of R 1 mm takes two corners, 0.6840 s against 0.6298 s with one)
CORNER_OFFSET = 20.0
#: the most corners an arc fillet is planned as (:func:`_arc_fillets`)
CORNERS_MAX = 4
#: searches again, each fillet whose bisection ran out with one more corner, at most this many
#: times after a search with fillets as corners that verified nothing better (``_fir_mirror``).
#: Swept 0 / 1 / 2 / 3 on the 120 filleted contours of ``tests/fuzz/test_fuzz_fir_fillets.py``:
#: faster than ``plan_fir`` on 18 / 27 / 29 / 29, cycle times summed 678.9245 / 677.2507 /
#: 676.9570 / 676.9570 s (681.4362 s plain), planning 73.2 / 80.8 / 82.4 / 82.2 s
FILLET_RETRIES = 2
#: a chord of a fillet is no longer than this share of the filters' reach (:func:`_chord_fillets`), and
#: the blocks either side of the fillet are longer than FILLET_RATIO of its longest chord. Swept
#: 0.0625 / 0.125 / 0.25 and 2 / 4 / 8 on the filleted rectangles (R 1 and 0.3 mm) and the offset
#: pocket of 8 rings as G1 chords of 1 and 5 um, with and without the envelope's limits: the same
#: cycle times (the pocket at 1 um 11.5952 -> 8.3051 s); the inner rings' 12-18 mm sides are
#: shorter than the reach, which is why a chord must be much shorter than it. Even at 0.5 / 1
#: bench_cam's freeform CAM files (2,251 and 10,359 chords) have no chord fillet
CHORD_REACH = 0.125
FILLET_RATIO = 4.0


@dataclass(frozen=True)
class Fillets:
    """The fillets :func:`cornered` plans as corners (``n`` of them).

    Attributes:
        corners: ``(n, d)`` where the lines either side of each fillet meet (``V``) [mm].
        splits: ``(n, d)`` each fillet's point nearest ``V`` (``P``; an arc's at half its sweep) [mm].
        pinned: ``(m, d)`` the planned vertices the mirror passes leave where they are: each
            fillet's ``V``, start, end and the points between [mm].
        first: ``(n,)`` the planned block that ends at each ``V`` (``V`` is planned corner ``first``).
        offset: ``(n,)`` ``|V - P|`` [mm].
        corner_of: ``(B - 1,)`` the fillet whose ``V``, start, end or inner vertex each planned corner
            is (an arc's start or end where it is tangent); -1 for the others.
        owners: ``(n,)`` a programmed block of each fillet (an arc's own, a run's first).
    """

    corners: np.ndarray
    splits: np.ndarray
    pinned: np.ndarray
    first: np.ndarray
    offset: np.ndarray
    corner_of: np.ndarray
    owners: np.ndarray


def chorded(tp: ToolPath, tol: np.ndarray) -> tuple[ToolPath, ToolPath, np.ndarray]:
    """The path the mirror's search plans and the one it checks: ``(planned, checked, owner)``.

    On a path of lines both are ``tp`` and ``owner`` is ``arange(M)``. With arcs, ``planned`` holds
    every arc as chords of equal angle (``ToolPath.to_polyline``) of sagitta at most
    :data:`CHORD_SHARE` of the least arc tolerance in ``tol`` ``(M,)`` [mm], and ``checked`` the
    same blocks as sub-arcs of the programmed arcs (the same centre and axis, the sweep split
    evenly: radius and axial offset are linear in the angle, so each is the programmed arc's own
    piece): the search moves and times the chords' vertices and checks the programmed arcs
    themselves. ``owner`` ``(B,)`` is each planned block's programmed block."""
    M = tp.n_blocks
    if not tp.is_arc.any():
        return tp, tp, np.arange(M)
    chords, owner = tp.to_polyline(CHORD_SHARE * float(np.min(tol[tp.is_arc])))
    count = np.bincount(owner, minlength=M)[owner]
    checked = ToolPath(tp.start, chords.points[1:], tp.centers[owner], tp.normals[owner],
                       np.where(tp.is_arc[owner], tp.sweeps[owner] / count, 0.0), tp.axes)
    return ToolPath.from_polyline(chords), checked, owner


def cornered(tp: ToolPath, tol: np.ndarray, feed: np.ndarray, window: float, extra: np.ndarray | None = None):
    """:func:`chorded` with the fillets planned as corners: ``(planned, checked, owner, fillets)``
    (a :class:`Fillets`), or None where the path has none (module docstring).

    A fillet is no longer than :data:`SHORT_REACH` times the filters' reach at its feed (``feed``
    ``(M,)`` [mm/s] times ``window``, the delays' sum [s]), lies in a plane and is not at the
    path's ends (the output rests there); it may turn the path back on itself (a slot's half
    circle). An arc fillet (:func:`_arc_fillets`) gives way to the polygon of its tangents (with
    one corner ``V``, the two tangent lines from its ends to where they meet; each corner turns
    by at most :data:`CORNER_TURN`), checked as its pieces (split at each
    ``P``, the arc's point nearest a corner); each fillet pins its vertices once, in its first
    corner's part. A chord fillet
    (:func:`_chord_fillets`) keeps its block count: its vertices move onto the polygon of its
    tangents, and it is checked as programmed. ``tol`` ``(M,)`` [mm] as :func:`chorded`'s;
    ``extra`` ``(M,)``: the searches each programmed block's fillet spent (``_fir_mirror``): one
    more corner for each (beyond :data:`CORNERS_MAX` the fillet stays as programmed)."""
    Td = float(window)
    extra = np.zeros(tp.n_blocks, dtype=int) if extra is None else extra
    arcs = _arc_fillets(tp, tol, feed, Td, extra)
    if arcs is None:
        planned, checked, owner = chorded(tp, tol)
        parts = []
    else:
        planned, checked, owner, parts = arcs
    chords = _chord_fillets(planned, checked, owner, feed, tol[owner], Td, extra)
    if chords is not None:
        planned, more = chords
        parts = parts + more
    if not parts:
        return None
    corner_of = np.full(planned.n_blocks - 1, -1)
    for i, (V, P, pinned, first, corners, _) in enumerate(parts):
        corner_of[corners] = i
    V, P, pinned, first, _, owners = zip(*parts)
    return planned, checked, owner, Fillets(np.array(V), np.array(P), np.concatenate(pinned), np.array(first),
                                            np.linalg.norm(np.array(V) - np.array(P), axis=1), corner_of,
                                            np.array(owners))


def _corner_points(S: np.ndarray, u: np.ndarray, E: np.ndarray, w: np.ndarray):
    """``(V, keep)``: where the line through ``S`` along ``u`` meets the one through ``E`` along
    ``w`` (unit directions; ``V = S + a u = E - b w``, by least squares), each ``(n, d)`` [mm], and
    whether they meet (in a plane) ahead of ``S`` and behind ``E`` by more than :data:`SHORT_LEG`."""
    d = E - S
    uw = np.sum(u * w, axis=1)
    det = np.maximum(1.0 - uw**2, 1e-300)  # each corner turns by at most CORNER_TURN < pi: not parallel
    du, dw = np.sum(d * u, axis=1), np.sum(d * w, axis=1)
    a, b = (du - uw * dw) / det, (dw - uw * du) / det
    V = S + a[:, None] * u
    planar = np.linalg.norm(V - (E - b[:, None] * w), axis=1) <= 1e-9 * (1.0 + np.linalg.norm(d, axis=1))
    return V, planar & (a > SHORT_LEG) & (b > SHORT_LEG) & (uw < 1.0 - 1e-12)


def _corner_count(turn, radius, tol):
    """The fewest corners of the tangent polygon of a fillet turning ``turn`` [rad] at ``radius``
    [mm] (arrays or scalars): each within :data:`CORNER_OFFSET` tolerances ``tol`` [mm] of the arc
    (corner ``i`` lies ``R (1 / cos(turn / 2n) - 1)`` outside it) and turning at most
    :data:`CORNER_TURN`; at least one."""
    half = np.arccos(radius / (radius + CORNER_OFFSET * tol))  # the largest half-turn per corner
    return np.maximum(np.ceil(np.maximum(turn / (2.0 * half), turn / CORNER_TURN) - 1e-9).astype(int), 1)


def _arc_fillets(tp: ToolPath, tol: np.ndarray, feed: np.ndarray, Td: float, extra: np.ndarray):
    """The arc fillets of ``tp`` as corners: ``(planned, checked, owner, parts)`` (:func:`cornered`;
    ``parts`` one ``(V, P, pinned, first, corners, owner)`` per corner: ``corners`` the planned corners
    it holds, ``owner`` its programmed block), or None where there are none. An arc fillet is
    tangent (within :data:`TANGENT_TURN`) to the blocks either side: an arc that meets a corner
    shares its window with that corner's dwell.

    A fillet of sweep ``theta`` becomes the ``n`` corners of the polygon of its tangents at ``i
    theta / n`` (``i = 0..n``): corner ``i`` lies ``R (1 / cos(theta / 2n) - 1)`` outside the arc
    point ``P_i`` at ``(i - 1/2) theta / n``, and the checked path splits the arc at the ``P_i``.
    ``n`` is the least that keeps that offset within :data:`CORNER_OFFSET` tolerances and each
    corner's turn ``theta / n`` within :data:`CORNER_TURN` (a half circle: two corners), plus
    ``extra`` ``(M,)`` (a search's spent fillets get one more corner); a fillet that would need
    more than :data:`CORNERS_MAX` stays as chords."""
    arc = tp.is_arc & (tp.lengths <= SHORT_REACH * feed * Td)
    arc[[0, -1]] = False  # the output rests on the path's ends: no corner to round there
    turn = tp.turning_angles()
    arc[1:] &= turn <= TANGENT_TURN
    arc[:-1] &= turn <= TANGENT_TURN
    k = np.flatnonzero(arc)
    theta, R = tp.sweeps[k], tp.radii[k]
    n = _corner_count(theta, R, tol[k]) + extra[k]
    geo = []
    for kj, th, nj in zip(k.tolist(), theta.tolist(), n.tolist()):
        if nj > CORNERS_MAX:
            continue
        t = th * np.arange(nj + 1) / nj  # the tangent points
        T = tp.arc_points(np.full(nj + 1, kj), t)
        d = tp.arc_derivatives(np.full(nj + 1, kj), t, 1)
        d = d / np.linalg.norm(d, axis=1, keepdims=True)
        V, ok = _corner_points(T[:-1], d[:-1], T[1:], d[1:])
        if ok.all():
            geo.append((kj, th, nj, V, tp.arc_points(np.full(nj, kj), th * (np.arange(nj) + 0.5) / nj)))
    if not geo:
        return None
    arc = np.zeros(tp.n_blocks, dtype=bool)
    arc[[g[0] for g in geo]] = True
    _, checked, owner = chorded(tp, tol)  # the other arcs' chords stay
    points, sweeps = checked.ends, checked.sweeps
    last = np.r_[owner[1:] != owner[:-1], True]
    stay = ~arc[owner] | last  # an arc fillet keeps its end point; its corners go in before it
    points, owner, sweeps = points[stay], owner[stay], sweeps[stay].copy()
    at = np.flatnonzero(arc[owner])  # the fillets' end points, in path order (as geo)
    counts = np.array([g[2] for g in geo])
    sweeps[at] = [g[1] / (2 * g[2]) for g in geo]  # the last piece: P_n to the end
    where = np.repeat(at, counts)
    plan_pts = np.insert(points, where, np.concatenate([g[3] for g in geo]), axis=0)
    check_pts = np.insert(points, where, np.concatenate([g[4] for g in geo]), axis=0)
    owner = np.insert(owner, where, np.repeat(owner[at], counts))
    sweeps = np.insert(sweeps, where, np.concatenate([[g[1] / (2 * g[2])] + [g[1] / g[2]] * (g[2] - 1) for g in geo]))
    planned = ToolPath.from_polyline(Polyline(np.vstack([tp.start[None], plan_pts])))
    checked = ToolPath(tp.start, check_pts, tp.centers[owner], tp.normals[owner], sweeps, tp.axes)
    parts = []
    before = np.concatenate([[0], np.cumsum(counts)[:-1]])
    for (kj, _, nj, V, P), a, b0 in zip(geo, at.tolist(), before.tolist()):
        pinned = np.vstack([V, tp.starts[kj][None], tp.ends[kj][None]])
        for i in range(nj):
            first = a + b0 + i  # the planned block that ends at corner i
            c = np.array([first] + ([first - 1] if i == 0 else []) + ([first + 1] if i == nj - 1 else []))
            parts.append((V[i], P[i], pinned if i == 0 else np.zeros((0, pinned.shape[1])), first,
                          c[(c >= 0) & (c < planned.n_blocks - 1)], kj))
    return planned, checked, owner, parts


def _chord_fillets(planned: ToolPath, checked: ToolPath, owner: np.ndarray, feed: np.ndarray, tol: np.ndarray,
                   Td: float, extra: np.ndarray):
    """The chord fillets of ``planned``'s lines as corners: ``(planned with their vertices moved,
    parts)`` (as :func:`_arc_fillets`'), or None where there are none; ``extra`` ``(M,)`` as
    :func:`cornered`'s.

    A chord fillet is a run of two or more consecutive short blocks (each no longer than
    :data:`CHORD_REACH`, all together than :data:`SHORT_REACH` times the reach at their feed;
    ``feed`` and ``tol`` per programmed and planned block, ``owner`` maps between them), lines in
    ``checked`` as in ``planned`` (not an arc's chords, not an arc fillet's pieces), between two
    such lines longer than the run and than :data:`FILLET_RATIO` times its longest chord, that
    turns one way at every vertex (its turn the sum of theirs). As an arc fillet
    (:func:`_arc_fillets`, its radius read as the run's length over its turn) it becomes the
    polygon of ``n`` tangents, here the lines through the points at ``i / n`` of its length along
    the chord there (the lines either side at its ends); the run's inner vertex nearest each
    corner moves onto it, the others onto the polygon's sides in proportion to their arc length.
    Not where two corners would take one vertex (too few chords)."""
    B = planned.n_blocks
    if B < 4 or planned.dim < 2:
        return None
    reach = SHORT_REACH * feed[owner] * Td
    lengths = planned.lengths
    line = ~checked.is_arc  # programmed lines: not an arc's chords, not an arc fillet's pieces
    short = line & (lengths <= CHORD_REACH * reach)
    # runs of short blocks: [s, e) block ranges, bounded by blocks that are not short
    edge = np.diff(np.r_[0, short.astype(np.int8), 0])
    starts, stops = np.flatnonzero(edge == 1), np.flatnonzero(edge == -1)
    pts = np.vstack([planned.start[None], planned.ends])
    out, parts = pts.copy(), []
    chords = np.diff(pts, axis=0)
    unit = chords / np.linalg.norm(chords, axis=1, keepdims=True)
    for s, e in zip(starts, stops):
        if e - s < 2 or s == 0 or e == B:
            continue
        run = float(np.sum(lengths[s:e]))
        bound = max(run, FILLET_RATIO * float(lengths[s:e].max()))  # the blocks either side are longer
        if run > float(np.min(reach[s:e])) or min(lengths[s - 1], lengths[e]) <= bound or not (line[s - 1] and line[e]):
            continue
        u, w = unit[s - 1], unit[e]
        if not _turns_one_way(unit[s - 1:e + 1]):
            continue
        # its turn: the sum of its vertices' (one way), more than pi where it turns back on itself
        turn = float(np.sum(np.arccos(np.clip(np.sum(unit[s - 1:e] * unit[s:e + 1], axis=1), -1.0, 1.0))))
        # as an arc's: the tangent polygon of the run (its radius read as length over turn)
        n = int(_corner_count(turn, run / max(turn, 1e-12), tol[s])) + int(extra[owner[s]])
        if n > CORNERS_MAX:
            continue
        along = np.r_[0.0, np.cumsum(lengths[s:e])]  # arc length of vertices s..e from S
        t = run * np.arange(n + 1) / n  # the tangent points, by arc length
        j = np.clip(np.searchsorted(along, t, side="right") - 1, 0, e - s - 1)  # the chord holding each
        T = pts[s + j] + (t - along[j])[:, None] * unit[s + j]
        d = unit[s + j]
        d[0], d[-1] = u, w  # at the run's ends: the lines either side
        T[-1] = pts[e]
        V, ok = _corner_points(T[:-1], d[:-1], T[1:], d[1:])
        if not ok.all():
            continue
        m = np.array([s + 1 + int(np.argmin(np.linalg.norm(pts[s + 1:e] - v, axis=1))) for v in V])
        if np.any(np.diff(m) <= 0):
            continue  # two corners on one vertex: too few chords for this many
        knots = np.r_[s, m, e]  # S, the vertices moved onto the corners, E
        poly = np.vstack([pts[s], V, pts[e]])
        for a0, a1, p0, p1 in zip(knots[:-1], knots[1:], poly[:-1], poly[1:]):
            f = (along[a0 - s:a1 - s + 1] - along[a0 - s]) / (along[a1 - s] - along[a0 - s])
            out[a0:a1 + 1] = p0 + f[:, None] * (p1 - p0)
        # each corner of the run (its vertices s..e are corners s - 1 .. e - 1) to the nearest moved corner
        nearest = np.argmin(np.abs(along[:, None] - along[m - s][None, :]), axis=1)
        for i in range(n):
            parts.append((V[i], pts[m[i]], out[s:e + 1].copy() if i == 0 else np.zeros((0, out.shape[1])),
                          int(m[i]) - 1, np.arange(s - 1, e)[nearest == i], owner[s]))
    if not parts:
        return None
    return ToolPath.from_polyline(Polyline(out)), parts


def _turns_one_way(units: np.ndarray) -> bool:
    """Whether the unit directions ``units`` ``(k + 1, d)`` of consecutive blocks turn the same way
    at each of their ``k`` vertices (about one axis, in 3-D the sum of their turns' axes: a run
    that turns back on itself has first and last directions opposite)."""
    a, b = units[:-1], units[1:]
    if units.shape[1] == 2:
        z = a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0]
        return bool(np.all(z > 0) or np.all(z < 0))
    turns = np.cross(a, b)
    axis = np.sum(turns, axis=0)
    return bool(np.linalg.norm(axis) > 1e-12 and np.all(turns @ axis > 0))


def planned_tolerance(tol: np.ndarray, g: np.ndarray, fillets: Fillets | None, h: np.ndarray | None) -> np.ndarray:
    """``(B,)`` the tolerance [mm] a round plans its timing at: ``g tol`` on every planned block
    (``tol``, ``g`` ``(B,)``), and on the two planned blocks either side of a fillet's corner
    (``fillets``, :func:`cornered`) ``|V - P| + (2 h - 1) tol`` (at least 0; ``h`` ``(n,)`` in
    ``[0, 1]``): eq 13/14 rounds the corner ``V`` ``tol`` outside ``P`` at ``h = 1``, through it at
    ``1/2``, ``tol`` inside at 0."""
    out = tol * g
    if fillets is None:
        return out
    x = np.maximum(fillets.offset + (2.0 * h - 1.0) * tol[fillets.first], 0.0)
    held = np.full(out.shape, -np.inf)  # a block between two corners of one arc: the larger (each corner its own)
    np.maximum.at(held, fillets.first, x)
    np.maximum.at(held, fillets.first + 1, x)
    return np.where(np.isfinite(held), held, out)


def bisect_rounding(position, corner_times: np.ndarray, delays: np.ndarray, fillets: Fillets, which: np.ndarray,
                    h: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> None:
    """One bisection step of the rounding ``h`` of each fillet in ``which`` (in place, with its
    bracket ``[lo, hi]``): up where the output's point nearest the fillet's ``P`` lies between ``P``
    and the corner ``V`` (rounded too little), down where it lies beyond ``P`` (cut too much).
    ``position``: the plan's profile (a ``NumpyPiecewise``), ``corner_times`` ``(B - 1,)`` [s] its
    corner instants, ``delays`` [s]."""
    centre = corner_times[fillets.first[which]]
    P = fillets.splits[which]
    q = position(nearest_instants(position, P, centre, 0.5 * float(np.sum(delays))))
    outside = np.linalg.norm(q - fillets.corners[which], axis=1) < fillets.offset[which]
    lo[which] = np.where(outside, h[which], lo[which])
    hi[which] = np.where(outside, hi[which], h[which])
    h[which] = 0.5 * (lo[which] + hi[which])
