"""The limit ratios of a candidate's verification rounds, recomputed only where its profile's input changed.

Each limit-holding round (``plan_fir(..., limits=...)``) reads the peak ratios of every corner
window ``[end_k, start_(k+1) + T_d]`` and every own span ``[start_k + T_d, end_k]`` of the new
profile (``_fir_limits.corner_limit_ratios``, ``own_span_ratios``). A round's repairs change a
few blocks' feeds and a few corners' overlaps; elsewhere the new profile is the old one shifted in
time. The filtered output at ``t`` depends on the input on ``[t - T_d, t]`` only (Sencer 2015 eq
1-4: moving averages of total delay ``T_d``), so:

* an own span depends on its block's pulse alone (the neighbours' outputs have ended or not begun);
* a corner window on the pulses of the blocks meeting ``[end_k - T_d, start_(k+1) + T_d]``, and on
  the dwells between them (and on either side, which place the next blocks).

:class:`RoundPeaks` keeps each window's ratio and recomputes, from the new profile's pieces, only
the windows whose input changed (all of them in a candidate's first round, or where many did). A
kept ratio is the new one up to rounding (the pieces' local coefficients and lengths at another
time offset, ~1e-13 relative), but for a window's end pieces (below). Every decision of a round is a comparison with
``1 + LIMIT_RTOL``, and the ratios above it are used as values (the slow-downs of ``plan_fir``):
so a kept ratio within ``THRESHOLD_GUARD`` of it, or next to a window that is, is recomputed too.
The second condition covers a window's ends: a window and its neighbours in time share their end
breaks, and where the profile's break lay an ulp beyond the window's end the window read the
neighbour's next piece as well, which a ratio kept from a round without that rounding lacks; that
piece is within the neighbour's ratio. (Windows now read only the pieces they overlap by more than
``_fir_piece_peaks.WINDOW_ULPS`` spacings, so such a piece is no longer read; the condition stays
as a guard.) Then each comparison comes out as with every ratio
recomputed, and every ratio above the threshold is the recomputed one, to the bit.
"""

from __future__ import annotations

import numpy as np

from research.interpolators._fir_limits import LIMIT_RTOL, THRESHOLD_GUARD
from research.interpolators._fir_piece_peaks import (
    DEGENERATE_PIECE,
    PiecePeaks,
    piece_ratios_at,
    range_max,
    window_interiors,
    window_maxima,
)
from research.limits import AxisLimits

#: above this share of its windows changed, a round reads every piece (``PiecePeaks``: one
#: compiled pass and a sparse table are cheaper than gathering most of the pieces)
FULL_SHARE = 0.25


class RoundPeaks:
    """Corner-window and own-span ratios of one candidate's rounds (module docstring).

    Args:
        table: the path's ``_fir_blocks.PulseTable``; limits: the per-axis limits;
        total_delay: ``T_d`` [s].

    Attributes:
        recomputed: windows recomputed by the last call (all ``2 M - 1`` on the whole profile).
    """

    def __init__(self, table, limits: AxisLimits, total_delay: float):
        self._arc_block = np.asarray(table.block)[table.arc_pieces]
        self.limits, self.total_delay = limits, float(total_delay)
        self._limit = np.ascontiguousarray(np.stack([limits.velocity, limits.acceleration, limits.jerk]),
                                           dtype=np.float64)
        self._last = None  # the last round's inputs and ratios
        self.recomputed = 0

    def __call__(self, position, starts, pulse_times, overlaps, factor, head, tail, arc_rel):
        """``(corner (M - 1,), own (M,))`` ratios of this round's profile, as
        ``corner_limit_ratios`` and ``own_span_ratios`` of its ``PiecePeaks``.

        Args:
            position: the profile (``NumpyPiecewise``); starts, pulse_times: ``(M,)`` [s];
            overlaps: ``(M - 1,)`` corner overlaps [s] (the dwells ``T_d - T_k``);
            factor ``(M, 3)``, head, tail ``(M,)``, arc_rel ``(A,)`` or None: the feed factors and
            line shares the profile was built from (``PulseTable.pieces``; copied, not kept).
        """
        Td = self.total_delay
        starts = np.asarray(starts, dtype=np.float64)
        ends = starts + np.asarray(pulse_times, dtype=np.float64)
        M = starts.size
        lo_own, hi_own = starts + Td, ends.copy()
        lo_own[0] = starts[0]
        hi_own[-1] = ends[-1] + Td
        some = hi_own > lo_own
        lo = np.concatenate([ends[:-1], lo_own])  # the corner windows, then the own spans
        hi = np.concatenate([starts[1:] + Td, hi_own])
        key = (np.array(factor), np.array(head), np.array(tail), None if arc_rel is None else np.array(arc_rel),
               np.array(overlaps))
        use = np.concatenate([np.ones(M - 1, dtype=bool), some])  # the windows that are not empty
        last, self._last = self._last, None
        fresh = None
        if last is not None:
            fresh = self._changed(last[0], key, starts, ends) | (use != last[1])
        if fresh is None or np.count_nonzero(fresh) > FULL_SHARE * fresh.size:
            values = np.zeros(2 * M - 1)
            values[use] = PiecePeaks(position, self.limits).over(lo[use], hi[use])
            self.recomputed = values.size
        else:
            values = np.where(use, last[2], 0.0)
            fresh &= use
            values[fresh] = self._windows(position, lo[fresh], hi[fresh])
            again = ~fresh & use & self._near(values, M)
            if again.any():
                values[again] = self._windows(position, lo[again], hi[again])
            self.recomputed = int(np.count_nonzero(fresh) + np.count_nonzero(again))
        self._last = (key, use, values)
        return values[: M - 1].copy(), values[M - 1:].copy()

    def _changed(self, last, key, starts, ends) -> np.ndarray:
        """``(2 M - 1,)`` True for the windows (corners, then own spans) whose input differs from
        the last round's (``last``, ``key``: the inputs of :meth:`__call__`): a block's pulse (its
        feed factors, shares or sub-arc factors) or a dwell."""
        (factor, head, tail, arc_rel, overlaps), M = last, starts.size
        block = np.any(key[0] != factor, axis=1) | (key[1] != head) | (key[2] != tail)
        if arc_rel is not None:
            block[self._arc_block[key[3] != arc_rel]] = True
        dwell = key[4] != overlaps
        Td = self.total_delay
        # corner k: the blocks meeting [end_k - T_d, start_k+1 + T_d] (one more either side), the dwells around them
        a = np.maximum(np.searchsorted(ends, ends[:-1] - Td, side="right") - 1, 0)
        b = np.minimum(np.searchsorted(starts, starts[1:] + Td, side="left"), M - 1)
        cb = np.concatenate([[0], np.cumsum(block)])
        cd = np.concatenate([[0], np.cumsum(dwell)])
        d0, d1 = np.maximum(a - 1, 0), np.minimum(b, M - 2)
        corner = (cb[b + 1] - cb[a] > 0) | (cd[d1 + 1] - cd[d0] > 0)
        return np.concatenate([corner, block])

    @staticmethod
    def _near(values: np.ndarray, M: int) -> np.ndarray:
        """``(2 M - 1,)`` True for the windows within ``THRESHOLD_GUARD`` of ``1 + LIMIT_RTOL`` or
        above, or next to one in time (corner ``k``: own spans ``k``, ``k + 1``, corners ``k +- 1``;
        own span ``k``: corners ``k - 1``, ``k``)."""
        high = values > 1.0 + LIMIT_RTOL - THRESHOLD_GUARD
        hc, ho = high[: M - 1], high[M - 1:]
        pad = np.concatenate([[False], hc, [False]])  # corners -1 .. M - 1
        corner = hc | ho[:-1] | ho[1:] | pad[:-2] | pad[2:]
        own = ho | pad[:-1] | pad[1:]
        return np.concatenate([corner, own])

    def _windows(self, position, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
        """``PiecePeaks(position).over(lo, hi)`` from the pieces these windows meet only (the same floats)."""
        if lo.size == 0:
            return np.zeros(0)
        lo, hi = window_interiors(lo, hi)
        breaks = np.asarray(position.breaks, dtype=np.float64)
        coeffs = np.asarray(position.coeffs, dtype=np.float64)
        K = coeffs.shape[0]
        first = np.clip(np.searchsorted(breaks, lo, side="right") - 1, 0, K - 1)
        last = np.clip(np.searchsorted(breaks, hi, side="left"), first + 1, K)
        h = np.diff(breaks)
        if coeffs.shape[1] != 4:  # above cubic degree: roots only where a window's largest may be
            return window_maxima(np.ascontiguousarray(coeffs), h, self._limit, first, last)
        mark = np.zeros(K + 1, dtype=np.int64)
        np.add.at(mark, first, 1)
        np.add.at(mark, last, -1)
        pieces = np.flatnonzero(np.cumsum(mark[:K]) > 0)
        ratio = piece_ratios_at(coeffs, h, self._limit, pieces)
        per_piece = np.zeros(K)
        per_piece[pieces] = np.where(h[pieces] > DEGENERATE_PIECE, ratio, 0.0)
        return range_max(per_piece, first, last)

