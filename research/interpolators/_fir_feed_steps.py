"""The compiled loop of ``_fir_limit_spread.FeedSteps.__call__``: feed multipliers of line blocks
whose velocity steps to their fixed neighbours are isolated steps within the limits (Sencer 2015
§2.1), along runs walking right, then left.

The loop is the Python loop it replaces, operation for operation (the same comparisons in the same
order, Python's ``min`` / ``max`` on two floats written out: the first argument kept unless the
second is strictly smaller / larger), so the multipliers are the same bit for bit; compiled, a
walk along a chain of thousands of blocks no longer spends its time in the interpreter (a 2,434
chord program under one filter and tight limits spent 67 of 85 s there).
"""

from __future__ import annotations

import numba
import numpy as np

_OPTIONS = dict(cache=True, nogil=True, error_model="numpy")


@numba.njit(**_OPTIONS)
def feed_steps(feeds, factor, col_start, col_end, u, step, velocity, is_arc, fixed, ks, out, within, unset):
    """Fill ``out``, ``within``, ``unset`` ``(M,)`` (``FeedSteps.__call__``'s results; ``out`` NaN,
    the others False on entry) for the blocks ``ks`` (ascending), visited in path order and back.

    Args:
        feeds: ``(M,)`` commanded feeds [mm/s]; factor: ``(M, 3)`` feed factors (head, body, tail).
        col_start, col_end: ``(M,)`` the factor column of each block's piece facing its start / end.
        u: ``(M, d)`` line directions; step, velocity: ``(d,)`` isolated step and velocity limit [mm/s].
        is_arc, fixed: ``(M,)`` bool; ks: ``(K,)`` int64 blocks to set.
    """
    M = feeds.size
    g = np.ones(M)
    is_set = np.zeros(M, dtype=np.bool_)
    K = ks.size
    near = np.empty(2, dtype=np.int64)
    for i in range(2 * K):
        n = ks[i] if i < K else ks[2 * K - 1 - i]
        if is_set[n] or is_arc[n]:
            continue
        count = 0
        for k in (n - 1, n + 1):
            if 0 <= k < M and (fixed[k] or is_set[k]):
                near[count] = k
                count += 1
        unset[n] = count == 0
        if count == 0:
            continue
        arc_near = False
        for c in range(count):
            arc_near = arc_near or is_arc[near[c]]
        if arc_near:
            continue
        top = feeds[n] * np.max(factor[n])
        cap = np.inf
        first = True
        for a in range(u.shape[1]):
            if u[n, a] != 0.0:
                r = velocity[a] / abs(u[n, a])
                if first or r < cap:
                    cap = r
                    first = False
        r = cap / top
        lo, hi = 0.0, (r if r < 1.0 else 1.0)
        for c in range(count):
            k = near[c]
            side = -1 if k < n else 1
            x = feeds[n] * factor[n, col_start[n] if side < 0 else col_end[n]]
            s = feeds[k] * factor[k, col_end[k] if side < 0 else col_start[k]] * (g[k] if is_set[k] else 1.0)
            lo_k, hi_k = -np.inf, np.inf
            for a in range(u.shape[1]):
                V = s * u[k, a]
                u_a = u[n, a]
                if u_a == 0.0:
                    if abs(V) > step[a]:
                        lo_k = np.inf
                        break
                    continue
                p = (V - step[a]) / (u_a * x)
                q = (V + step[a]) / (u_a * x)
                small = q if q < p else p  # min(p, q)
                large = q if q > p else p  # max(p, q)
                lo_k = small if small > lo_k else lo_k
                hi_k = large if large < hi_k else hi_k
            if lo_k == np.inf:
                lo = np.inf
                break
            lo = lo_k if lo_k > lo else lo
            hi = hi_k if hi_k < hi else hi
        if not (lo <= hi and hi > 0.0):
            continue
        if hi < 1.0 - 1e-12:
            out[n] = hi
            g[n] = hi
        else:
            within[n] = True
            g[n] = 1.0
        is_set[n] = True
        unset[n] = False
