"""Compiled (Numba) kernels of the FIR look-ahead's candidates (``_fir_lookahead``) and of their
predicted cycle time (``fir``'s branch and bound).

:func:`candidate_pieces` is a candidate's windows, block pieces and sub-arc feeds in one pass, with
:func:`line_piece_feeds` (the line pieces under the windows' staircase, :func:`staircase_cuts`
where a line has more than three steps) and the range minima of :func:`_range_min_into`;
:func:`predicted_cycle` is a candidate's predicted cycle time without its piece arrays. Each does
the operations of its NumPy form (``tests/interpolators``: bit for bit).
"""

from __future__ import annotations

import math

import numba
import numpy as np

from research._sorted_search import left_from, right_from
from research.interpolators._fir_kernels import _OPTIONS


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
                    last_motion, t_in, t_out, full, shrink, others, tol_v, delays, h_full, turn):
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
            ``(n,)`` sorted descending, ``n <= 2``; h_full: ``H2(T_d / 2)``; turn: the corners'
            speed change (``_fir_overlap.corner_speed_change``).
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
            bend = 0.0
            for c in range(dims):
                x = f_in * t_in[j + 1, c] - f_out * t_out[j, c]
                s += x * x
                bend += (t_in[j + 1, c] - t_out[j, c]) ** 2
            dF = math.sqrt(s)
            if turn:  # _fir_overlap.corner_speed_change
                dF = min(dF, max(f_in, f_out) * math.sqrt(bend))
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
def slowing_windows(F, s_v, full, f_full, hold):
    """The windows of :func:`candidate_pieces` that slow the path: those of the full-overlap
    vertices ``full`` ``(M - 1,)`` whose feed ``f_full`` (one per such vertex) is below the faster
    block at the vertex (``F`` ``(M,)`` [mm/s]), each ``[s_v - hold f, s_v + hold f]`` [mm] about
    its vertex's arc length ``s_v``. Returns ``(vertex, feed, lo, hi)``, one entry per window in
    path order (also ``_fir_lookahead.arc_cuts``: the same floats)."""
    V = full.size
    js, fs = np.empty(V, np.int64), np.empty(V)
    n, q = 0, 0
    for v in range(V):
        if full[v]:
            fv = f_full[q]
            q += 1
            if fv < max(F[v], F[v + 1]) * (1 - 1e-12):
                js[n], fs[n] = v, fv
                n += 1
    lo, hi = np.empty(n), np.empty(n)
    for w in range(n):
        j, fw = js[w], fs[w]
        half = hold[j]
        lo[w], hi[w] = s_v[j] - half * fw, s_v[j] + half * fw
    return js[:n], fs[:n], lo, hi


@numba.njit(**_OPTIONS)
def candidate_pieces(cum, L, F, s_v, full, f_full, hold, arc, span_start, span_end, arc_F):
    """``_fir_lookahead._candidate``'s windows, block pieces and sub-arc feeds in one compiled pass
    (the same operations per window, so bit for bit): the windows of the full-overlap vertices
    ``full`` ``(M - 1,)`` whose feed ``f_full`` (one per such vertex) is below the faster block at
    the vertex, held ``hold`` [s] each side, slow the blocks they cover (``body``, a minimum) and
    the head or tail of the blocks they reach into (:func:`line_piece_feeds`), and the sub-arcs
    ``[span_start, span_end]`` they overlap. Returns ``(head, tail, feeds (M, 3), arc_rel (A,))``,
    ``arc_rel`` the sub-arcs' feeds over ``arc_F``, at most 1."""
    M = L.size
    js, fs, lo, hi = slowing_windows(F, s_v, full, f_full, hold)
    n = js.size
    half = np.empty(n)
    first, last = np.empty(n, np.int64), np.empty(n, np.int64)
    k_r, k_l = np.empty(n, np.int64), np.empty(n, np.int64)
    for w in range(n):
        j = js[w]
        half[w] = hold[j]
        right = right_from(cum, hi[w], j + 1)
        first[w], last[w] = left_from(cum, lo[w], j + 1), right - 2
        k_r[w] = min(max(right - 1, 0), M - 1)
        k_l[w] = min(max(right_from(cum, lo[w], first[w]) - 1, 0), M - 1)
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
            a_first[w] = right_from(span_end, lo[w], a_first[w - 1] if w else 0)
            a_last[w] = left_from(span_start, hi[w], a_last[w - 1] + 1 if w else 0) - 1
        _range_min_into(arc_rel, a_first, a_last, fs[:n])
        for a in range(A):
            arc_rel[a] = min(arc_rel[a] / arc_F[a], 1.0)
    return head, tail, feeds, arc_rel
