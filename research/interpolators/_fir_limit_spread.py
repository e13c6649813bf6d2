"""A slowed block's feed step, followed along the chain within one limit-holding round.

Phase 1 of ``_fir_limits`` slows a block that breaks a limit alone. Its neighbour then meets it
with a feed step, and on a chain of collinear or nearly collinear blocks (a line cut into blocks, a
finely tessellated curve) under limits below the FIR envelope that step breaks a limit at the
corner between them: a velocity step ``dV`` through the FIR chain peaks at ``|dV| / T_1`` and
``|dV| / (T_1 T_2)``, the same peaks as a block that starts from rest at ``dV`` (Sencer 2015
§2.1). The next round then found that corner, checked the neighbour alone and slowed it, and so
on: one block per round from each slowed block, ``N / 2`` rounds and a planning cost ~ ``N^2`` on
``N`` blocks (a 1,000 mm line cut into 2,000 blocks: 1,001 rounds, 4.2 s).

:func:`spread_slow_down` takes those steps within the round. After blocks are slowed it reads the
windows ``[end_k, start_(k+1) + T_d]`` of their corners at the new feeds, from the exact profile of
the blocks around each corner alone (:class:`CornerWindows`: the output at ``t`` averages the input
over ``[t - T_d, t]``, so a window depends only on the pulses and dwells that meet ``[end_k - T_d,
start_(k+1) + T_d]``; the local profile reads it up to the rounding of another time offset). The
unchecked blocks in a window above a limit are checked alone (phase 1) at once, as the next round
would check them, and the steps repeat until no block is slowed. Each step checks at least one
new block, so there are at most ``M`` steps, each local to the corners it reads.

Phase 1 checks blocks independently, so the blocks further along the chain are checked alone ahead
of the step that reaches them, in runs that double (1, 2, 4, ... blocks beyond the block reached,
:func:`spread_slow_down`), and their results kept until reached: the alone checks of a chain of
``N`` blocks cost ``O(N)`` pieces in ``O(log N)`` calls, not ``N`` calls.

Nothing here decides the plan alone: a window is taken as breaking only ``THRESHOLD_GUARD`` above
``1 + LIMIT_RTOL`` (the rounding of the other time offset cannot flip it), and the next round reads
every window of the whole profile as before.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from research.interpolators._fir_limits import LIMIT_RTOL, THRESHOLD_GUARD
from research.interpolators._fir_piece_peaks import PiecePeaks
from research.interpolators._fir_profile import profile, timing
from research.limits import AxisLimits
from research.piecewise import NumpyPiecewise


class CornerWindows:
    """Limit ratios of a few corners' windows, each from the exact profile of the blocks around it.

    Args:
        table: the path's ``_fir_blocks.PulseTable``.
        lengths, feeds: ``(M,)`` block lengths [mm] and commanded feeds [mm/s].
        t_in, t_out: ``(M, d)`` unit tangents at each block's start and end.
        tol_vertex: ``(M - 1,)`` corner tolerances [mm]; delays: ``(n,)`` filter delays [s].
        limits: the per-axis limits.
    """

    def __init__(self, table, lengths: np.ndarray, feeds: np.ndarray, t_in: np.ndarray, t_out: np.ndarray,
                 tol_vertex: np.ndarray, delays: np.ndarray, limits: AxisLimits):
        self.table, self.limits = table, limits
        M = table.n_blocks
        self.lengths, self.feeds = np.asarray(lengths, dtype=np.float64)[:M], np.asarray(feeds, dtype=np.float64)[:M]
        self.t_in, self.t_out = np.asarray(t_in, dtype=np.float64), np.asarray(t_out, dtype=np.float64)
        self.tol = np.asarray(tol_vertex, dtype=np.float64)
        self.delays = np.asarray(delays, dtype=np.float64)
        self.total_delay = 0.0
        for d in self.delays.tolist():  # summed in order, as the profile build does
            self.total_delay += d

    def breaking(self, corners: np.ndarray, head, tail, factor, arc_rel, full, shrink, others) -> np.ndarray:
        """``(M,)`` True for the blocks in the window of a corner of ``corners`` (``(C,)`` indices)
        whose largest ``peak / limit`` exceeds ``1 + LIMIT_RTOL + THRESHOLD_GUARD`` in the plan of
        feed factors ``factor`` ``(M, 3)``, line shares ``head``, ``tail``, sub-arc factors
        ``arc_rel``, full-overlap flags ``full``, overlap multipliers ``shrink`` and tolerance
        shares ``others`` (``(M - 1,)``, as ``_fir_profile.timing``)."""
        M = self.table.n_blocks
        out = np.zeros(M, dtype=bool)
        corners = np.unique(np.asarray(corners, dtype=np.int64))
        if corners.size == 0:
            return out
        lo_blk, hi_blk = np.maximum(corners - 1, 0), np.minimum(corners + 2, M - 1)
        while True:
            ratios, windows, covered = self._read(corners, lo_blk, hi_blk, head, tail, factor, arc_rel, full, shrink, others)
            back, ahead = covered
            if back.all() and ahead.all():
                break
            # a window whose input reaches past its blocks: twice as many blocks on that side
            lo_blk = np.where(back, lo_blk, np.maximum(lo_blk - 2 * (corners - lo_blk + 1), 0))
            hi_blk = np.where(ahead, hi_blk, np.minimum(hi_blk + 2 * (hi_blk - corners), M - 1))
        blocks, first, last = windows
        for c in np.flatnonzero(ratios > 1.0 + LIMIT_RTOL + THRESHOLD_GUARD):
            out[blocks[first[c]:last[c]]] = True
        return out

    def _read(self, corners, lo_blk, hi_blk, head, tail, factor, arc_rel, full, shrink, others):
        """Ratios of the corners' windows, the blocks in each, and whether each window's input lies
        within its blocks ``lo_blk .. hi_blk`` (before, after); the block ranges merged where they
        meet, and the merged ranges built as one profile, each after an exact stop."""
        table, Td = self.table, self.total_delay
        M = table.n_blocks
        order = np.argsort(lo_blk, kind="stable")
        runs = []  # merged [a, z] block ranges
        for a, z in zip(lo_blk[order].tolist(), hi_blk[order].tolist()):
            if runs and a <= runs[-1][1] + 1:
                runs[-1][1] = max(runs[-1][1], z)
            else:
                runs.append([a, z])
        blocks = np.concatenate([np.arange(a, z + 1) for a, z in runs])
        n = blocks.size
        last_run = len(runs) - 1
        # each run's pieces (contiguous in the table), the gap piece after its last block but the last run's
        idx = np.concatenate([np.arange(table.first_motion[a], table.last_motion[z] + 1 + (r < last_run))
                              for r, (a, z) in enumerate(runs)])
        local = np.empty(M, dtype=np.int64)  # position of a block in ``blocks``
        local[blocks] = np.arange(n)
        blk = local[table.block[idx]]
        frac, piece_factor = table.pieces_at(idx, head, tail, factor, arc_rel)
        pos = np.empty(table.block.size, dtype=np.int64)
        pos[idx] = np.arange(idx.size)
        motion_ends = np.stack([pos[table.first_motion[blocks]], pos[table.last_motion[blocks]]])
        tangents = np.stack([self.t_in[blocks], self.t_out[blocks]])
        k = np.minimum(blocks[:-1], M - 2)  # the corner after each block (a run's last: any, replaced)
        piece_tv, overlaps = timing(self.lengths[blocks], self.feeds[blocks], blk, piece_factor, motion_ends, tangents,
                                    full[k], shrink[k], others[k], self.tol[k], self.delays)
        joined = blocks[1:] == blocks[:-1] + 1
        gaps = np.append(np.where(joined, Td - overlaps, Td), 0.0)  # between runs: an exact stop
        starts, ends, breaks, coeffs, _ = profile(np.zeros(self.t_in.shape[1]), table.geo[idx], blk, table.gap[idx],
                                                  frac, piece_tv, gaps, self.delays)
        j = local[corners]
        lo, hi = ends[j], starts[j + 1] + Td
        ratios = PiecePeaks(NumpyPiecewise(breaks, coeffs), self.limits).over(lo, hi)
        a, z = local[lo_blk], local[hi_blk]
        back = (blocks[a] == 0) | (starts[a] <= lo - Td)
        ahead = (blocks[z] == M - 1) | (ends[z] >= hi)
        # the blocks whose filtered span [start, end + T_d] meets each window (as _fir_limits.blocks_in_windows)
        first = np.searchsorted(ends + Td, lo, side="right")
        last = np.searchsorted(starts, hi, side="left")
        return ratios, (blocks, first, last), (back, ahead)


def spread_slow_down(slowed: np.ndarray, checked: np.ndarray, factor: np.ndarray,
                     breaking: Callable[[np.ndarray, np.ndarray], np.ndarray],
                     hold: Callable[[np.ndarray, np.ndarray], np.ndarray]) -> np.ndarray:
    """Follow the slow-down of the blocks ``slowed`` along the chain (module docstring).

    Args:
        slowed: ``(M,)`` bool, the blocks just slowed (their factors already in ``factor``).
        checked: ``(M,)`` bool, the blocks checked alone so far; updated in place.
        factor: ``(M, 3)`` feed factors of the plan (not changed; the result is a new array).
        breaking: ``(factor, corners) -> (M,)`` bool, the blocks in the windows of ``corners``
            that break a limit at those factors (:meth:`CornerWindows.breaking`).
        hold: ``(factor, which) -> (M,)`` feed multipliers under which the blocks ``which`` alone
            keep the limits at those factors (``_fir_limits.hold_block_limits``).

    Returns:
        The feed factors with every slow-down that the chain's windows call for applied.
    """
    M = slowed.size
    ahead = np.full(M, np.nan)  # multipliers of blocks checked ahead of the step that reaches them
    run = 1
    new = np.asarray(slowed, dtype=bool)
    while True:
        ks = np.flatnonzero(new)
        corners = np.unique(np.concatenate([ks - 1, ks]))
        corners = corners[(corners >= 0) & (corners < M - 1)]
        near = breaking(factor, corners) & ~checked if corners.size else np.zeros(M, dtype=bool)
        if not near.any():
            return factor
        missing = near & np.isnan(ahead)
        if missing.any():
            # the blocks within ``run`` of each one not yet checked, checked alone in one call
            mark = np.zeros(M + 1, dtype=np.int64)
            m = np.flatnonzero(missing)
            np.add.at(mark, np.maximum(m - run, 0), 1)
            np.add.at(mark, np.minimum(m + run + 1, M), -1)
            batch = (np.cumsum(mark)[:M] > 0) & ~checked & np.isnan(ahead)
            ahead[batch] = hold(factor, batch)[batch]
            run *= 2
        checked |= near
        g = np.where(near, ahead, 1.0)
        new = g < 1.0
        if not new.any():
            return factor
        factor = factor * g[:, None]
