"""Compiled (Numba) kernels of the FIR planner: window displacements and their root search (the
look-ahead), the sampled path check, and the corner-distance search (the verification).

The look-ahead of ``fir`` evaluates, for every vertex ``j`` of a chain of short blocks, the windowed
displacement (``_fir_feed`` module docstring)::

    d_j(F) = F sum_i du_i H2(T_d / 2 - |s_i - s_j| / F),   |s_i - s_j| < F T_d / 2,

and finds the largest feed with ``|d_j(F)| <= eps`` by a safeguarded Newton search (its slope
``d d_j / dF`` summed in the same pass). In NumPy both are vectorised over the vertices, which costs
one array pass (and a Python step) per root-search iteration over all active vertices, and a ragged
gather per evaluation. Here each vertex is one scalar loop: its turns are summed in place, its
search runs to its own end. The truncated powers ``(r)_+^(n+1)`` are products (not C ``pow``), and
the Newton search takes 3-5 evaluations per vertex where the false-position search before it took
6-8, so the feeds agree with that search's to its resolution (~1e-9 relative), not bit for bit
(benchmarks/README.md, bench_cam section); ``tests/interpolators/test_fir_kernels.py`` checks the
kernels against slow independent computations.

:func:`chain_feed_decisions` runs the same search only as far as a dwell decision of the
look-ahead's tighter levels needs it (exact decisions), :func:`line_piece_feeds` the line pieces
under the windows' staircase (bit for bit), and :func:`predicted_cycle` a candidate's predicted
cycle time (a bound of the branch and bound) without its piece arrays.

The verification kernels (:func:`sampled_line_distances`, :func:`corner_distances`) evaluate the
exact profile on its NumPy arrays with Horner's rule, as :class:`research.piecewise.NumpyPiecewise`,
and replace per-sample NumPy gathers (path check) and the JAX grid + Newton search
(``_fir_verify``) inside the planner's rounds. Each finds its piece from the last one's index and
is compiled with the profile's row and axis counts as constants for two filters.

Compiled on first use and cached on disk (``cache=True``): the first call of a fresh checkout pays
the compilation (about 16 s for all of them, measured at load 4; the verification kernels'
specialisations add about 8 s, at load 2), later processes load it (0.7 s).
"""

from __future__ import annotations

import math

import numba
import numpy as np

_OPTIONS = dict(cache=True, nogil=True, error_model="numpy")

#: rounding slack of every tolerance check of the planner: an error [mm] passes a tolerance ``eps``
#: when ``<= eps (1 + VERIFY_RTOL) + VERIFY_ATOL`` (1e-9 relative and 1 pm absolute, for the rounding
#: of the exact profile's evaluation; far below any machine's resolution)
VERIFY_RTOL, VERIFY_ATOL = 1e-9, 1e-9


def verified_bound(tolerance):
    """The largest error [mm] that passes ``tolerance`` [mm] (scalar or array), rounding slack included."""
    return tolerance * (1.0 + VERIFY_RTOL) + VERIFY_ATOL


@numba.njit(**_OPTIONS)
def _left_in(a, v, lo, hi):
    """``np.searchsorted(a, v, side="left")`` where the answer is known to lie in ``[lo, hi]``."""
    while lo < hi:
        mid = (lo + hi) >> 1
        if a[mid] < v:
            lo = mid + 1
        else:
            hi = mid
    return lo


@numba.njit(**_OPTIONS)
def _right_in(a, v, lo, hi):
    """``np.searchsorted(a, v, side="right")`` where the answer is known to lie in ``[lo, hi]``."""
    while lo < hi:
        mid = (lo + hi) >> 1
        if a[mid] <= v:
            lo = mid + 1
        else:
            hi = mid
    return lo


@numba.njit(**_OPTIONS)
def _left(a, v):
    """``np.searchsorted(a, v, side="left")``."""
    return _left_in(a, v, 0, a.size)


@numba.njit(**_OPTIONS)
def _right(a, v):
    """``np.searchsorted(a, v, side="right")``."""
    return _right_in(a, v, 0, a.size)


@numba.njit(**_OPTIONS)
def _right_from(a, v, hint):
    """``np.searchsorted(a, v, side="right")`` (the count of entries ``<= v``, unique on a sorted
    array) found from a nearby index ``hint`` by a galloping search: steps of 1, 2, 4, ... away from
    ``hint`` until the answer is bracketed, then a binary search in the bracket. ``O(log distance)``
    for queries that move little along ``a``."""
    n = a.size
    i = min(max(hint, 0), n)
    if i > 0 and a[i - 1] > v:  # the answer is below i
        hi, step = i, 1
        lo = hi - step
        while lo > 0 and a[lo - 1] > v:
            hi = lo
            step *= 2
            lo = max(hi - step, 0)
        lo = max(lo, 0)
    else:  # the answer is at or above i
        lo, step = i, 1
        hi = lo + step
        while hi <= n and a[hi - 1] <= v:
            lo = hi
            step *= 2
            hi = lo + step
        hi = min(hi, n)
    return _right_in(a, v, lo, hi)  # binary search inside the bracket


@numba.njit(**_OPTIONS)
def _ipow(r, m):
    """``r^m`` for an integer ``m >= 0`` by repeated multiplication (``m`` is ``n + 1 - k`` here:
    at most a few factors)."""
    out = 1.0
    for _ in range(m):
        out *= r
    return out


@numba.njit(**_OPTIONS)
def _displacement(s, du, rho, sign, p, norm, prefix, binom, direct, q, F, out, dout):
    """``d_j`` at the re-centred arc length ``q`` for feed ``F`` into ``out`` ``(d,)`` and its
    derivative ``d d_j / dF`` into ``dout`` ``(d,)``: a direct sum over the window's turns when it
    holds at most ``direct`` of them, else the prefix sums (``ChainError.displacement``).

    Direct sum: each turn adds ``du_i norm F sum_r sign_r (rho_r - x_i)_+^p`` with
    ``x_i = |s_i - q| / F``; since ``d x_i / dF = -x_i / F`` its derivative is
    ``du_i norm sum_r sign_r (rho_r - x_i)_+^(p-1) (rho_r - x_i + p x_i)`` (the boundary of the
    window adds nothing: ``(.)_+^p`` is ``C^(p-1)``). Prefix sums: ``d_j = norm F^(1-p) S(F)`` with
    ``S`` a polynomial in ``F rho_r +- q`` whose coefficients are the prefix sums (constant while no
    turn enters or leaves a window, and entering turns add 0 and a zero derivative)."""
    d = du.shape[1]
    for k in range(d):
        out[k] = 0.0
        dout[k] = 0.0
    R = F * np.max(rho)
    first = _right(s, q - R)
    count = _left(s, q + R) - first
    if count <= direct:
        for i in range(first, first + count):
            x = abs(s[i] - q) / F if F > 0 else np.inf
            h = 0.0
            g = 0.0
            for r_i in range(rho.size):
                r = rho[r_i] - x
                if r > 0.0:  # (r)_+^p: a term of 0 adds nothing (skipped, the same sum)
                    r1 = sign[r_i] * _ipow(r, p - 1)
                    h += r1 * r
                    g += r1 * (r + p * x)
            w = h * norm * F
            wd = g * norm
            for k in range(d):
                out[k] += w * du[i, k]
                dout[k] += wd * du[i, k]
        return
    at = _left(s, q)
    for r_i in range(rho.size):
        rr = rho[r_i]
        Rr = F * rr
        b = _left(s, q + Rr)
        a = _right(s, q - Rr)
        right, left = Rr + q, Rr - q
        for m in range(p + 1):
            c = sign[r_i] * binom[m]
            e = p - m
            cr = (-1.0) ** m * _ipow(right, e)
            cl = _ipow(left, e)
            dcr = (-1.0) ** m * e * rr * _ipow(right, e - 1) if e > 0 else 0.0
            dcl = e * rr * _ipow(left, e - 1) if e > 0 else 0.0
            for k in range(d):
                pr = prefix[m, b, k] - prefix[m, at, k]
                pl = prefix[m, at, k] - prefix[m, a, k]
                out[k] += c * (cr * pr + cl * pl)
                dout[k] += c * (dcr * pr + dcl * pl)
    if F > 0:
        scale = _ipow(1.0 / F, p - 1) * norm
        dscale = scale * (1.0 - p) / F
    else:
        scale = dscale = 0.0
    for k in range(d):
        dout[k] = dscale * out[k] + scale * dout[k]
        out[k] *= scale


@numba.njit(**_OPTIONS)
def chain_displacements(s, du, rho, sign, p, norm, prefix, binom, direct, q, F):
    """``(J, d)`` displacements ``d_j`` at re-centred arc lengths ``q`` ``(J,)`` for feeds ``F`` ``(J,)``."""
    out = np.zeros((q.size, du.shape[1]))
    scratch = np.zeros(du.shape[1])
    for j in range(q.size):
        _displacement(s, du, rho, sign, p, norm, prefix, binom, direct, q[j], F[j], out[j], scratch)
    return out


@numba.njit(**_OPTIONS)
def _log_error(s, du, rho, sign, p, norm, prefix, binom, direct, q, F, t, tiny, buf, dbuf):
    """``(g, g')``: ``g = log(max(|d_j(F)|, tiny t) / t)`` and its slope ``d g / d log F =
    F (d_j . d_j') / |d_j|^2`` (NaN where the error is floored: no slope there)."""
    _displacement(s, du, rho, sign, p, norm, prefix, binom, direct, q, F, buf, dbuf)
    acc = 0.0
    dot = 0.0
    for k in range(buf.size):
        acc += buf[k] * buf[k]
        dot += buf[k] * dbuf[k]
    e = math.sqrt(acc)
    if e <= tiny * t:
        return math.log(tiny), np.nan
    return math.log(e / t), F * dot / acc


@numba.njit(**_OPTIONS)
def chain_largest_feeds(s, du, rho, sign, p, norm, prefix, binom, direct, q, hi, tol, e_hi, steps, close, tiny):
    """Largest feed ``<= hi`` with ``|d_j| <= tol`` for every query (``ChainError.largest_feed``).

    Safeguarded Newton in log space: ``g(x) = log(|d_j(e^x)| / tol)``, ``x = log F`` (the error is
    nearly a power of the feed, so ``g`` is nearly linear in ``x``), with its exact slope from
    :func:`_displacement`. The first point is ``F = hi tol / |d_j(hi)|`` (feasible where the error
    grows at least linearly in feed); each step aims at ``g = -close / 2``, the middle of the
    stopping band ``(-close, 0]``, from the last point evaluated. A step that leaves the bracket
    ``[l, h]`` (feasible low end, infeasible high end), or a point without slope, falls back to a
    false-position step in log space with the Illinois modification (Dowell & Jarratt 1971), or to
    bisection while the low end is 0. Steps stay half a resolution inside the bracket.

    Args:
        q: ``(J,)`` re-centred arc lengths; hi, tol, e_hi: ``(J,)`` feed bound, tolerance and
            ``|d_j(hi)|``; steps, close, tiny: the search's resolution exponent, stopping distance
            (log ratio) and error floor (``_fir_feed``'s constants).

    Returns:
        ``(J,)`` feeds [mm/s]: the low end of the bracket when its ``g`` is within ``close`` of 0,
        the bracket is ``2^-steps`` of its start, or after ``2 steps`` evaluations.
    """
    J = q.size
    buf = np.zeros(du.shape[1])
    dbuf = np.zeros(du.shape[1])
    out = np.empty(J)
    none = np.empty(0)
    for j in range(J):
        out[j] = _feed_search(s, du, rho, sign, p, norm, prefix, binom, direct, q[j], hi[j], tol[j], e_hi[j], steps,
                              close, tiny, buf, dbuf, False, 0.0, 0.0, none)
    return out


@numba.njit(**_OPTIONS)
def chain_feed_decisions(s, du, rho, sign, p, norm, prefix, binom, direct, q, hi, tol, e_hi, steps, close, tiny,
                         stretch_cap, Td, costs):
    """:func:`chain_largest_feeds` run only as far as the look-ahead's dwell decisions need it.

    A nested level of ``_fir_lookahead`` reads its window feed ``f`` only through the decisions
    ``cost <= slow_cost(f)`` (``_fir_lookahead._slow_cost``: ``min(f T_d, cap) (1 / f - 1 / hi)``,
    non-increasing in ``f``), one per dwell rule. The search's bracket ``[l, h]`` only shrinks, and
    the feed it would return lies in ``{l} U [l + w / 2, h - w / 2]`` (``w`` its resolution: every
    later point is evaluated there). So once the bracket is wider than ``w`` and no cost lies in
    ``(slow_cost(h), slow_cost(l)]`` (and ``l > 0``: the search may end at 0), every decision at
    the search's own result is the one at ``h``, and ``h`` is returned: the same decisions, exactly
    (the two ends are ``>= w / 2 ~ 7e-12`` relative apart, far above the rounding of
    ``slow_cost``). A query decides at once where every cost is NaN (no decision read).

    Args:
        As :func:`chain_largest_feeds`; stretch_cap: ``(J,)`` the ``cap`` of ``slow_cost`` [mm];
        Td: the window ``T_d`` [s]; costs: ``(J, C)`` dwell costs [s] (NaN: not read).

    Returns:
        ``(J,)`` feeds [mm/s] whose decisions ``cost <= slow_cost(feed)`` are those of the full search.
    """
    J = q.size
    buf = np.zeros(du.shape[1])
    dbuf = np.zeros(du.shape[1])
    out = np.empty(J)
    for j in range(J):
        out[j] = _feed_search(s, du, rho, sign, p, norm, prefix, binom, direct, q[j], hi[j], tol[j], e_hi[j], steps,
                              close, tiny, buf, dbuf, True, stretch_cap[j], Td, costs[j])
    return out


@numba.njit(**_OPTIONS)
def _slow_cost(f, cap, Td, F):
    """``_fir_lookahead._slow_cost`` of one feed (the same operations, so the same rounding)."""
    return min(f * Td, cap) * (1.0 / max(f, 1e-300) - 1.0 / F)


@numba.njit(**_OPTIONS)
def _decided(l, h, F, cap, Td, costs):
    """No cost lies in ``(slow_cost(h), slow_cost(l)]`` (:func:`chain_feed_decisions`); while
    ``l = 0`` only a query without costs is (the search may still end at 0, whose ``slow_cost``
    rounds to 0)."""
    s_h = _slow_cost(h, cap, Td, F)
    s_l = _slow_cost(l, cap, Td, F)
    for c in costs:
        if c == c and (l == 0.0 or s_h < c <= s_l):
            return False
    return True


@numba.njit(**_OPTIONS)
def _feed_search(s, du, rho, sign, p, norm, prefix, binom, direct, qj, hj, t, e, steps, close, tiny, buf, dbuf,
                 decide, cap, Td, costs):
    """One query of :func:`chain_largest_feeds` (``decide``: stopped as :func:`chain_feed_decisions`)."""
    h = hj
    if e <= t:
        return h
    if not t > 0:
        return 0.0
    if decide and _decided(0.0, h, hj, cap, Td, costs):
        return h
    resolution = 0.5 ** steps
    target = -0.5 * close
    g_h = math.log(e / t)
    x = h * t / e
    l, g_l, g_low = 0.0, -np.inf, -np.inf  # g_low: the low end's own g (g_l is Illinois-weighted)
    width = h * resolution
    side = 0
    for it in range(2 * steps):
        gx, slope = _log_error(s, du, rho, sign, p, norm, prefix, binom, direct, qj, x, t, tiny, buf, dbuf)
        if gx <= 0:
            if side == -1:
                g_h = 0.5 * g_h
            g_l, g_low, l = gx, gx, x
            side = -1
        elif it == 0:  # the first point is infeasible: the bracket stays [0, hi], bisected
            x = 0.5 * h
            continue
        else:
            if side == 1:
                g_l = 0.5 * g_l
            g_h, h = gx, x
            side = 1
        if not (h - l > width and g_low < -close):
            break
        if decide and _decided(l, h, hj, cap, Td, costs):
            return h
        guard = 0.5 * width
        nxt = math.exp(math.log(x) - (gx - target) / slope) if slope > 0 else np.nan
        if not (l + guard <= nxt <= h - guard):  # no slope, or a step out of the bracket
            if l > 0:
                xl = math.log(l)
                nxt = math.exp(xl + (math.log(h) - xl) * (-g_l) / (g_h - g_l))
            else:
                nxt = 0.5 * h  # no power law through F = 0: bisect
            if nxt != nxt:
                nxt = 0.5 * (l + h)
            nxt = min(max(nxt, l + guard), h - guard)
        x = nxt
    return l


@numba.njit(**_OPTIONS)
def sampled_line_distances(breaks, coeffs, t, starts, half_window, seg_start, seg_vec, seg_inv):
    """Trajectory samples and their squared distances to the three blocks around each (lines).

    The exact profile is evaluated at ``t`` (clipped to its breaks; Horner's rule on the piece
    ``searchsorted(breaks, t, "right") - 1``, clipped, as :class:`research.piecewise.NumpyPiecewise`),
    the block whose input the averaging window is centred on is ``searchsorted(starts, t - T_d / 2,
    "right") - 1`` (clipped), and each sample is projected on the segments of blocks ``k - 1 .. k +
    1`` (clipped to the path; an arc's entry is its chord here and is replaced by the caller). Both
    searches step on from the previous sample's (:func:`_right_next`: the samples run forward, a grid
    then the corner instants), and any order of ``t`` gives the same result. Compiled with the row
    count ``D`` and axis count ``A`` of ``coeffs`` as constants for the profiles of two filters
    (``D`` = 4 on lines, 9 with arcs; ``A`` = 2 or 3; about 2x faster), any other pair generically
    (each pair costs about 1.2 s of compilation, once per cache).

    Args:
        breaks, coeffs: ``(K + 1,)`` and ``(K, D, A)`` of the position profile.
        t: ``(N,)`` sample times [s]; starts: ``(M,)`` block pulse starts [s]; half_window: ``T_d / 2``.
        seg_start, seg_vec: ``(M, A)`` start and end-minus-start of each block [mm];
            seg_inv: ``(M,)`` ``1 / |seg_vec|^2`` (0 for a zero-length block).

    Returns:
        ``(q (N, A), block (N,), d2 (N, 3))``.
    """
    D, A = coeffs.shape[1], coeffs.shape[2]
    if A == 3:
        if D == 4:
            return _line_distances(breaks, coeffs, t, starts, half_window, seg_start, seg_vec, seg_inv, 4, 3)
        if D == 9:
            return _line_distances(breaks, coeffs, t, starts, half_window, seg_start, seg_vec, seg_inv, 9, 3)
    if A == 2:
        if D == 4:
            return _line_distances(breaks, coeffs, t, starts, half_window, seg_start, seg_vec, seg_inv, 4, 2)
        if D == 9:
            return _line_distances(breaks, coeffs, t, starts, half_window, seg_start, seg_vec, seg_inv, 9, 2)
    return _line_distances(breaks, coeffs, t, starts, half_window, seg_start, seg_vec, seg_inv, D, A)


@numba.njit(**_OPTIONS)
def _line_distances(breaks, coeffs, t, starts, half_window, seg_start, seg_vec, seg_inv, D, A):
    """:func:`sampled_line_distances` with the coefficient rows ``D`` and axes ``A`` of ``coeffs``
    passed apart: compiled for a constant pair (the loops over rows and axes unroll and the
    Horner sums stay in registers; the same operations in the same order) or for any pair."""
    N = t.size
    K = coeffs.shape[0]
    M = starts.size
    q = np.empty((N, A))
    block = np.empty(N, dtype=np.int64)
    d2 = np.empty((N, 3))
    t_lo, t_hi = breaks[0], breaks[K]
    found, at = 0, 0  # searchsorted(breaks, ., "right") and searchsorted(starts, ., "right") of the last sample
    for i in range(N):
        tc = min(max(t[i], t_lo), t_hi)
        found = _right_next(breaks, tc, found)
        piece = min(max(found - 1, 0), K - 1)
        tau = tc - breaks[piece]
        for a in range(A):
            v = coeffs[piece, D - 1, a]
            for m in range(D - 2, -1, -1):
                v = v * tau + coeffs[piece, m, a]
            q[i, a] = v
        at = _right_next(starts, t[i] - half_window, at)
        k = min(max(at - 1, 0), M - 1)
        block[i] = k
        for c in range(3):
            kb = min(max(k - 1 + c, 0), M - 1)
            dot = 0.0
            for a in range(A):
                dot += (q[i, a] - seg_start[kb, a]) * seg_vec[kb, a]
            u = min(max(dot * seg_inv[kb], 0.0), 1.0)
            acc = 0.0
            for a in range(A):
                r = (q[i, a] - seg_start[kb, a]) - u * seg_vec[kb, a]
                acc += r * r
            d2[i, c] = acc
    return q, block, d2


@numba.njit(**_OPTIONS)
def _right_next(a, v, i):
    """``np.searchsorted(a, v, side="right")`` from ``0 <= i <= a.size``, the count of a previous
    query: ``i`` or ``i + 1`` when ``v`` moved on by at most one entry (two comparisons, the common
    case of samples that run forward), else the galloping search of :func:`_right_from` (a jump, or
    a ``v`` that went back). Exact for any ``i``; fast for a nearby one."""
    n = a.size
    if i == 0 or a[i - 1] <= v:
        if i == n or a[i] > v:
            return i
        if i + 1 == n or a[i + 1] > v:
            return i + 1
    return _right_from(a, v, i)


@numba.njit(**_OPTIONS)
def corner_distances(breaks, coeffs, vertices, centre, half_window, grid, newton_steps):
    """Distance [mm] from each vertex ``(C, A)`` to the profile near ``centre`` ``(C,)`` [s]: the best
    of ``grid`` points evenly spread over ``centre +- half_window``, refined by ``newton_steps``
    safeguarded Newton steps on ``|p(t) - V|^2`` kept within one grid step (the compiled form of
    ``_fir_verify._corner_distances``; never above the best grid point's distance).

    The profile is evaluated as :class:`research.piecewise.NumpyPiecewise` (clipped time, piece
    ``searchsorted(breaks, t, "right") - 1``, Horner's rule; derivatives 0 outside the breaks), each
    piece found from a nearby index (:func:`_right_next`): a grid point's from the same grid point
    of the last corner, the first Newton step's from the best grid point, the others' from the
    last step. Compiled for the same row and axis counts as constants as
    :func:`sampled_line_distances`."""
    D, A = coeffs.shape[1], coeffs.shape[2]
    if A == 3:
        if D == 4:
            return _corner_rows(breaks, coeffs, vertices, centre, half_window, grid, newton_steps, 4, 3)
        if D == 9:
            return _corner_rows(breaks, coeffs, vertices, centre, half_window, grid, newton_steps, 9, 3)
    if A == 2:
        if D == 4:
            return _corner_rows(breaks, coeffs, vertices, centre, half_window, grid, newton_steps, 4, 2)
        if D == 9:
            return _corner_rows(breaks, coeffs, vertices, centre, half_window, grid, newton_steps, 9, 2)
    return _corner_rows(breaks, coeffs, vertices, centre, half_window, grid, newton_steps, D, A)


@numba.njit(**_OPTIONS)
def _corner_rows(breaks, coeffs, vertices, centre, half_window, grid, newton_steps, D, A):
    """:func:`corner_distances` with the coefficient rows ``D`` and axes ``A`` of ``coeffs`` passed
    apart, as :func:`_line_distances`."""
    C = vertices.shape[0]
    K = coeffs.shape[0]
    t_lo, t_hi = breaks[0], breaks[K]
    out = np.empty(C)
    step = half_window * (2.0 / (grid - 1))
    # search index of each grid point at the last corner: the corner instants run forward, a few
    # pieces apart, while the grid spans many pieces
    at_grid = np.zeros(grid, np.int64)
    for c in range(C):
        best, best_d2, found = 0.0, np.inf, 0
        for g in range(grid):
            tg = centre[c] + half_window * (-1.0 + 2.0 * g / (grid - 1))
            tc = min(max(tg, t_lo), t_hi)
            at_grid[g] = _right_next(breaks, tc, at_grid[g])
            piece = min(max(at_grid[g] - 1, 0), K - 1)
            tau = tc - breaks[piece]
            d2 = 0.0
            for a in range(A):
                v = coeffs[piece, D - 1, a]
                for m in range(D - 2, -1, -1):
                    v = v * tau + coeffs[piece, m, a]
                e = v - vertices[c, a]
                d2 += e * e
            if d2 < best_d2:
                best, best_d2, found = tg, d2, at_grid[g]
        lo, hi = best - step, best + step
        t = best
        for _ in range(newton_steps):
            tc = min(max(t, t_lo), t_hi)
            found = _right_next(breaks, tc, found)
            piece = min(max(found - 1, 0), K - 1)
            tau = tc - breaks[piece]
            inside = t_lo <= t <= t_hi
            slope, curvature = 0.0, 0.0
            for a in range(A):
                v = coeffs[piece, D - 1, a]
                for m in range(D - 2, -1, -1):
                    v = v * tau + coeffs[piece, m, a]
                v1 = 0.0
                if D > 1:
                    v1 = coeffs[piece, D - 1, a] * (D - 1)
                    for m in range(D - 2, 0, -1):
                        v1 = v1 * tau + coeffs[piece, m, a] * m
                v2 = 0.0
                if D > 2:
                    v2 = coeffs[piece, D - 1, a] * (D - 1) * (D - 2)
                    for m in range(D - 2, 1, -1):
                        v2 = v2 * tau + coeffs[piece, m, a] * m * (m - 1)
                if not inside:
                    v1, v2 = 0.0, 0.0
                e = v - vertices[c, a]
                slope += e * v1
                curvature += v1 * v1 + e * v2
            if curvature > 0:
                t = t - slope / curvature
            t = min(max(t, lo), hi)
        tc = min(max(t, t_lo), t_hi)
        found = _right_next(breaks, tc, found)
        piece = min(max(found - 1, 0), K - 1)
        tau = tc - breaks[piece]
        d2 = 0.0
        for a in range(A):
            v = coeffs[piece, D - 1, a]
            for m in range(D - 2, -1, -1):
                v = v * tau + coeffs[piece, m, a]
            e = v - vertices[c, a]
            d2 += e * e
        out[c] = math.sqrt(min(d2, best_d2))
    return out


@numba.njit(**_OPTIONS)
def scatter_max(out, index, values):
    """``np.maximum.at(out, index, values)`` in one compiled pass (NumPy's ``ufunc.at`` costs tens
    of ns an element)."""
    for i in range(index.size):
        k = index[i]
        if values[i] > out[k]:
            out[k] = values[i]


@numba.njit(**_OPTIONS)
def _nan_min(a, b):
    """``np.minimum(a, b)`` of two floats (a NaN wins), written as a select, not a branch."""
    return b if (b < a or b != b) else a


@numba.njit(**_OPTIONS)
def _range_min_into(out, first, last, values):
    """``out[k] = min(out[k], min{values[r] : first[r] <= k <= last[r]})`` in place, for the
    ``n = out.size`` cells.

    A range is intersected with the cells ``[0, n - 1]`` (``first`` raised to 0, ``last`` lowered to
    ``n - 1``); one with ``first > last`` after that, e.g. wholly beyond an end, covers nothing. Each range marks the
    ``O(log length)`` nodes of an implicit segment tree over the cells (``2 n`` floats, a leaf
    ``n + k`` per cell, node ``i``'s children ``2 i`` and ``2 i + 1``) that tile it, and one top-down
    pass hands every node's minimum to its children, so that a leaf holds the minimum over the nodes
    above it: ``O(R log n + n)`` time, ``O(n)`` memory. ``min`` is exact, so the result is that of
    any other correct order; a NaN wins as in ``np.minimum``. The marking step updates both sides
    of a level unconditionally (with ``inf`` where a side takes no node): branch-free, which is
    about 4x faster than the branching form on the planner's ranges (benchmarks/README.md).

    Args:
        out: ``(n,)`` float64, the starting values, lowered in place.
        first, last: ``(R,)`` int64 inclusive cell ranges (any integers; intersected as above).
        values: ``(R,)`` float64, the value of each range.
    """
    n = out.size
    if n == 0:
        return
    tree = np.full(2 * n, np.inf)
    for r in range(first.size):
        lo, hi = max(first[r], 0), min(last[r], n - 1)
        if lo > hi:
            continue
        v = values[r]
        lo += n
        hi += n + 1  # half-open [lo, hi) over the leaves
        while lo < hi:
            tree[lo] = _nan_min(tree[lo], v if lo & 1 else np.inf)  # a right child: its own node
            lo += lo & 1
            odd = hi & 1
            hi -= odd
            tree[hi] = _nan_min(tree[hi], v if odd else np.inf)  # left of an odd end: its own node
            lo >>= 1
            hi >>= 1
    for i in range(1, n):  # parents before children: i < 2 i
        tree[2 * i] = _nan_min(tree[2 * i], tree[i])
        tree[2 * i + 1] = _nan_min(tree[2 * i + 1], tree[i])
    for k in range(n):
        out[k] = _nan_min(out[k], tree[n + k])


@numba.njit(**_OPTIONS)
def _left_from(a, v, hint):
    """``np.searchsorted(a, v, side="left")`` (the count of entries ``< v``) by a galloping search
    from ``hint``, as :func:`_right_from`."""
    n = a.size
    i = min(max(hint, 0), n)
    if i > 0 and a[i - 1] >= v:
        hi, step = i, 1
        lo = hi - step
        while lo > 0 and a[lo - 1] >= v:
            hi = lo
            step *= 2
            lo = max(hi - step, 0)
        lo = max(lo, 0)
    else:
        lo, step = i, 1
        hi = lo + step
        while hi <= n and a[hi - 1] < v:
            lo = hi
            step *= 2
            hi = lo + step
        hi = min(hi, n)
    return _left_in(a, v, lo, hi)


@numba.njit(**_OPTIONS)
def sample_charges(t, centre, block, dist, tol_block, is_arc, half_window):
    """Tolerance, violation and charge key of path samples (``_fir_verify._charged_samples``).

    Sample ``i`` at time ``t[i]``, its window's block ``block[i]`` and distance ``dist[i]``: it is
    near the corner whose instant (``centre``, ``(M - 1,)``, sorted) is closest, when within
    ``half_window``; its tolerance is its block's, or the smaller of that and the vertex's (the
    smaller of the vertex's two blocks) when near. Key: the near vertex; else, on a line, the vertex
    ``clip(block, 0, M - 2)``; else (inside an arc) ``M - 1 + block``; ``-1`` on a one-block path's
    line. The same comparisons as the NumPy form it replaces.

    Returns:
        ``(limit (N,), key (N,), bad (N,))``.
    """
    N, C = t.size, centre.size
    M = C + 1
    limit = np.empty(N)
    key = np.empty(N, np.int64)
    bad = np.empty(N, np.bool_)
    hint = 0
    for i in range(N):
        b = block[i]
        lim = tol_block[b]
        near = -1
        if M > 1:
            hint = _left_from(centre, t[i], hint)
            k = min(max(hint, 1), M - 1)
            k2 = min(k, M - 2)
            j = k - 1 if abs(centre[k - 1] - t[i]) <= abs(centre[k2] - t[i]) else k2
            if abs(centre[j] - t[i]) <= half_window:
                near = j
                lim = min(lim, min(tol_block[j], tol_block[j + 1]))
        limit[i] = lim
        bad[i] = dist[i] > lim * (1.0 + VERIFY_RTOL) + VERIFY_ATOL
        if near >= 0:
            key[i] = near
        elif not is_arc[b]:
            key[i] = min(max(b, 0), max(M - 2, 0)) if M > 1 else -1
        else:
            key[i] = M - 1 + b
    return limit, key, bad


@numba.njit(**_OPTIONS)
def staircase_cuts(r_h, f_h, r_t, f_t, length, cap):
    """``_fir_lookahead.staircase_cut`` for every line ``b``, one compiled loop: the cut
    candidates ``x`` (0, the length, the reaches from each end, clipped and sorted), the allowed
    feed on each interval between them (the covering windows' minimum, capped, ``1e-300`` at
    least; ``inf`` on an empty interval), and the cuts ``a <= c`` of least ``cost(0, a) +
    cost(a, c) + cost(c, n - 1)`` with ``cost(i, j) = (x_j - x_i) / min(allowed_i .. allowed_j-1)``
    (0 on an empty piece; the first least in row-major order). The same operations in the same
    order as the NumPy form it replaced (bit for bit). Returns ``(head share (B,), tail share
    (B,), feeds (B, 3))``."""
    B, H = r_h.shape
    T = r_t.shape[1]
    n = H + T + 2
    head, tail, feeds = np.empty(B), np.empty(B), np.empty((B, 3))
    x = np.empty(n)
    allowed = np.empty(n - 1)
    low = np.empty((n, n))
    cost = np.empty((n, n))
    for b in range(B):
        L = length[b]
        x[0], x[1] = 0.0, L
        for h in range(H):
            x[2 + h] = r_h[b, h]
        for t in range(T):
            x[2 + H + t] = L - r_t[b, t]
        for i in range(n):
            x[i] = min(max(x[i], 0.0), L)
        x.sort()
        for i in range(n - 1):
            lo, hi = x[i], x[i + 1]
            if hi > lo:
                fh = np.inf
                for h in range(H):
                    if r_h[b, h] >= hi and f_h[b, h] < fh:
                        fh = f_h[b, h]
                ft = np.inf
                for t in range(T):
                    if L - r_t[b, t] <= lo and f_t[b, t] < ft:
                        ft = f_t[b, t]
                allowed[i] = max(min(min(fh, ft), cap[b]), 1e-300)
            else:
                allowed[i] = np.inf
        for i in range(n):
            m = np.inf
            for j in range(n):
                if j > i:
                    m = min(m, allowed[j - 1])
                    low[i, j] = m
                else:
                    low[i, j] = np.inf
                span = x[j] - x[i]
                cost[i, j] = span / low[i, j] if span > 0 else 0.0
        best, a, c = np.inf, 0, 0
        for i in range(n):
            for j in range(i, n):
                total = cost[0, i] + cost[i, j] + cost[j, n - 1]
                if total < best:
                    best, a, c = total, i, j
        xa, xc = x[a], x[c]
        head[b], tail[b] = xa / L, (L - xc) / L
        feeds[b, 0] = min(low[0, a] if xa > 0 else cap[b], cap[b])
        feeds[b, 1] = min(low[a, c] if xc > xa else cap[b], cap[b])
        feeds[b, 2] = min(low[c, n - 1] if xc < L else cap[b], cap[b])
    return head, tail, feeds


@numba.njit(**_OPTIONS)
def predicted_cycle(lengths, feeds, block, role, fraction, arc_of, arc_rel, factor, head, tail, first_motion,
                    last_motion, t_in, t_out, full, shrink, others, tol_v, delays, h_full):
    """Cycle time ``sum_pieces share L / (F f) + sum_corners (T_d - T_k) + T_d`` [s] of a candidate
    plan, in one pass (``fir.plan_fir``'s ``predicted_time``: ``PulseTable.pieces`` and
    ``_fir_profile.timing`` without their arrays; the same operations per piece and corner, summed in
    order rather than pairwise, and Numba's ``cbrt`` is not NumPy's bit for bit, so equal to ~1e-15
relative: it is used as a bound only). One or two filters (eq 13/14's closed
    forms, as ``_fir_profile.overlaps``).

    Args:
        lengths, feeds: ``(M,)`` block lengths [mm] and commanded feeds [mm/s]; block, role,
            fraction: the table's pieces (role 0 / 1 / 2 a line's head / body / tail, -1 otherwise;
            pieces of ``block >= M`` are padding); arc_of: ``(P,)`` index of each sub-arc piece in
            ``arc_rel`` (-1 elsewhere); factor ``(M, 3)``, head, tail ``(M,)``: the candidate's
            feed factors and shares; first_motion, last_motion: ``(M,)`` pieces; t_in, t_out:
            ``(M, d)`` tangents; full, shrink, others, tol_v: ``(M - 1,)`` per corner; delays:
            ``(n,)`` sorted descending, ``n <= 2``; h_full: ``H2(T_d / 2)``.
    """
    M = lengths.size
    P = block.size
    total = 0.0
    for i in range(P):
        b = block[i]
        if b >= M:
            continue
        r = role[i]
        if r == 0:
            fr = head[b]
        elif r == 1:
            fr = 1.0 - head[b] - tail[b]
        elif r == 2:
            fr = tail[b]
        else:
            fr = fraction[i]
        f = factor[b, r if r >= 0 else 1]
        a = arc_of[i]
        if a >= 0:
            f *= arc_rel[a]
        total += fr * (lengths[b] / (feeds[b] * f))
    Td = 0.0
    for k in range(delays.size):
        Td += delays[k]
    T1 = delays[0]
    T2 = delays[1] if delays.size > 1 else 0.0
    dims = t_in.shape[1]
    gaps = 0.0
    for j in range(M - 1):
        if full[j]:
            ov = Td
        else:
            f_in = feeds[j + 1] * _piece_factor(factor, arc_rel, role, arc_of, block, first_motion[j + 1])
            f_out = feeds[j] * _piece_factor(factor, arc_rel, role, arc_of, block, last_motion[j])
            s = 0.0
            for c in range(dims):
                x = f_in * t_in[j + 1, c] - f_out * t_out[j, c]
                s += x * x
            dF = math.sqrt(s) if s > 0 else 0.0
            tol = max(tol_v[j] - others[j], 0.0)
            h = min(tol / (dF if dF > 0 else 1.0), h_full)
            if dF > 0 and h < h_full:
                if delays.size == 1:
                    Tk = math.sqrt(8.0 * T1 * h)
                elif h <= T2**2 / (6.0 * T1):
                    Tk = np.cbrt(48.0 * T1 * T2 * h)
                else:
                    Tk = T2 + math.sqrt(8.0 * T1 * h - T2**2 / 3.0)
                ov = min(max(Tk, 0.0), Td)
            else:
                ov = Td
        gaps += Td - ov * shrink[j]
    return total + gaps + Td


@numba.njit(**_OPTIONS)
def _piece_factor(factor, arc_rel, role, arc_of, block, i):
    """Feed factor of piece ``i`` (``PulseTable.pieces``)."""
    r = role[i]
    f = factor[block[i], r if r >= 0 else 1]
    a = arc_of[i]
    if a >= 0:
        f *= arc_rel[a]
    return f


@numba.njit(**_OPTIONS)
def line_piece_feeds(h_blk, h_reach, h_feed, t_blk, t_reach, t_feed, L, body, F, arc):
    """``_fir_lookahead.line_pieces`` in one compiled pass (the same operations per line, and the
    same padded rows for :func:`staircase_cuts`, so bit for bit): returns ``(head, tail, feeds)``."""
    M = L.size
    n_h, n_t = np.zeros(M, np.int64), np.zeros(M, np.int64)
    r_h, f_h, r_t, f_t = np.zeros(M), np.full(M, np.inf), np.zeros(M), np.full(M, np.inf)
    for i in range(h_blk.size):
        k = h_blk[i]
        n_h[k] += 1
        r_h[k] = max(r_h[k], h_reach[i])
        f_h[k] = min(f_h[k], h_feed[i])
    for i in range(t_blk.size):
        k = t_blk[i]
        n_t[k] += 1
        r_t[k] = max(r_t[k], t_reach[i])
        f_t[k] = min(f_t[k], t_feed[i])
    head, tail, feeds = np.empty(M), np.empty(M), np.empty((M, 3))
    b = np.empty(M)
    slot = np.full(M, -1)
    B, H, T = 0, 1, 1
    for k in range(M):
        b[k] = min(body[k], F[k])
        # one window at each end (or none): the staircase has at most three steps
        a_cut = min(r_h[k], L[k] - r_t[k])  # the head piece ends where the tail's reach begins, if earlier
        b_cut = max(L[k] - r_t[k], r_h[k])
        over = r_h[k] + r_t[k] > L[k]
        feeds[k, 0] = min(f_h[k] if a_cut > 0 else b[k], b[k])
        feeds[k, 1] = min(b[k], min(f_h[k] if over else np.inf, f_t[k] if over else np.inf))
        feeds[k, 2] = min(f_t[k] if b_cut < L[k] else b[k], b[k])
        head[k], tail[k] = a_cut / L[k], (L[k] - b_cut) / L[k]
        if not arc[k] and (n_h[k] > 1 or n_t[k] > 1):
            slot[k] = B
            B += 1
            H, T = max(H, n_h[k]), max(T, n_t[k])
    if B:
        rh, fh = np.zeros((B, H)), np.full((B, H), np.inf)
        rt, ft = np.zeros((B, T)), np.full((B, T), np.inf)
        fill_h, fill_t = np.zeros(B, np.int64), np.zeros(B, np.int64)
        for i in range(h_blk.size):  # entries in their order within each line (a stable sort)
            s = slot[h_blk[i]]
            if s >= 0:
                rh[s, fill_h[s]], fh[s, fill_h[s]] = h_reach[i], h_feed[i]
                fill_h[s] += 1
        for i in range(t_blk.size):
            s = slot[t_blk[i]]
            if s >= 0:
                rt[s, fill_t[s]], ft[s, fill_t[s]] = t_reach[i], t_feed[i]
                fill_t[s] += 1
        rows = np.flatnonzero(slot >= 0)
        hs, ts, fs = staircase_cuts(rh, fh, rt, ft, L[rows], b[rows])
        for s in range(B):
            k = rows[s]
            head[k], tail[k] = hs[s], ts[s]
            for c in range(3):
                feeds[k, c] = fs[s, c]
    for k in range(M):
        if arc[k]:
            for c in range(3):
                feeds[k, c] = F[k]
            head[k], tail[k] = 0.0, 0.0
        # an empty end piece takes the feed of the nearest piece that is not: eq 13/14 reads a
        # block's entry and exit feeds from its first and last pieces
        mid = 1.0 - head[k] - tail[k] > 0
        h, m, t = feeds[k, 0], feeds[k, 1], feeds[k, 2]
        feeds[k, 0] = h if head[k] > 0 else (m if mid else t)
        feeds[k, 2] = t if tail[k] > 0 else (m if mid else h)
    return head, tail, feeds


@numba.njit(**_OPTIONS)
def _below(x, v, right):
    """The search of :func:`_search` goes on past an entry ``x``."""
    return x < v or (right and x == v)


@numba.njit(**_OPTIONS)
def _search(a, v, right, hint):
    """``np.searchsorted(a, v, side="right" if right else "left")`` for a non-decreasing ``a`` and
    a number ``v`` (not NaN): the first index whose entry is above ``v`` (right) or not below it.
    Galloping from ``hint`` (the answer for a nearby ``v``), then bisecting: ``O(log d)`` for an
    answer ``d`` entries from the hint."""
    n = a.size
    if n == 0:
        return 0
    i = min(max(hint, 0), n - 1)
    step = 1
    if _below(a[i], v, right):  # the answer is in [i + 1, n]
        lo = i + 1
        while lo + step - 1 < n and _below(a[lo + step - 1], v, right):
            lo += step
            step <<= 1
        hi = min(lo + step - 1, n)
    else:  # in [0, i]
        hi = i
        while hi - step >= 0 and not _below(a[hi - step], v, right):
            hi -= step
            step <<= 1
        lo = max(hi - step + 1, 0)
    while lo < hi:
        mid = (lo + hi) >> 1
        if _below(a[mid], v, right):
            lo = mid + 1
        else:
            hi = mid
    return lo


@numba.njit(**_OPTIONS)
def candidate_pieces(cum, L, F, s_v, full, f_full, hold, arc, span_start, span_end, arc_F):
    """``_fir_lookahead._candidate``'s windows, block pieces and sub-arc feeds in one compiled pass
    (the same operations per window, so bit for bit): the windows of the full-overlap vertices
    ``full`` ``(M - 1,)`` whose feed ``f_full`` (one per such vertex) is below the faster block at
    the vertex, held ``hold`` [s] each side, slow the blocks they cover (``body``, a minimum) and
    the head or tail of the blocks they reach into (:func:`line_piece_feeds`), and the sub-arcs
    ``[span_start, span_end]`` they overlap. Returns ``(head, tail, feeds (M, 3), arc_rel (A,))``,
    ``arc_rel`` the sub-arcs' feeds over ``arc_F``, at most 1."""
    M, V = L.size, full.size
    js, fs = np.empty(V, np.int64), np.empty(V)
    n, q = 0, 0
    for v in range(V):
        if full[v]:
            fv = f_full[q]
            q += 1
            if fv < max(F[v], F[v + 1]) * (1 - 1e-12):
                js[n], fs[n] = v, fv
                n += 1
    lo, hi, half = np.empty(n), np.empty(n), np.empty(n)
    first, last = np.empty(n, np.int64), np.empty(n, np.int64)
    k_r, k_l = np.empty(n, np.int64), np.empty(n, np.int64)
    for w in range(n):
        j, fw = js[w], fs[w]
        half[w] = hold[j]
        lo[w], hi[w] = s_v[j] - half[w] * fw, s_v[j] + half[w] * fw
        right = _search(cum, hi[w], True, j + 1)
        first[w], last[w] = _search(cum, lo[w], False, j + 1), right - 2
        k_r[w] = min(max(right - 1, 0), M - 1)
        k_l[w] = min(max(_search(cum, lo[w], True, first[w]) - 1, 0), M - 1)
    body = F.copy()
    _range_min_into(body, first, last, fs[:n])
    t_cum = np.empty(M + 1)
    t_cum[0] = 0.0
    for k in range(M):
        t_cum[k + 1] = t_cum[k] + L[k] / body[k]
    h_blk, h_reach, h_feed = np.empty(n, np.int64), np.empty(n), np.empty(n)
    t_blk, t_reach, t_feed = np.empty(n, np.int64), np.empty(n), np.empty(n)
    n_h, n_t = 0, 0
    for w in range(n):
        j, fw, kr, kl = js[w], fs[w], k_r[w], k_l[w]
        reach_r = min(hi[w] - cum[kr], max(half[w] - (t_cum[kr] - t_cum[j + 1]), 0.0) * fw)
        if hi[w] < cum[kr + 1] and reach_r > 0:
            h_blk[n_h], h_reach[n_h], h_feed[n_h] = kr, reach_r, fw
            n_h += 1
    for w in range(n):
        j, fw, kl = js[w], fs[w], k_l[w]
        reach_l = min(cum[kl + 1] - lo[w], max(half[w] - (t_cum[j + 1] - t_cum[kl + 1]), 0.0) * fw)
        if lo[w] > cum[kl] and reach_l > 0:
            t_blk[n_t], t_reach[n_t], t_feed[n_t] = kl, reach_l, fw
            n_t += 1
    head, tail, feeds = line_piece_feeds(h_blk[:n_h], h_reach[:n_h], h_feed[:n_h], t_blk[:n_t], t_reach[:n_t],
                                         t_feed[:n_t], L, body, F, arc)
    A = span_start.size
    arc_rel = np.full(A, np.inf)
    if A:
        a_first, a_last = np.empty(n, np.int64), np.empty(n, np.int64)
        for w in range(n):  # windows in path order: each search starts from the one before
            a_first[w] = _search(span_end, lo[w], True, a_first[w - 1] if w else 0)
            a_last[w] = _search(span_start, hi[w], False, a_last[w - 1] + 1 if w else 0) - 1
        _range_min_into(arc_rel, a_first, a_last, fs[:n])
        for a in range(A):
            arc_rel[a] = min(arc_rel[a] / arc_F[a], 1.0)
    return head, tail, feeds, arc_rel
