"""Compiled (Numba) kernels of the FIR planner's verification rounds (``_fir_verify``).

:func:`sampled_line_distances` (the sampled path check) and :func:`corner_distances` (the
corner-distance search) evaluate the exact profile on its NumPy arrays with Horner's rule, as
:class:`research.piecewise.NumpyPiecewise`, and replace per-sample NumPy gathers and the JAX grid +
Newton search inside the planner's rounds. Each finds its piece from the last one's index and is
compiled with the profile's row and axis counts as constants for two filters.
:func:`charge_samples` charges path samples to their corner or arc and keeps the largest
distance of each, :func:`grid_times` makes their times, :func:`scatter_max` is
``np.maximum.at`` in one pass. ``tests/interpolators/test_fir_kernels.py`` checks them against
NumPy computations.
"""

from __future__ import annotations

import math

import numba
import numpy as np

from research._sorted_search import left_from as _left_from, right_from as _right_from
from research.interpolators._fir_kernels import _OPTIONS, VERIFY_ATOL, VERIFY_RTOL


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
    (``D`` = 4 on lines, 9 with arcs; ``A`` = 2 or 3; about 2x faster), any other pair generically;
    the form is chosen here, in Python, so that only the pairs met are compiled (each costs about
    1.2-2 s of compilation, once per cache; a compiled choice compiled all five at once).

    Args:
        breaks, coeffs: ``(K + 1,)`` and ``(K, D, A)`` of the position profile.
        t: ``(N,)`` sample times [s]; starts: ``(M,)`` block pulse starts [s]; half_window: ``T_d / 2``.
        seg_start, seg_vec: ``(M, A)`` start and end-minus-start of each block [mm];
            seg_inv: ``(M,)`` ``1 / |seg_vec|^2`` (0 for a zero-length block).

    Returns:
        ``(q (N, A), block (N,), d2 (N, 3))``.
    """
    return _LINE_FORMS.get(coeffs.shape[1:], _line_any)(breaks, coeffs, t, starts, half_window, seg_start, seg_vec, seg_inv)


# one function per (rows, axes) pair, written out as _fir_profile's _rows1 ...: Numba caches a compiled
# function by its source, and the constants in each one's source are what make its form fast
@numba.njit(**_OPTIONS)
def _line_4_3(breaks, coeffs, t, starts, half_window, seg_start, seg_vec, seg_inv):
    return _line_distances(breaks, coeffs, t, starts, half_window, seg_start, seg_vec, seg_inv, 4, 3)


@numba.njit(**_OPTIONS)
def _line_9_3(breaks, coeffs, t, starts, half_window, seg_start, seg_vec, seg_inv):
    return _line_distances(breaks, coeffs, t, starts, half_window, seg_start, seg_vec, seg_inv, 9, 3)


@numba.njit(**_OPTIONS)
def _line_4_2(breaks, coeffs, t, starts, half_window, seg_start, seg_vec, seg_inv):
    return _line_distances(breaks, coeffs, t, starts, half_window, seg_start, seg_vec, seg_inv, 4, 2)


@numba.njit(**_OPTIONS)
def _line_9_2(breaks, coeffs, t, starts, half_window, seg_start, seg_vec, seg_inv):
    return _line_distances(breaks, coeffs, t, starts, half_window, seg_start, seg_vec, seg_inv, 9, 2)


@numba.njit(**_OPTIONS)
def _line_any(breaks, coeffs, t, starts, half_window, seg_start, seg_vec, seg_inv):
    return _line_distances(breaks, coeffs, t, starts, half_window, seg_start, seg_vec, seg_inv, coeffs.shape[1], coeffs.shape[2])


_LINE_FORMS = {(4, 3): _line_4_3, (9, 3): _line_9_3, (4, 2): _line_4_2, (9, 2): _line_9_2}


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
            d2[i, c] = segment_distance2(q, i, seg_start, seg_vec, seg_inv, min(max(k - 1 + c, 0), M - 1), A)
    return q, block, d2


@numba.njit(**_OPTIONS)
def segment_distance2(q, i, seg_start, seg_vec, seg_inv, b, A):
    """Squared distance [mm^2] from point ``q[i]`` to block ``b`` as a segment (its start, its end
    minus start, the inverse of that's squared length; 0 for a zero-length one: its start), on the
    first ``A`` axes (a constant where the caller's form is compiled for one)."""
    dot = 0.0
    for a in range(A):
        dot += (q[i, a] - seg_start[b, a]) * seg_vec[b, a]
    u = min(max(dot * seg_inv[b], 0.0), 1.0)
    acc = 0.0
    for a in range(A):
        r = (q[i, a] - seg_start[b, a]) - u * seg_vec[b, a]
        acc += r * r
    return acc


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
def _squared_distance(coeffs, piece, tau, vertices, c, D, A):
    """``|p(tau) - vertices[c]|^2`` [mm^2] on ``piece`` of the profile, Horner's rule on its ``D`` rows
    for each of its ``A`` axes (compiled inline into the corner search)."""
    d2 = 0.0
    for a in range(A):
        v = coeffs[piece, D - 1, a]
        for m in range(D - 2, -1, -1):
            v = v * tau + coeffs[piece, m, a]
        e = v - vertices[c, a]
        d2 += e * e
    return d2


def corner_distances(breaks, coeffs, vertices, centre, half_window, grid, newton_steps, bound, more_steps):
    """Distance [mm] from each vertex ``(C, A)`` to the profile near ``centre`` ``(C,)`` [s]: the best
    of ``grid`` points evenly spread over ``centre +- half_window``, refined by ``newton_steps``
    safeguarded Newton steps on ``|p(t) - V|^2`` (Gauss-Newton where Newton's curvature is not
    positive) kept within one grid step (the compiled form of
    ``_fir_verify._corner_distances``; never above the best grid point's distance). A vertex whose
    distance is still above its ``bound`` ``(C,)`` [mm] then takes up to ``more_steps`` further
    steps, until one leaves its time where it is, and then, while still above it, the same steps
    from every other local minimum of the grid (a window over chords shorter than a grid step
    has several basins, and the best grid point's need not hold the least: a vertex 0.12 eps from
    the trajectory read 1.37 eps); it keeps the least distance met (each is the distance to a
    point of the trajectory: never optimistic).

    The profile is evaluated as :class:`research.piecewise.NumpyPiecewise` (clipped time, piece
    ``searchsorted(breaks, t, "right") - 1``, Horner's rule; derivatives 0 outside the breaks), each
    piece found from a nearby index (:func:`_right_next`): a grid point's from the same grid point
    of the last corner, the first Newton step's from the best grid point, the others' from the
    last step. Compiled for the same row and axis counts as constants as
    :func:`sampled_line_distances`."""
    return _CORNER_FORMS.get(coeffs.shape[1:], _corner_any)(breaks, coeffs, vertices, centre, half_window, grid,
                                                            newton_steps, bound, more_steps)


@numba.njit(**_OPTIONS)
def _corner_4_3(breaks, coeffs, vertices, centre, half_window, grid, newton_steps, bound, more_steps):
    return _corner_rows(breaks, coeffs, vertices, centre, half_window, grid, newton_steps, bound, more_steps, 4, 3)


@numba.njit(**_OPTIONS)
def _corner_9_3(breaks, coeffs, vertices, centre, half_window, grid, newton_steps, bound, more_steps):
    return _corner_rows(breaks, coeffs, vertices, centre, half_window, grid, newton_steps, bound, more_steps, 9, 3)


@numba.njit(**_OPTIONS)
def _corner_4_2(breaks, coeffs, vertices, centre, half_window, grid, newton_steps, bound, more_steps):
    return _corner_rows(breaks, coeffs, vertices, centre, half_window, grid, newton_steps, bound, more_steps, 4, 2)


@numba.njit(**_OPTIONS)
def _corner_9_2(breaks, coeffs, vertices, centre, half_window, grid, newton_steps, bound, more_steps):
    return _corner_rows(breaks, coeffs, vertices, centre, half_window, grid, newton_steps, bound, more_steps, 9, 2)


@numba.njit(**_OPTIONS)
def _corner_any(breaks, coeffs, vertices, centre, half_window, grid, newton_steps, bound, more_steps):
    return _corner_rows(breaks, coeffs, vertices, centre, half_window, grid, newton_steps, bound, more_steps,
                        coeffs.shape[1], coeffs.shape[2])


_CORNER_FORMS = {(4, 3): _corner_4_3, (9, 3): _corner_9_3, (4, 2): _corner_4_2, (9, 2): _corner_9_2}


def nearest_times(breaks, coeffs, vertices, centre, half_window, grid, newton_steps):
    """``(C,)`` time [s] of the point of the profile nearest each vertex ``(C, A)`` near ``centre``
    ``(C,)`` [s]: the best of ``grid`` points over ``centre +- half_window``, then ``newton_steps``
    safeguarded Newton steps within one grid step of it (the search of :func:`corner_distances`
    without its bound: the time it settles on, the nearer of it and the best grid point). Compiled
    for the same row and axis counts as constants as :func:`corner_distances` (the mirror's search
    calls it every round: its generic form took a fifth of ``plan_fir_mirror``'s time on bench_cam's
    quick file)."""
    return _NEAREST_FORMS.get(coeffs.shape[1:], _nearest_any)(breaks, coeffs, vertices, centre, half_window, grid,
                                                              newton_steps)


@numba.njit(**_OPTIONS)
def _nearest_4_3(breaks, coeffs, vertices, centre, half_window, grid, newton_steps):
    return _nearest_rows(breaks, coeffs, vertices, centre, half_window, grid, newton_steps, 4, 3)


@numba.njit(**_OPTIONS)
def _nearest_9_3(breaks, coeffs, vertices, centre, half_window, grid, newton_steps):
    return _nearest_rows(breaks, coeffs, vertices, centre, half_window, grid, newton_steps, 9, 3)


@numba.njit(**_OPTIONS)
def _nearest_4_2(breaks, coeffs, vertices, centre, half_window, grid, newton_steps):
    return _nearest_rows(breaks, coeffs, vertices, centre, half_window, grid, newton_steps, 4, 2)


@numba.njit(**_OPTIONS)
def _nearest_9_2(breaks, coeffs, vertices, centre, half_window, grid, newton_steps):
    return _nearest_rows(breaks, coeffs, vertices, centre, half_window, grid, newton_steps, 9, 2)


@numba.njit(**_OPTIONS)
def _nearest_any(breaks, coeffs, vertices, centre, half_window, grid, newton_steps):
    return _nearest_rows(breaks, coeffs, vertices, centre, half_window, grid, newton_steps, coeffs.shape[1],
                         coeffs.shape[2])


_NEAREST_FORMS = {(4, 3): _nearest_4_3, (9, 3): _nearest_9_3, (4, 2): _nearest_4_2, (9, 2): _nearest_9_2}


@numba.njit(**_OPTIONS)
def _nearest_rows(breaks, coeffs, vertices, centre, half_window, grid, newton_steps, D, A):
    """:func:`nearest_times` with the coefficient rows ``D`` and axes ``A`` of ``coeffs`` passed apart."""
    C, K = vertices.shape[0], coeffs.shape[0]
    t_lo, t_hi = breaks[0], breaks[K]
    out = np.empty(C)
    step = half_window * (2.0 / (grid - 1))
    at_grid = np.zeros(grid, np.int64)
    for c in range(C):
        best, best_d2, found = 0.0, np.inf, 0
        for g in range(grid):
            tg = centre[c] + half_window * (-1.0 + 2.0 * g / (grid - 1))
            tc = min(max(tg, t_lo), t_hi)
            at_grid[g] = _right_next(breaks, tc, at_grid[g])
            piece = min(max(at_grid[g] - 1, 0), K - 1)
            d2 = _squared_distance(coeffs, piece, tc - breaks[piece], vertices, c, D, A)
            if d2 < best_d2:
                best, best_d2, found = tc, d2, at_grid[g]
        t = best
        for _ in range(newton_steps):
            t, found = _newton_time(breaks, coeffs, vertices, c, t, found, t_lo, t_hi, best - step, best + step, D, A)
        d2, found = _distance_at(breaks, coeffs, vertices, c, t, found, t_lo, t_hi, D, A)
        out[c] = min(max(t, t_lo), t_hi) if d2 < best_d2 else best
    return out


@numba.njit(inline="always", **_OPTIONS)
def _newton_time(breaks, coeffs, vertices, c, t, found, t_lo, t_hi, lo, hi, D, A):
    """One safeguarded Newton step of the corner search (:func:`corner_distances`) from ``t``:
    ``(next time within [lo, hi], its piece search index)``."""
    K = coeffs.shape[0]
    tc = min(max(t, t_lo), t_hi)
    found = _right_next(breaks, tc, found)
    piece = min(max(found - 1, 0), K - 1)
    tau = tc - breaks[piece]
    inside = t_lo <= t <= t_hi
    slope, curvature, speed2 = 0.0, 0.0, 0.0
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
        speed2 += v1 * v1
    if curvature > 0:
        t = t - slope / curvature
    elif speed2 > 0:  # Gauss-Newton where Newton's model has no minimum (_fir_verify._corner_distances)
        t = t - slope / speed2
    return min(max(t, lo), hi), found


@numba.njit(inline="always", **_OPTIONS)
def _distance_at(breaks, coeffs, vertices, c, t, found, t_lo, t_hi, D, A):
    """``(|p(t) - V_c|^2, piece search index)`` at the clipped time ``t``."""
    K = coeffs.shape[0]
    tc = min(max(t, t_lo), t_hi)
    found = _right_next(breaks, tc, found)
    piece = min(max(found - 1, 0), K - 1)
    return _squared_distance(coeffs, piece, tc - breaks[piece], vertices, c, D, A), found


@numba.njit(**_OPTIONS)
def _corner_rows(breaks, coeffs, vertices, centre, half_window, grid, newton_steps, bound, more_steps, D, A):
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
    grid_d2 = np.empty(grid)
    for c in range(C):
        best, best_d2, found, best_g = 0.0, np.inf, 0, 0
        for g in range(grid):
            tg = centre[c] + half_window * (-1.0 + 2.0 * g / (grid - 1))
            tc = min(max(tg, t_lo), t_hi)
            at_grid[g] = _right_next(breaks, tc, at_grid[g])
            piece = min(max(at_grid[g] - 1, 0), K - 1)
            tau = tc - breaks[piece]
            d2 = _squared_distance(coeffs, piece, tau, vertices, c, D, A)
            grid_d2[g] = d2
            if d2 < best_d2:
                best, best_d2, found, best_g = tg, d2, at_grid[g], g
        lo, hi = best - step, best + step
        t = best
        for _ in range(newton_steps):
            t, found = _newton_time(breaks, coeffs, vertices, c, t, found, t_lo, t_hi, lo, hi, D, A)
        d2, found = _distance_at(breaks, coeffs, vertices, c, t, found, t_lo, t_hi, D, A)
        least = min(d2, best_d2)
        least = _descend(breaks, coeffs, vertices, c, t, found, t_lo, t_hi, lo, hi, more_steps, least, bound[c], D, A)
        # still above the bound: the other local minima of the grid, each refined the same way (the
        # distance along a window over chords shorter than a grid step has several: the best grid
        # point can sit in a basin whose minimum is not the least)
        for g in range(grid):
            if math.sqrt(least) <= bound[c]:
                break
            if g == best_g or (g > 0 and grid_d2[g - 1] < grid_d2[g]) or (g < grid - 1 and grid_d2[g + 1] < grid_d2[g]):
                continue
            tg = centre[c] + half_window * (-1.0 + 2.0 * g / (grid - 1))
            least = _descend(breaks, coeffs, vertices, c, tg, at_grid[g], t_lo, t_hi, tg - step, tg + step,
                             newton_steps + more_steps, least, bound[c], D, A)
        out[c] = math.sqrt(least)
    return out


@numba.njit(inline="always", **_OPTIONS)
def _descend(breaks, coeffs, vertices, c, t, found, t_lo, t_hi, lo, hi, steps, least, bound, D, A):
    """Up to ``steps`` Newton steps of the corner search from ``t`` within ``[lo, hi]`` while the
    least squared distance met, ``least``, is above ``bound^2``, until one leaves its time where it
    is: the least squared distance met."""
    for _ in range(steps):
        if math.sqrt(least) <= bound:
            break
        t_next, found = _newton_time(breaks, coeffs, vertices, c, t, found, t_lo, t_hi, lo, hi, D, A)
        if t_next == t:
            break
        t = t_next
        d2, found = _distance_at(breaks, coeffs, vertices, c, t, found, t_lo, t_hi, D, A)
        least = min(least, d2)
    return least


@numba.njit(**_OPTIONS)
def scatter_max(out, index, values):
    """``np.maximum.at(out, index, values)`` in one compiled pass (NumPy's ``ufunc.at`` costs tens
    of ns an element)."""
    for i in range(index.size):
        k = index[i]
        if values[i] > out[k]:
            out[k] = values[i]


@numba.njit(**_OPTIONS)
def grid_times(i, j, first, count, stride, ends, t0, t1, period):
    """Grid samples ``i .. j - 1`` of the runs ``r`` of ``count[r]`` grid points ``t0 + (first[r] +
    n stride[r]) period``, ``n = 0 .. count[r] - 1`` (``ends``: their cumulative counts), clipped to
    ``[t0, t1]`` (``_fir_verify._sample_times``): the run of sample ``k`` is ``searchsorted(ends, k,
    "right")``, its grid index ``first[run] + (k - (ends[run] - count[run])) stride[run]``, the
    integer converted to a float before the product, as NumPy's ``int64 * float64``."""
    out = np.empty(max(j - i, 0))
    run = 0
    for k in range(i, j):
        while ends[run] <= k:
            run += 1
        out[k - i] = min(max(t0 + (first[run] + (k - (ends[run] - count[run])) * stride[run]) * period, t0), t1)
    return out


@numba.njit(**_OPTIONS)
def thinned_runs(first, last, s_first, s_last, s_stride):
    """The grid-index runs ``[first[r], last[r]]`` (sorted, disjoint) cut by the steady spans
    ``[s_first[s], s_last[s]]`` (sorted, disjoint; ``_fir_verify.steady_spans``): outside a span
    every index is kept, inside it only ``s_first[s] + n s_stride[s]`` (the same indices whichever
    runs meet the span). Returns ``(first', count', stride')`` of the runs kept, in order."""
    R, S = first.size, s_first.size
    cap = 2 * (R + S) + 1
    out_first = np.empty(cap, np.int64)
    out_count = np.empty(cap, np.int64)
    out_stride = np.empty(cap, np.int64)
    n, s = 0, 0
    for r in range(R):
        cur, end = first[r], last[r]
        if cur > end:
            continue
        while s < S and s_last[s] < cur:
            s += 1
        k = s
        while k < S and s_first[k] <= end:
            if s_first[k] > cur:  # dense stretch before the span
                out_first[n], out_count[n], out_stride[n] = cur, s_first[k] - cur, 1
                n += 1
            lo, hi = max(cur, s_first[k]), min(end, s_last[k])
            a = s_first[k] + -((s_first[k] - lo) // s_stride[k]) * s_stride[k]  # first kept index >= lo
            if a <= hi:
                out_first[n], out_count[n], out_stride[n] = a, (hi - a) // s_stride[k] + 1, s_stride[k]
                n += 1
            cur = hi + 1
            if s_last[k] > end:
                break
            k += 1
        if cur <= end:
            out_first[n], out_count[n], out_stride[n] = cur, end - cur + 1, 1
            n += 1
    return out_first[:n], out_count[:n], out_stride[:n]


@numba.njit(**_OPTIONS)
def overlay_spans(s_first, s_last, s_stride, c_first, c_last, c_stride):
    """The grid-index spans ``s`` (sorted, disjoint; they take precedence) laid over the spans ``c``
    (sorted, disjoint): every ``s`` span, and each ``c`` span less the ``s`` spans it meets, in
    order (``_fir_verify.path_deviations``' ``spans``). A cut ``c`` piece keeps its stride from its
    own first index. Returns ``(first, last, stride)``."""
    S, C = s_first.size, c_first.size
    cap = 2 * (S + C) + 1
    out_first = np.empty(cap, np.int64)
    out_last = np.empty(cap, np.int64)
    out_stride = np.empty(cap, np.int64)
    n, s, covered = 0, 0, -1
    for c in range(C):
        cur, end = max(c_first[c], covered + 1), c_last[c]
        while s < S and s_first[s] <= end:
            if s_first[s] > cur and cur <= end:  # the part of c before the s span
                out_first[n], out_last[n], out_stride[n] = cur, s_first[s] - 1, c_stride[c]
                n += 1
            out_first[n], out_last[n], out_stride[n] = s_first[s], s_last[s], s_stride[s]
            n += 1
            covered = s_last[s]
            cur = max(cur, covered + 1)
            s += 1
        if cur <= end:
            out_first[n], out_last[n], out_stride[n] = cur, end, c_stride[c]
            n += 1
    while s < S:
        out_first[n], out_last[n], out_stride[n] = s_first[s], s_last[s], s_stride[s]
        n += 1
        s += 1
    return out_first[:n], out_last[:n], out_stride[:n]


@numba.njit(**_OPTIONS)
def charge_samples(t, d2, block, centre, tol_block, is_arc, half_window, redo, worst, slack, stopped):
    """Distance, tolerance, violation and charge key of path samples, and the largest distance of
    each key (``_fir_verify._charged_samples``).

    Sample ``i`` at time ``t[i]``, its window's block ``block[i]``, its squared distances ``d2[i]``
    ``(3,)`` to blocks ``block - 1 .. block + 1``: its distance is ``sqrt(min d2[i])``. It is near
    the corner whose instant (``centre``, ``(M - 1,)``, sorted) is closest, when within
    ``half_window``; its tolerance is its block's, or the smaller of that and the vertex's (the
    smaller of the vertex's two blocks) when near. A corner that is an exact stop (``stopped[j]``;
    an empty ``stopped``: none) has no blend and passes through its vertex at its instant: a sample
    by it is not near it but on its block on that side of the instant (``j`` before, ``j + 1``
    after), whose tolerance and key it takes (the window's own block is the one before the stop's
    gap, whose tolerance, 0 under ``G61``, held the next arc's start to 0 before). Key: the near vertex; else, on a line, the
    vertex ``clip(block, 0, M - 2)``; else (inside an arc) ``M - 1 + block``; ``-1`` on a one-block
    path's line. It is over when its distance is above ``verified_bound(tolerance) + slack``
    (the same product and sums, compiled without contraction into a fused multiply-add; ``slack``
    [mm]: the profile's own rounding, ``_fir_verify.profile_rounding``). A sample kept
    (``redo[key]``; with an empty ``redo``, every key ``>= 0``) and not over raises ``worst[key]``
    to its distance, in place.

    Returns:
        ``(largest distance of the samples not over (-inf if none), over (V,) indices, their
        distances, tolerances, keys and kept flags, the tolerance (N,) and key (N,) of every
        sample)``.
    """
    N, C = t.size, centre.size
    M = C + 1
    whole = redo.size == 0
    s_limit, s_key = np.empty(N), np.empty(N, np.int64)
    over = np.empty(N, np.int64)
    o_dist, o_limit, o_key, o_keep = np.empty(N), np.empty(N), np.empty(N, np.int64), np.empty(N, np.bool_)
    deviation = -np.inf
    n_over, hint = 0, 0
    for i in range(N):
        dist = math.sqrt(min(min(d2[i, 0], d2[i, 1]), d2[i, 2]))
        b = block[i]
        lim = tol_block[b]
        near = -1
        if M > 1:
            hint = _left_from(centre, t[i], hint)
            k = min(max(hint, 1), M - 1)
            k2 = min(k, M - 2)
            j = k - 1 if abs(centre[k - 1] - t[i]) <= abs(centre[k2] - t[i]) else k2
            if abs(centre[j] - t[i]) <= half_window:
                if stopped.size and stopped[j]:  # the block on its side of the stop, not the window's
                    b = j if t[i] < centre[j] else j + 1
                    lim = tol_block[b]
                else:
                    near = j
                    lim = min(lim, min(tol_block[j], tol_block[j + 1]))
        if near >= 0:
            key = near
        elif not is_arc[b]:
            key = min(max(b, 0), max(M - 2, 0)) if M > 1 else -1
        else:
            key = M - 1 + b
        keep = key >= 0 if whole else redo[key]
        s_limit[i], s_key[i] = lim, key
        if dist > (lim * (1.0 + VERIFY_RTOL) + VERIFY_ATOL) + slack:
            over[n_over], o_dist[n_over], o_limit[n_over], o_key[n_over], o_keep[n_over] = i, dist, lim, key, keep
            n_over += 1
        else:
            deviation = max(deviation, dist)
            if keep and dist > worst[key]:
                worst[key] = dist
    # the violations copied out of their (N,) buffers: they wait in batches across chunks
    # (``_fir_verify._scan``), where views would keep every chunk's buffers (0.6 kB a segment)
    return (deviation, over[:n_over], o_dist[:n_over].copy(), o_limit[:n_over].copy(), o_key[:n_over].copy(),
            o_keep[:n_over].copy(), s_limit, s_key)
