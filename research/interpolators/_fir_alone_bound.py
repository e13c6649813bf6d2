"""A closed-form upper bound on the peaks of a line block alone (phase 1 of ``_fir_limits``).

With every corner an exact stop, a line block's filtered output is its own velocity input alone:
a staircase ``s(t) u`` on ``[0, T_v]`` (unit direction ``u``; levels ``F f_i``, the feed times
each piece's factor; zero before and after) through the FIR chain ``T_1 >= T_2 >= ...`` (Sencer
2015 eq 1-4). Every filter is a moving average, so with ``0 <= s <= S`` (the highest level):

* velocity: ``s * b_1 * b_2 ...`` is an average of ``s``: ``|v_a| <= S |u_a|``;
* acceleration: ``d/dt (s * b_1) = (s(t) - s(t - T_1)) / T_1``, averaged by the other filters:
  ``|a_a| <= S |u_a| / T_1`` (eq 5/8: a rest-to-rest pulse peaks at ``F / T_1``);
* jerk (two filters or more): ``d^2/dt^2 (s * b_1 * b_2) = J(t) / (T_1 T_2)`` with
  ``J(t) = A(t) - A(t - T_1)`` and ``A(t) = s(t) - s(t - T_2)`` in ``[-S, S]``, averaged by the
  others; so ``|j_a| <= c S |u_a| / (T_1 T_2)``. ``c = 2`` in general, ``c = 1`` unless ``A(t)`` and
  ``A(t - T_1)`` can have opposite signs: ``A(t) > 0`` needs an up-step of ``s`` in ``(t - T_2, t]``,
  ``A(t) < 0`` a down-step there, so opposite signs need an up-step ``p`` and a down-step ``q``
  with ``T_1 - T_2 < |q - p| < T_1 + T_2``. For a single level this is the known doubling of a
  short block (``T_1 - T_2 < T_v < T_1 + T_2``, :func:`_fir_limits.feed_caps`); where no such pair
  exists ``|J| <= max(|A(t)|, |A(t - T_1)|) <= S``.

With one filter the exact profile is piecewise quadratic: its jerk on every piece is 0 (what the
exact peaks of ``_fir_piece_peaks.PiecePeaks`` read). Arc blocks (turning direction) get no bound.
"""

from __future__ import annotations

import numba
import numpy as np

#: step pairs within this [s] of the doubling interval's ends count as inside it: the times of a
#: block's steps in the exact profile differ from those computed here by rounding (~1e-14 s)
STEP_MARGIN = 1e-9


def alone_bounds(table, blocks: np.ndarray, fraction: np.ndarray, piece_factor: np.ndarray, lengths: np.ndarray,
                 feeds: np.ndarray, delays: np.ndarray, limits) -> np.ndarray:
    """``(M,)`` upper bound on the largest ``peak / limit`` of each line block in ``blocks`` alone
    (every corner an exact stop), over axes and velocity, acceleration, jerk; ``inf`` for arcs and
    the blocks not asked for.

    Args:
        table: the path's ``_fir_blocks.PulseTable``; ``blocks``: ``(M,)`` bool.
        fraction, piece_factor: ``(P,)`` share of its block and feed factor of every piece.
        lengths, feeds: block lengths [mm] and commanded feeds [mm/s] indexed by a piece's block
            (``(M_pad + 1,)``, as ``_fir_profile.timing``).
        delays: ``(n,)`` filter delays [s]; limits: the per-axis ``AxisLimits``.
    """
    d = np.sort(np.asarray(delays, dtype=np.float64))[::-1]
    ks = np.flatnonzero(blocks)
    ks = ks[table.role[table.first_motion[ks]] >= 0]  # lines (an arc's pieces have role -1)
    out = np.full(table.n_blocks, np.inf)
    if ks.size == 0:
        return out
    T1 = float(d[0])
    T2 = float(d[1]) if d.size > 1 else 0.0
    with np.errstate(divide="ignore"):  # a zero limit: no bound where an axis moves
        inv_limits = np.stack([1.0 / limits.velocity, 1.0 / (T1 * limits.acceleration),
                               (1.0 / (T1 * T2 * limits.jerk)) if d.size > 1 else np.zeros(limits.n_axes)])
    out[ks] = _bounds(ks, table.first_motion, table.last_motion, table.block, table.geo,
                      np.asarray(fraction, dtype=np.float64), np.asarray(piece_factor, dtype=np.float64),
                      np.asarray(lengths, dtype=np.float64), np.asarray(feeds, dtype=np.float64),
                      np.ascontiguousarray(inv_limits), T1, T2)
    return out


@numba.njit(cache=True, nogil=True, error_model="numpy")
def _bounds(ks, first_motion, last_motion, block, geo, fraction, piece_factor, lengths, feeds, inv_limits, T1, T2):
    """The bound of :func:`alone_bounds` for the line blocks ``ks`` (module docstring; ``geo``: the
    pieces' ``dP/du`` coefficients, a line's ``L u`` in row 0)."""
    out = np.empty(ks.size)
    A = geo.shape[2]
    width = 0
    for n in range(ks.size):
        width = max(width, last_motion[ks[n]] - first_motion[ks[n]] + 2)
    times, jumps = np.empty(width), np.empty(width)  # a block's steps: one per level change, and its stop
    for n in range(ks.size):
        k = ks[n]
        top, level, t, m = 0.0, 0.0, 0.0, 0
        for i in range(first_motion[k], last_motion[k] + 1):
            tv = lengths[block[i]] / (feeds[block[i]] * piece_factor[i])  # eq 5, as _fir_profile.timing
            dur = fraction[i] * tv
            if dur > 0.0:
                s = 1.0 / tv  # the level's speed per unit of dP/du (the profile's coefficient factor)
                if s != level:
                    times[m], jumps[m] = t, s - level
                    m += 1
                level, top, t = s, max(top, s), t + dur
        times[m], jumps[m] = t, -level
        m += 1
        c = 1.0
        for p in range(m):
            for q in range(m):
                if jumps[p] > 0.0 and jumps[q] < 0.0:
                    gap = abs(times[q] - times[p])
                    if T1 - T2 - STEP_MARGIN < gap < T1 + T2 + STEP_MARGIN:
                        c = 2.0
        best = 0.0
        for a in range(A):
            peak = abs(geo[first_motion[k], 0, a]) * top
            if peak > 0.0:
                best = max(best, peak * inv_limits[0, a], peak * inv_limits[1, a], c * peak * inv_limits[2, a])
        out[n] = best
    return out
