"""What the path check's samples prove between them: the distance to the path on each interval
between two consecutive samples, bounded from the samples' own distances to the nearby blocks
(used by ``_fir_verify._scan``, the path check of ``plan_fir`` and of the mirror).

A sampled check sees the distance ``d(t)`` from the output to the path only at its samples. Where
``d`` is smooth it can rise above the larger of two samples ``h`` apart by the curvature term
``K h^2 / 8``; where the nearest part of the path changes between them (the medial axis of the
path: the bisector inside a corner, an arc's end, near an arc's centre) ``d`` has a peak, a kink,
that rises to first order in ``h``. Measured before this check (``plan_fir``, 1 ms samples, 240
random filleted contours of ``tests/fuzz/test_fuzz_fir_fillets.py``): 6 plans broke eps between
samples, by up to 8.8 % (a 95 deg corner filleted at R 84 um = eps, where the output passes 11 um
from the fillet's centre), while the check read eps at most.

**The bound.** ``d = min_f f`` over the *features* of the blocks around the two samples: each line
segment, each arc's two end points, and an arc's body (the distance to its circle) where the
whole interval lies inside its sweep. Each feature is *semiconvex* along the motion, ``-f'' <=
K_f``, so on the interval ``f(s) <= l_f(s) + K_f h^2 / 8``, ``l_f`` the straight interpolation of
its two sample values (``s`` in ``[0, 1]``), and ``d(s) <= U = max_s min_f (l_f(s) + K_f h^2 /
8)``. ``U`` is exact to ``O(h^2)`` at a kink between two straight features, where the samples
alone miss it to ``O(h)``. An arc's body counts only where the ball of radius ``|v| h`` around a
sample (which holds the whole interval) lies inside the sweep's wedge, away from the axis.

The curvature terms, with ``V``, ``A``, ``J`` the bounds of ``|v|``, ``|a|``, ``|j|`` over the
profile pieces that meet the interval (:func:`derivative_bound`):

- a segment and a point are convex sets, so their distance is convex in the point and ``-f'' <=
  A``. Where the interval projects inside the segment its distance is the line's, whose ``-f''``
  is at most the acceleration across the line, ``|a_perp|``: at most its larger value at the two
  samples plus ``J h / 2``.
- an arc's body ``f = |(r - R, z)|`` (``r`` the distance from the axis, ``z`` along it) is a norm of
  ``(r - R, z)``, so ``-f'' <= |r''| + |z''|``, ``z'' = a . n``; ``r'' = (|v_in|^2 - r'^2 + w . a_in)
  / r`` in the arc's plane. Coarsely ``|r''| <= A + V^2 / rho`` (``rho`` the least ``r`` over the
  interval); finely its larger value at the two samples plus ``h / 2`` times ``|r'''| <= J + 6 A V /
  rho + 3 V^3 / rho^2`` (from ``r''' = (3 v . a + w . j) / r - 3 r' r'' / r``), which is small where
  the motion is nearly circular (an arc at its eq 8 feed: ``r'' = 0``, where the coarse term is
  ``V^2 / rho``). A spiral's and a helix's radius and axial offset change with the angle: their
  slopes times ``|phi''| <= (A + 2 V^2 / rho) / rho`` are added.

The coarse terms are tried first (no motion evaluated); the fine ones where those leave the
interval unproven.

**Refinement.** Where ``U`` is above the limit and neither sample is, the interval is cut into
``n`` equal parts (``n`` from ``K`` and the room the limit leaves above the samples, and at least
1, 4, 16 in the three rounds, :data:`SPLITS`) and sampled at its bound's peak as well (a kink's);
the new samples are checked as any other (a violation there is a real one) and their intervals
bounded in turn. An interval the bound still cannot prove after the three rounds is left to its
samples (at most ``check_period / 64`` apart there; counted, :attr:`Certifier.unproven`): where the
bound is loose rather than the distance high. That happens where a sample's nearest feature is
none of the blocks' whole (an interval that crosses the joint of two arcs of one circle, each
arc's body cut off at its end: a ramp-cut arc at eps 0.1 um read 1.0-1.8 eps there against a
sampled 0.77 eps), and charging such bounds would slow a plan for nothing.

What it does not cover: an interval whose bound needs a block that neither sample's three
blocks hold is bounded by the blocks both hold (a valid bound, looser); a sample above the
three-block distance's limit that ``ToolPath.distance_bound`` then finds within it (a crowded path:
another pass nearer) leaves its two intervals unbounded; the blocks of tolerance 0 (exact stops,
whose output runs on the path) keep their samples alone.
"""

from __future__ import annotations

import math

import numba
import numpy as np

from research.interpolators._fir_kernels import _OPTIONS, VERIFY_ATOL, VERIFY_RTOL
from research.interpolators._fir_verify_kernels import segment_distance2

#: share of its tolerance by which ``plan_fir``'s output may exceed it between two samples (every
#: sample keeps the tolerance itself): the share the mirror's check allows (``_fir_mirror_check.
#: SAMPLE_MARGIN``, swept there) and the fuzz tests check the sampled trajectories to. Without it
#: an arc at its eq 8 feed, whose output keeps a constant distance of eps from it, could never be
#: proven: any curvature term ``K h^2 / 8 > 0`` lies above eps
BETWEEN_RTOL = 1e-3

#: equal parts an interval is cut into at least, in each round of the refinement
#: (:func:`split_fractions`; its bound's peak is sampled as well): the first round tries the peak
#: alone (a kink between two straight features: its sample settles the interval); where the bound
#: stays above the limit, a feature is far from straight (a segment's end passed close by, whose
#: distance is convex and lies well below its chord) and equal parts follow
SPLITS = (1, 4, 16)
#: most parts an interval is cut into at once (the curvature term's count, :func:`split_fractions`)
SPLIT = 16
#: intervals refined at once (:class:`Certifier`): at most ``BATCH * SPLIT`` new samples in memory
BATCH = 1 << 10


def derivative_bound(position, order: int) -> np.ndarray:
    """``(P,)`` bound on ``|d^order q / dt^order|`` over each piece of ``position`` (a
    ``NumpyPiecewise`` in local coefficients): ``sum_m m! / (m - order)! |c_m| dt^(m - order)`` per
    axis, ``dt`` the piece's length, then the norm over the axes [mm/s^order]."""
    c = np.abs(position.coeffs)
    m = np.arange(c.shape[1])
    falling = np.ones(m.size)
    for j in range(order):
        falling = falling * (m - j)
    dt = np.diff(position.breaks)
    weight = np.where(m >= order, falling, 0.0)[None, :] * dt[:, None] ** np.maximum(m - order, 0)[None, :]
    return np.linalg.norm(np.einsum("km,kma->ka", weight, c), axis=1)


class PathFeatures:
    """The path's blocks as the features of the bound (module docstring), in contiguous arrays:
    segment start and vector of every block ``(M, d)``, arc flags and rows, and the arc geometry
    of ``ToolPath`` (centre, axis, in-plane frame, radii, axial offsets, sweep; empty without arcs)."""

    __slots__ = ("start", "vec", "inv", "is_arc", "arc_row", "geo")

    def __init__(self, path, segments):
        self.start, self.vec, self.inv = segments
        self.is_arc = np.ascontiguousarray(path.is_arc)
        self.arc_row = np.ascontiguousarray(path._cache["arc_row"])
        if self.is_arc.any():
            self.geo = path._geo_rows()
        else:
            z3, z1 = np.zeros((0, 3)), np.zeros(0)
            self.geo = (z3, z3, z3, z3, z1, z1, z1, z1, z1)


def interval_bounds(t, q, block, d2, tol, kept, rel, extra, span, breaks, coeffs, speed, accel, jerk,
                    features: PathFeatures):
    """``U`` of the module docstring for the intervals between consecutive samples ``i, i + 1``.

    Args:
        t, q, block: ``(N,)`` sample times [s], points ``(N, A)`` [mm] and the block each window
            is centred on; d2: ``(N, 3)`` squared distances [mm^2] to the blocks ``block - 1 ..
            block + 1`` (clipped): a sample's distance is the root of the least, and they are the
            segment features where those blocks are lines.
        tol, kept: ``(N,)`` each sample's tolerance [mm] and whether its key is checked; its limit
            is ``verified_bound(tol) + extra`` [mm] (``inf`` where not kept), an interval's the
            smaller of its samples' plus ``rel`` of their tolerance.
        span: longest interval bounded [s] (longer ones are thinned steady spans: not bounded).
        breaks, coeffs: ``(P + 1,)`` and ``(P, D, A)`` the profile in local coefficients;
            speed, accel, jerk: ``(P,)`` its ``|v|`` [mm/s], ``|a|`` [mm/s^2] and ``|j|``
            [mm/s^3] bounds per piece (:func:`derivative_bound`), filled in place where first
            needed (negative: not yet).

    Returns:
        ``(U (N - 1,), K (N - 1,), s (N - 1,))``: ``U`` is ``-inf`` where the interval is proven
        within the smaller limit of its samples (or not bounded: longer than ``span``, or a sample
        above its limit), else the bound; ``K`` [mm/s^2] the largest curvature term there and
        ``s`` in ``[0, 1]`` where the bound peaks."""
    return _interval_bounds(t, q, block, d2, tol, kept, rel, extra, span, breaks, coeffs, speed, accel, jerk,
                            features.start, features.vec, features.inv, features.is_arc, features.arc_row,
                            *features.geo)


def split_fractions(h, K, S, top, limit, least: int = 1):
    """Where to sample each interval anew (module docstring, "Refinement"), as fractions of it:
    at the peak of its bound ``S`` (a kink, where the bound exceeds the samples to first order)
    and at ``j / n``, ``j = 1 .. n - 1``, with ``n`` enough that the curvature term ``K (h / n)^2 /
    8`` fits in half the room the limit leaves above the larger sample ``top`` [mm] (at most
    :data:`SPLIT`), and at least ``least``. Returns ``(interval of each new sample, its fraction)``,
    sorted by both; a peak at an end of its interval is left out."""
    room = np.maximum(limit - top, 0.0)
    with np.errstate(divide="ignore", invalid="ignore"):
        n = np.ceil(h * np.sqrt(K / (4.0 * room)))
    n = np.maximum(np.clip(np.nan_to_num(n, nan=SPLIT, posinf=SPLIT), 1, SPLIT), least).astype(np.int64)
    inner = n - 1
    group = np.repeat(np.arange(n.size), inner)
    frac = (np.arange(inner.sum()) - np.repeat(np.cumsum(inner) - inner, inner) + 1) / n[group]
    peak = (S > 0.0) & (S < 1.0)
    group = np.concatenate([group, np.flatnonzero(peak)])
    frac = np.concatenate([frac, S[peak]])
    order = np.lexsort((frac, group))
    return group[order], frac[order]


@numba.njit(**_OPTIONS)
def _point_distance(q, i, start, vec, b, at_end):
    acc = 0.0
    for a in range(q.shape[1]):
        r = q[i, a] - start[b, a] - (vec[b, a] if at_end else 0.0)
        acc += r * r
    return math.sqrt(acc)


@numba.njit(**_OPTIONS)
def _arc_frame(q, i, row, c, n, e1, e2):
    """``(x, y, z)`` of sample ``i`` in the frame of arc ``row``: along ``e1``, ``e2`` from its
    centre and along its axis ``n`` (a sample of two axes at ``z = 0``)."""
    w0, w1, w2 = q[i, 0] - c[row, 0], q[i, 1] - c[row, 1], (q[i, 2] if q.shape[1] > 2 else 0.0) - c[row, 2]
    return (w0 * e1[row, 0] + w1 * e1[row, 1] + w2 * e1[row, 2], w0 * e2[row, 0] + w1 * e2[row, 1] + w2 * e2[row, 2],
            w0 * n[row, 0] + w1 * n[row, 1] + w2 * n[row, 2])


@numba.njit(**_OPTIONS)
def _along(v, row, e):
    """``v . e[row]`` of a ``(3,)`` vector."""
    return v[0] * e[row, 0] + v[1] * e[row, 1] + v[2] * e[row, 2]


@numba.njit(**_OPTIONS)
def _inside_sweep(q, i, row, reach, c, n, e1, e2, sweep):
    """The radius of sample ``i`` from the axis of arc ``row`` where the ball of radius ``reach``
    around it lies inside the arc's sweep (a wedge of at most pi, two half-planes: at least
    ``reach`` inside each) and away from the axis; 0 elsewhere, and for sweeps beyond pi
    (:func:`_arc_body` decides those)."""
    Phi = sweep[row]
    if Phi > math.pi:
        return 0.0
    x, y, _ = _arc_frame(q, i, row, c, n, e1, e2)
    if y < reach or x * math.sin(Phi) - y * math.cos(Phi) < reach:
        return 0.0
    r = math.sqrt(x * x + y * y)
    return r if r > reach else 0.0


@numba.njit(**_OPTIONS)
def _arc_body(q, i, row, reach, c, n, e1, e2, r0, r1, a0, a1, sweep):
    """``(distance to the arc's circle through its nearest turn, radius from the axis)`` of sample
    ``i``, or ``(inf, 0)`` where the ball of radius ``reach`` around it leaves the sweep's wedge or
    meets the axis (the body then is no feature of the interval)."""
    x, y, z = _arc_frame(q, i, row, c, n, e1, e2)
    r = math.sqrt(x * x + y * y)
    if r <= reach:
        return math.inf, 0.0
    phi = math.atan2(y, x)
    if phi < 0.0:
        phi += 2.0 * math.pi
    Phi = sweep[row]
    # the turn whose axial offset is nearest (a helix of several turns), within the sweep
    best, best_phi = math.inf, phi
    m = 0
    while phi + 2.0 * math.pi * m <= Phi + 1e-12:
        p = phi + 2.0 * math.pi * m
        gap = abs(z - (a0[row] + (a1[row] - a0[row]) * p / Phi))
        if gap < best:
            best, best_phi = gap, p
        m += 1
    if best == math.inf:
        return math.inf, 0.0
    delta = math.asin(min(1.0, reach / r))
    full = Phi >= 2.0 * math.pi * (1.0 - 1e-12) and r0[row] == r1[row] and a0[row] == a1[row]
    if not full and (best_phi - delta < 0.0 or best_phi + delta > Phi):
        return math.inf, 0.0
    rad = r0[row] + (r1[row] - r0[row]) * best_phi / Phi
    ax = a0[row] + (a1[row] - a0[row]) * best_phi / Phi
    cs, sn = math.cos(best_phi), math.sin(best_phi)
    acc = 0.0
    for a in range(3):
        p = c[row, a] + ax * n[row, a] + rad * (cs * e1[row, a] + sn * e2[row, a])
        qa = q[i, a] if a < q.shape[1] else 0.0
        acc += (qa - p) * (qa - p)
    return math.sqrt(acc), r


@numba.njit(**_OPTIONS)
def _fill_bounds(coeffs, breaks, speed, accel, jerk, k):
    """The ``|v|``, ``|a|`` and ``|j|`` bounds of piece ``k`` (:func:`derivative_bound`'s sums, by
    Horner's rule in the piece's length) into ``speed[k]``, ``accel[k]`` and ``jerk[k]``."""
    D, A = coeffs.shape[1], coeffs.shape[2]
    dt = breaks[k + 1] - breaks[k]
    v2, a2, j2 = 0.0, 0.0, 0.0
    for a in range(A):
        v, acc, jk = 0.0, 0.0, 0.0
        for m in range(D - 1, 0, -1):
            c = abs(coeffs[k, m, a])
            v = v * dt + m * c
            if m >= 2:
                acc = acc * dt + m * (m - 1) * c
            if m >= 3:
                jk = jk * dt + m * (m - 1) * (m - 2) * c
        v2 += v * v
        a2 += acc * acc
        j2 += jk * jk
    speed[k], accel[k], jerk[k] = math.sqrt(v2), math.sqrt(a2), math.sqrt(j2)


@numba.njit(**_OPTIONS)
def _motion(coeffs, breaks, k, t, v, a):
    """Velocity and acceleration at ``t`` on piece ``k`` into ``v``, ``a`` ``(3,)`` (0 beyond the
    profile's axes)."""
    D, A = coeffs.shape[1], coeffs.shape[2]
    tau = min(max(t - breaks[k], 0.0), breaks[k + 1] - breaks[k])
    for x in range(3):
        v[x], a[x] = 0.0, 0.0
    for x in range(A):
        vx, ax = 0.0, 0.0
        for m in range(D - 1, 0, -1):
            vx = vx * tau + m * coeffs[k, m, x]
            if m >= 2:
                ax = ax * tau + m * (m - 1) * coeffs[k, m, x]
        v[x], a[x] = vx, ax


@numba.njit(**_OPTIONS)
def _normal_accel(q, i, a, start, vec, inv, b, reach):
    """``|a|`` across line block ``b`` (its part normal to the line) at sample ``i``, where the
    ball of radius ``reach`` around the sample projects inside the segment (its distance there is
    the line's, whose ``-d''`` is at most that); -1 elsewhere."""
    A = q.shape[1]
    dot = 0.0
    for x in range(A):
        dot += (q[i, x] - start[b, x]) * vec[b, x]
    u = dot * inv[b]
    margin = reach * math.sqrt(inv[b])
    if inv[b] <= 0.0 or u < margin or u > 1.0 - margin:
        return -1.0
    along = 0.0
    for x in range(A):
        along += a[x] * vec[b, x]
    along *= inv[b]
    acc = 0.0
    for x in range(A):
        r = a[x] - along * vec[b, x]
        acc += r * r
    return math.sqrt(acc)


@numba.njit(**_OPTIONS)
def _radial_curvature(q, i, v, a, row, c, n, e1, e2):
    """``(|r''|, |a . n|)`` at sample ``i`` about the axis of arc ``row``: the second derivative of
    the sample's radius from the axis and the acceleration along the axis (the two parts of the
    arc body's ``-d''``)."""
    x, y, _ = _arc_frame(q, i, row, c, n, e1, e2)
    vx, vy, ax, ay, an = _along(v, row, e1), _along(v, row, e2), _along(a, row, e1), _along(a, row, e2), _along(a, row, n)
    r = math.sqrt(x * x + y * y)
    r1 = (x * vx + y * vy) / r
    return abs((vx * vx + vy * vy + x * ax + y * ay - r1 * r1) / r), abs(an)


@numba.njit(**_OPTIONS)
def _covered(fa, fb, fk, F, L, h):
    """Whether every ``s`` in ``[0, 1]`` has a feature ``f < F`` with ``l_f(s) + K_f h^2 / 8 <= L``:
    each feature holds on ``[0, x]`` (rising), ``[x, 1]`` (falling), all or nothing of it."""
    inc, dec = -1.0, 2.0
    for f in range(F):
        room = L - fk[f] * h * h / 8.0
        ina, inb = fa[f] <= room, fb[f] <= room
        if ina and inb:
            return True
        if ina:
            inc = max(inc, (room - fa[f]) / (fb[f] - fa[f]))
        elif inb:
            dec = min(dec, (fa[f] - room) / (fa[f] - fb[f]))
    return inc >= dec


@numba.njit(**_OPTIONS)
def _interval_bounds(t, q, block, d2, tol, kept, rel, extra, span, breaks, coeffs, speed, accel, jerk, start, vec, inv,
                     is_arc, arc_row, c, n, e1, e2, r0, r1, a0, a1, sweep):
    N = t.size
    M = start.shape[0]
    P = speed.size
    U = np.full(max(N - 1, 0), -np.inf)
    Kout = np.zeros(max(N - 1, 0))
    Sout = np.zeros(max(N - 1, 0))
    fa = np.empty(64)
    fb = np.empty(64)
    fk = np.empty(64)
    va, aa, vb, ab = np.zeros(3), np.zeros(3), np.zeros(3), np.zeros(3)
    fblk, frho = np.empty(3, np.int64), np.empty(3)  # the shared blocks' features: block, arc radius less reach
    d, limit = np.empty(N), np.empty(N)
    for i in range(N):
        d[i] = math.sqrt(min(min(d2[i, 0], d2[i, 1]), d2[i, 2]))
        limit[i] = (tol[i] * (1.0 + VERIFY_RTOL) + VERIFY_ATOL) + extra if kept[i] else math.inf
    piece = 0
    for i in range(N - 1):
        h = t[i + 1] - t[i]
        if h <= 0.0 or h > span:
            continue
        if tol[i] <= 0.0 or tol[i + 1] <= 0.0:
            continue  # an exact stop's block (tolerance 0): its output runs on the path, checked by its samples
        if d[i] > limit[i] or d[i + 1] > limit[i + 1]:
            continue  # a violation at a sample: charged there
        # |v| and |a| bounds over the pieces that meet [t_i, t_i+1]
        while piece > 0 and breaks[piece] > t[i]:
            piece -= 1
        while piece < P - 1 and breaks[piece + 1] <= t[i]:
            piece += 1
        V, A, J = 0.0, 0.0, 0.0
        k = piece
        while True:  # the bounds of each piece computed where first needed (negative: not yet)
            if speed[k] < 0.0:
                _fill_bounds(coeffs, breaks, speed, accel, jerk, k)
            V, A, J = max(V, speed[k]), max(A, accel[k]), max(J, jerk[k])
            if k == P - 1 or breaks[k + 1] >= t[i + 1]:
                break
            k += 1
        L = min(limit[i] + rel * tol[i], limit[i + 1] + rel * tol[i + 1])
        if 0.5 * (d[i] + d[i + 1] + V * h) <= L:
            continue  # 1-Lipschitz in the point, which moves at most V h
        reach = V * h
        lo = max(min(block[i], block[i + 1]) - 1, 0)
        hi = min(max(block[i], block[i + 1]) + 1, M - 1)
        # first the blocks the two samples' three-block distances share (no distance computed):
        # a line's segment, an arc's body where the interval lies inside its sweep (its distance
        # there is the body's, :func:`_inside_sweep`; a spiral's and a helix's with the circle's
        # curvature term, as in :func:`_arc_body`)
        F, ka, kb = 0, block[i], block[i + 1]
        for ca in range(3):
            ba = min(max(ka - 1 + ca, 0), M - 1)
            cb = ba - (kb - 1)
            if not (0 <= cb <= 2 and min(max(kb - 1 + cb, 0), M - 1) == ba) or (ca and ba == min(max(ka - 2 + ca, 0), M - 1)):
                continue  # not shared, or a block clipped twice
            if not is_arc[ba]:
                fa[F], fb[F], fk[F], fblk[F], frho[F] = math.sqrt(d2[i, ca]), math.sqrt(d2[i + 1, cb]), A, ba, 0.0
                F += 1
                continue
            row = arc_row[ba]
            ra = _inside_sweep(q, i, row, reach, c, n, e1, e2, sweep)
            rb = _inside_sweep(q, i + 1, row, reach, c, n, e1, e2, sweep) if ra > 0.0 else 0.0
            if rb > 0.0:
                rho = min(ra, rb) - reach
                fa[F], fb[F], fk[F], fblk[F], frho[F] = math.sqrt(d2[i, ca]), math.sqrt(d2[i + 1, cb]), A + V * V / rho, ba, rho
                F += 1
        if F and _covered(fa, fb, fk, F, L, h):
            continue
        if F:  # the curvature terms from the motion at the two samples (module docstring), then again
            _motion(coeffs, breaks, piece, t[i], va, aa)
            _motion(coeffs, breaks, k, t[i + 1], vb, ab)
            for f in range(F):
                ba = fblk[f]
                if not is_arc[ba]:  # -d'' <= |a| across the line where it is the segment's distance
                    na = _normal_accel(q, i, aa, start, vec, inv, ba, reach)
                    nb_ = _normal_accel(q, i + 1, ab, start, vec, inv, ba, reach) if na >= 0.0 else -1.0
                    if nb_ >= 0.0:
                        fk[f] = min(fk[f], max(na, nb_) + 0.5 * J * h)
                    continue
                # an arc's body: -d'' <= |r''| + |a . n| + (the spiral's and helix's slopes) |phi''|
                row, rho = arc_row[ba], frho[f]
                rr_a, an_a = _radial_curvature(q, i, va, aa, row, c, n, e1, e2)
                rr_b, an_b = _radial_curvature(q, i + 1, vb, ab, row, c, n, e1, e2)
                r3 = J + 6.0 * A * V / rho + 3.0 * V ** 3 / rho ** 2  # bounds the third derivative of r
                slope = (abs(r1[row] - r0[row]) + abs(a1[row] - a0[row])) / sweep[row]
                fk[f] = min(fk[f], max(rr_a, rr_b) + 0.5 * r3 * h + max(an_a, an_b) + 0.5 * J * h
                            + slope * (A + 2.0 * V * V / rho) / rho)
        if F and _covered(fa, fb, fk, F, L, h):
            continue
        F = 0
        for b in range(lo, hi + 1):
            if F + 3 > fa.size:
                fa2, fb2, fk2 = np.empty(2 * fa.size), np.empty(2 * fa.size), np.empty(2 * fa.size)
                fa2[:F], fb2[:F], fk2[:F] = fa[:F], fb[:F], fk[:F]
                fa, fb, fk = fa2, fb2, fk2
            if not is_arc[b]:
                fa[F] = math.sqrt(segment_distance2(q, i, start, vec, inv, b, q.shape[1]))
                fb[F], fk[F] = math.sqrt(segment_distance2(q, i + 1, start, vec, inv, b, q.shape[1])), A
                F += 1
                continue
            for at_end in (False, True):
                fa[F], fb[F], fk[F] = _point_distance(q, i, start, vec, b, at_end), _point_distance(q, i + 1, start, vec, b, at_end), A
                F += 1
            row = arc_row[b]
            ba, ra = _arc_body(q, i, row, reach, c, n, e1, e2, r0, r1, a0, a1, sweep)
            bb, rb = _arc_body(q, i + 1, row, reach, c, n, e1, e2, r0, r1, a0, a1, sweep)
            if ba < math.inf and bb < math.inf:
                fa[F], fb[F], fk[F] = ba, bb, A + V * V / (min(ra, rb) - reach)
                F += 1
        if _covered(fa, fb, fk, F, L, h):
            continue
        Kmax = 0.0
        for f in range(F):
            Kmax = max(Kmax, fk[f])
        # the bound itself: the largest of the concave min over s, by golden-section search
        lo_s, hi_s = 0.0, 1.0
        g = 0.6180339887498949
        for _ in range(80):
            s1, s2 = hi_s - g * (hi_s - lo_s), lo_s + g * (hi_s - lo_s)
            v1, v2 = math.inf, math.inf
            for f in range(F):
                e = fk[f] * h * h / 8.0
                v1 = min(v1, fa[f] + (fb[f] - fa[f]) * s1 + e)
                v2 = min(v2, fa[f] + (fb[f] - fa[f]) * s2 + e)
            if v1 < v2:
                lo_s = s1
            else:
                hi_s = s2
        best, at = -math.inf, 0.5
        for s in (0.0, 1.0, lo_s, hi_s):
            v = math.inf
            for f in range(F):
                v = min(v, fa[f] + (fb[f] - fa[f]) * s + fk[f] * h * h / 8.0)
            if v > best:
                best, at = v, s
        U[i] = max(best, L * (1.0 + 1e-12)) if F else math.inf
        Kout[i], Sout[i] = Kmax, at
    return U, Kout, Sout


class Certifier:
    """The bound of one path check (module docstring): fed the check's grid samples in time order
    (:meth:`add`), it refines the intervals it cannot prove :data:`BATCH` at a time (the memory a
    check holds stays bounded whatever the cycle's length; :meth:`close` refines the rest). Its
    new samples are checked as any other (``evaluate``): a violation found there is charged there.

    Args:
        position: the exact profile (``NumpyPiecewise``); features: :class:`PathFeatures` of the
            checked path; evaluate: ``evaluate(times)`` checks new samples as any other (their
            violations charged there) and returns their fields (as :meth:`add` takes them);
            span: longest interval bounded [s] (the grid's stride; longer ones are thinned steady
            spans); extra: added to every sample's verified bound [mm]: the profile's rounding,
            and the mirror's margin (its samples are held below the tolerance by it, its
            intervals to the tolerance); rel: the share of their tolerance an interval may exceed
            its samples' limits by (:data:`BETWEEN_RTOL` for ``plan_fir``, 0 for the mirror).
    """

    def __init__(self, position, features: PathFeatures, evaluate, span: float, extra: float = 0.0,
                 rel: float = 0.0):
        self.features, self.evaluate = features, evaluate
        self.span, self.extra, self.rel = float(span), float(extra), float(rel)
        self.breaks, self.coeffs = np.ascontiguousarray(position.breaks), np.ascontiguousarray(position.coeffs)
        self.speed, self.accel, self.jerk = (np.full(self.coeffs.shape[0], -1.0) for _ in range(3))
        self.prev = None  # the last sample of the grid so far (its fields)
        self.pending, self.n_pending = [], 0  # intervals not proven, held until BATCH of them
        self.refined = 0  # samples added by the refinement
        self.unproven = 0  # intervals whose bound stayed above their limit after every round

    def add(self, samples) -> None:
        """Bound the intervals between the grid samples ``samples`` (``(t, q, block, d2, tol, kept)``
        as :func:`interval_bounds` takes them), following the last sample of the previous call, and
        refine those it cannot prove."""
        if self.prev is not None:
            samples = tuple(np.concatenate([a, b]) for a, b in zip(self.prev, samples))
        if samples[0].size == 0:
            return
        self.prev = tuple(a[-1:] for a in samples)
        found = self._unproven(samples, np.ones(samples[0].size - 1, dtype=bool))
        if found is not None:
            self.pending.append(found)
            self.n_pending += found[2].size
            if self.n_pending >= BATCH:
                self.close()

    def close(self) -> None:
        """Refine the intervals held back so far (:meth:`add` holds up to :data:`BATCH`)."""
        if self.pending:
            parts, self.pending, self.n_pending = self.pending, [], 0
            a, b = (tuple(np.concatenate(f) for f in zip(*(p[side] for p in parts))) for side in (0, 1))
            self._refine(0, (a, b) + tuple(np.concatenate([p[k] for p in parts]) for k in (2, 3, 4)))

    def _unproven(self, seq, inside):
        """The intervals of the sample sequence ``seq`` (those where ``inside``) whose bound is above
        their limit: ``(first fields, second fields, U, K, S)``, or None."""
        t, q, block, d2, tol, kept = seq
        U, K, S = interval_bounds(t, np.ascontiguousarray(q), block, np.ascontiguousarray(d2), tol, kept, self.rel,
                                  self.extra, self.span, self.breaks, self.coeffs, self.speed, self.accel,
                                  self.jerk, self.features)
        j = np.flatnonzero((U > -np.inf) & inside)
        if not j.size:
            return None
        return tuple(x[j] for x in seq), tuple(x[j + 1] for x in seq), U[j], K[j], S[j]

    def _refine(self, level: int, found) -> None:
        """Refine the intervals ``found`` (:meth:`_unproven`) from round ``level`` of :data:`SPLITS`
        on, :data:`BATCH` at a time, depth first (module docstring)."""
        if found is None:
            return
        a, b, U, K, S = found
        if level == len(SPLITS):
            self.unproven += U.size
            return
        for lo in range(0, U.size, BATCH):
            part = slice(lo, lo + BATCH)
            a_p, b_p = tuple(x[part] for x in a), tuple(x[part] for x in b)
            h = b_p[0] - a_p[0]
            group, frac = split_fractions(h, K[part], S[part], np.maximum(self._distance(a_p), self._distance(b_p)),
                                          np.minimum(self._limit(a_p), self._limit(b_p)), SPLITS[level])
            new = self.evaluate(a_p[0][group] + h[group] * frac)
            self.refined += group.size
            # each interval's samples in order: its first, the new ones, its last
            inner = np.bincount(group, minlength=h.size)
            size = inner + 2
            start = np.cumsum(size) - size
            slot = np.arange(group.size) - np.repeat(np.cumsum(inner) - inner, inner) + 1
            seq = []
            for k, field in enumerate(a_p):
                out = np.empty((int(size.sum()),) + field.shape[1:], field.dtype)
                out[start] = field
                out[start + size - 1] = b_p[k]
                out[start[group] + slot] = new[k]
                seq.append(out)
            inside = np.ones(int(size.sum()) - 1, dtype=bool)
            inside[(start + size - 1)[:-1]] = False  # from one interval's last sample to the next one's first
            self._refine(level + 1, self._unproven(tuple(seq), inside))

    @staticmethod
    def _distance(s):
        return np.sqrt(s[3].min(axis=1))

    def _limit(self, s):
        return np.where(s[5], s[4] * (1.0 + VERIFY_RTOL + self.rel) + VERIFY_ATOL + self.extra, np.inf)
