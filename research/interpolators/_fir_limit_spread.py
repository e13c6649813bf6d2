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

Phase 1 alone slows every block of such a chain to the feed of a start from rest (a line cut
into blocks under a jerk limit below ``F / (T_1 T_2)``: every block at ``J T_1 T_2``, 6x the time
at the velocity limit). So a block in a breaking window first takes the largest feed whose velocity
steps to its set neighbours keep the limits (:class:`FeedSteps`, closed form for isolated steps:
a staircase of feeds back up to the commanded one), kept where the exact profile of the blocks
around it confirms the steps' windows; where it does not (pulses shorter than ``T_d``: the steps
interact), the feed of its slowest set neighbour (a plateau, from which a later block steps);
phase 1 alone where neither holds, for arcs and blocks whose step bound is infeasible, after
:data:`MAX_STEPS` such feeds of one block (each only lowers it),
and where phase 1 gives the block a higher feed (a block shorter than ``T_1`` peaks below its
input's level alone: the step bound, at steady state, is then the lower one). A block whose walk goes on (a set neighbour on one side only) has the blocks beyond it proposed
in the same step, in runs that double while every one takes a feed (:data:`MAX_WALK`), the rest
of a run dropped after a proposal the exact profile rejects (:func:`_connected`; a 4,000-chord
circle under limits: 6.0 -> 2.9 s). A line whose pieces run at different feeds (the look-ahead's
head and tail) is scaled as a whole, its step taken by the piece facing the neighbour. Blocks set so are not marked as checked alone: a later round's window above a limit still
checks them alone, as before.

Nothing here decides the plan alone: a window is taken as breaking only ``THRESHOLD_GUARD`` above
``1 + LIMIT_RTOL`` (the rounding of the other time offset cannot flip it), and the next round reads
every window of the whole profile as before.
"""

from __future__ import annotations

import copy
from collections.abc import Callable, Generator

import numpy as np

from research.interpolators._fir_feed_steps import feed_steps
from research.interpolators._fir_limits import LIMIT_RTOL, THRESHOLD_GUARD, isolated_step
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
        turn: the corners' speed change (``_fir_overlap.corner_speed_change``).
    """

    def __init__(self, table, lengths: np.ndarray, feeds: np.ndarray, t_in: np.ndarray, t_out: np.ndarray,
                 tol_vertex: np.ndarray, delays: np.ndarray, limits: AxisLimits, turn: bool):
        self.table, self.limits, self.turn = table, limits, turn
        M = table.n_blocks
        self.lengths, self.feeds = np.asarray(lengths, dtype=np.float64)[:M], np.asarray(feeds, dtype=np.float64)[:M]
        self.t_in, self.t_out = np.asarray(t_in, dtype=np.float64), np.asarray(t_out, dtype=np.float64)
        self.tol = np.asarray(tol_vertex, dtype=np.float64)
        self.delays = np.asarray(delays, dtype=np.float64)
        self.total_delay = 0.0
        for d in self.delays.tolist():  # summed in order, as the profile build does
            self.total_delay += d
        # block k's input pulse at its commanded feed, pulses end to end: [T[k], T[k + 1]] (_reach)
        self._shortest = np.concatenate([[0.0], np.cumsum(self.lengths / self.feeds)])

    def breaking(self, corners: np.ndarray, head, tail, factor, arc_rel, full, shrink, others) -> np.ndarray:
        """``(M,)`` True for the blocks in the window of a corner of ``corners`` (``(C,)`` indices)
        whose largest ``peak / limit`` exceeds ``1 + LIMIT_RTOL + THRESHOLD_GUARD`` in the plan of
        feed factors ``factor`` ``(M, 3)``, line shares ``head``, ``tail``, sub-arc factors
        ``arc_rel``, full-overlap flags ``full``, overlap multipliers ``shrink`` and tolerance
        shares ``others`` (``(M - 1,)``, as ``_fir_profile.timing``)."""
        out = np.zeros(self.table.n_blocks, dtype=bool)
        corners = np.unique(np.asarray(corners, dtype=np.int64))
        if corners.size == 0:
            return out
        ratios, (blocks, first, last) = self.with_blocks(corners, head, tail, factor, arc_rel, full, shrink, others)
        for c in np.flatnonzero(ratios > 1.0 + LIMIT_RTOL + THRESHOLD_GUARD):
            out[blocks[first[c]:last[c]]] = True
        return out

    def ratios(self, corners: np.ndarray, head, tail, factor, arc_rel, full, shrink, others) -> np.ndarray:
        """``(C,)`` largest ``peak / limit`` in the windows of ``corners`` (distinct, ascending) in
        the plan of :meth:`breaking`'s arguments."""
        corners = np.asarray(corners, dtype=np.int64)
        if not corners.size:
            return np.zeros(0)
        return self.with_blocks(corners, head, tail, factor, arc_rel, full, shrink, others)[0]

    def with_blocks(self, corners, *plan):
        """``(ratios (C,), (blocks, first, last))``: the largest ``peak / limit`` in the windows of
        ``corners`` (distinct, ascending) in the plan of :meth:`breaking`'s arguments, and the
        blocks each covers (window ``c``: ``blocks[first[c]:last[c]]``), read by :meth:`_read` on
        block ranges grown until each window's input lies within them."""
        M = self.table.n_blocks
        lo_blk, hi_blk = self._reach(corners)
        while True:
            ratios, windows, (back, ahead) = self._read(corners, lo_blk, hi_blk, *plan)
            if back.all() and ahead.all():
                return ratios, windows
            # a window whose input reaches past its blocks: twice as many blocks on that side
            lo_blk = np.where(back, lo_blk, np.maximum(lo_blk - 2 * (corners - lo_blk + 1), 0))
            hi_blk = np.where(ahead, hi_blk, np.minimum(hi_blk + 2 * (hi_blk - corners), M - 1))

    def _reach(self, corners):
        """First block ranges of the corners' windows: the blocks whose input pulses, laid end to
        end at their commanded feeds without the dwells between them, meet ``T_d`` before block
        ``k``'s end or after block ``k + 1``'s start, and one more either side (at least ``k - 1 ..
        k + 2``). Feed factors (at most 1) and dwells only make the pulses longer and put them
        further apart, so these hold each window's input (``_read`` confirms it and grows a range
        that does not): one profile build a call instead of doubling from four blocks (a window
        at 200 mm/s with ``T_d`` = 90 ms covers 18 mm, a hundred blocks of a CAM program)."""
        M = self.table.n_blocks
        T, t = self._shortest, self._shortest[corners + 1]
        lo_blk = np.minimum(np.searchsorted(T, t - self.total_delay, side="right") - 2, corners - 1)
        hi_blk = np.maximum(np.searchsorted(T, t + self.total_delay, side="left"), corners + 2)
        return np.maximum(lo_blk, 0), np.minimum(hi_blk, M - 1)

    def _read(self, corners, lo_blk, hi_blk, head, tail, factor, arc_rel, full, shrink, others):
        """Ratios of the corners' windows, the blocks in each, and whether each window's input lies
        within its blocks ``lo_blk .. hi_blk`` (before, after); the block ranges merged where they
        meet, and the merged ranges built as one profile, each after an exact stop."""
        table, Td = self.table, self.total_delay
        M = table.n_blocks
        # the merged [a, z] block ranges: a range starts a run where it begins past every range
        # before it ends (+ 1: ranges that meet join)
        order = np.argsort(lo_blk, kind="stable")
        a_s, z_s = lo_blk[order], hi_blk[order]
        reach = np.maximum.accumulate(z_s)
        first = np.concatenate([[True], a_s[1:] > reach[:-1] + 1])
        run_a = a_s[first]
        run_z = reach[np.append(np.flatnonzero(first)[1:] - 1, z_s.size - 1)]
        blocks = _ranges(run_a, run_z + 1)
        n = blocks.size
        # each run's pieces (contiguous in the table), the gap piece after its last block but the last run's
        piece_end = table.last_motion[run_z] + 1
        piece_end[:-1] += 1
        idx = _ranges(table.first_motion[run_a], piece_end)
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
                                    full[k], shrink[k], others[k], self.tol[k], self.delays, self.turn)
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


def _ranges(starts: np.ndarray, stops: np.ndarray) -> np.ndarray:
    """``concatenate([arange(a, b) for a, b in zip(starts, stops)])`` for ascending, disjoint
    ranges ``a < b``, without a Python loop."""
    sizes = stops - starts
    out = np.ones(int(sizes.sum()), dtype=np.int64)
    out[0] = starts[0]
    heads = np.cumsum(sizes)[:-1]
    out[heads] = starts[1:] - stops[:-1] + 1  # the jump from one range's last element to the next's first
    return np.cumsum(out)


class FeedSteps:
    """The largest feed of a line block whose velocity steps to its neighbours keep the limits.

    An isolated step ``dV`` of the input velocity through the FIR chain ``T_1 >= T_2 >= ...``
    peaks at ``|dV_i| / T_1`` in acceleration and ``|dV_i| / (T_1 T_2)`` in jerk on each axis (the
    trapezoidal acceleration of Sencer 2015 §2.1, whose rest-to-rest pulse is a step from 0), so
    a line at feed ``x`` along ``u`` next to a neighbour at velocity ``V`` keeps axis ``i`` where
    ``|x u_i - V_i| <= min(A_i T_1, J_i T_1 T_2)``, and ``x |u_i| <= v_i``: an interval of ``x`` per
    axis and neighbour (for a line in pieces, the piece facing the neighbour, the block's factors
    scaled alike). That is a staircase of feeds (a ramp from a slowed block back up to the
    commanded feed) where phase 1 would slow each block to what it keeps alone (every block of a
    chain at the feed of a start from rest). The bound is exact for isolated steps only (pulses of
    ``T_d`` or more either side, full overlap): :func:`spread_slow_down` checks every proposal on
    the exact profile and takes phase 1 where it fails.

    Args:
        feeds: ``(M,)`` commanded feeds [mm/s]; t_in: ``(M, d)`` block directions at their starts
            (a line's direction); is_arc: ``(M,)``; delays: ``(n,)`` [s]; limits: the axis limits.
    """

    def __init__(self, feeds, t_in, is_arc, delays, limits: AxisLimits):
        self.step = np.ascontiguousarray(isolated_step(delays, limits), dtype=np.float64)  # (A,) largest isolated step [mm/s]
        self.velocity = np.ascontiguousarray(limits.velocity, dtype=np.float64)
        self.feeds = np.ascontiguousarray(feeds, dtype=np.float64)
        self.u, self.is_arc = np.ascontiguousarray(t_in, dtype=np.float64), np.ascontiguousarray(is_arc, dtype=bool)
        self.head = self.tail = np.zeros(self.feeds.size)
        self._columns = None  # each block's factor column facing its start and its end (made on first use)

    def of(self, head: np.ndarray, tail: np.ndarray) -> "FeedSteps":
        """The same bounds for a candidate whose lines have head and tail shares ``head``, ``tail``
        ``(M,)`` (its pieces of their own feed factors: the piece facing a neighbour takes the step)."""
        out = copy.copy(self)
        out.head, out.tail, out._columns = np.asarray(head), np.asarray(tail), None
        return out

    def columns(self) -> tuple[np.ndarray, np.ndarray]:
        """``(M,)`` int64 each: the feed-factor column of every block's piece facing its start and
        its end, head / body / tail, the first of them that is not empty from that side (made once
        per head and tail shares)."""
        if self._columns is None:
            body = 1.0 - self.head - self.tail
            self._columns = (np.where(self.head > 0.0, 0, np.where(body > 0.0, 1, 2)).astype(np.int64),
                             np.where(self.tail > 0.0, 2, np.where(body > 0.0, 1, 0)).astype(np.int64))
        return self._columns

    def facing_feeds(self, factor: np.ndarray, blocks: np.ndarray, side: int) -> np.ndarray:
        """``(B,)`` feeds [mm/s] of the pieces of ``blocks`` facing their start (``side`` -1) or end
        (+1) at feed factors ``factor`` ``(M, 3)`` (:meth:`columns`)."""
        blocks = np.asarray(blocks, dtype=np.int64)
        return self.feeds[blocks] * factor[blocks, self.columns()[int(side > 0)][blocks]]

    def __call__(self, factor: np.ndarray, which: np.ndarray, fixed: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(multipliers, within, unset)``: ``(M,)`` feed multipliers ``< 1`` of the blocks ``which``
        (each block's factors scaled alike) under which the steps between their pieces facing their
        ``fixed`` neighbours and those neighbours' facing pieces keep the limits (NaN where there
        is none: an arc or an arc neighbour, no fixed neighbour, no feasible multiplier); ``(M,)``
        True where a block's feed is already within the bound; ``(M,)`` True where a block has no
        fixed neighbour yet. Blocks in path order, then back, each one set counting as fixed for
        the next (a ramp of several blocks in one call)."""
        M = self.feeds.size
        out, within, unset = np.full(M, np.nan), np.zeros(M, dtype=bool), np.zeros(M, dtype=bool)
        # the walk of runs right, then left, compiled (``_fir_feed_steps``: the loop it replaces,
        # operation for operation)
        feed_steps(self.feeds, np.ascontiguousarray(factor, dtype=np.float64), *self.columns(), self.u, self.step,
                   self.velocity, self.is_arc, np.ascontiguousarray(fixed, dtype=bool),
                   np.flatnonzero(which).astype(np.int64), out, within, unset)
        return out, within, unset

    def levels(self, factor: np.ndarray, which: np.ndarray, fixed: np.ndarray) -> np.ndarray:
        """``(M,)`` multipliers that bring the pieces of the blocks ``which`` facing their ``fixed``
        neighbours to those neighbours' facing feeds, the lowest of them (NaN where that is not
        lower); along runs walking right, then left, each one set counting as fixed for the next."""
        M = which.size
        out = np.full(M, np.nan)
        g_set = {}
        start, end = self.columns()
        ks = np.flatnonzero(which).tolist()
        for n in ks + ks[::-1]:
            if n in g_set:
                continue
            g = np.inf
            for k in (n - 1, n + 1):
                if 0 <= k < M and (fixed[k] or k in g_set):
                    side = -1 if k < n else 1
                    own = self.feeds[n] * factor[n, (start if side < 0 else end)[n]]  # n's piece facing k
                    theirs = self.feeds[k] * factor[k, (end if side < 0 else start)[k]] * g_set.get(k, 1.0)
                    g = min(g, theirs / own)
            if g < 1.0 - 1e-12:
                out[n] = g_set[n] = g
        return out


#: times one block's feed may be lowered by :class:`FeedSteps` within one spread (then phase 1)
MAX_STEPS = 8
#: most blocks proposed in one step beyond a block whose walk goes on (its run doubles while every
#: proposal holds on the exact profile, and starts again at 1 after a rejection)
MAX_WALK = 256


def _checked_steps(ok, prop, factor, fixed, ratios, thr) -> np.ndarray:
    """``ok`` less the proposals next to a corner whose window breaks a limit with every proposal
    ``prop`` applied (the corners between a proposed block and a set or proposed neighbour)."""
    M = ok.size
    k = np.flatnonzero(ok)
    set_ = fixed | ok
    left = k[(k > 0) & set_[np.maximum(k - 1, 0)]] - 1
    right = k[(k < M - 1) & set_[np.minimum(k + 1, M - 1)]]
    cs = np.unique(np.concatenate([left, right]))
    bad = cs[ratios(factor * np.where(ok, prop, 1.0)[:, None], cs) > thr]
    out = ok.copy()
    out[bad] = out[bad + 1] = False
    return out


def _connected(ok: np.ndarray, fixed: np.ndarray) -> np.ndarray:
    """The blocks of ``ok`` joined to a ``fixed`` block through ``ok`` blocks (a run's proposals
    rest on those before it: after a rejected one, the rest of its run is dropped too)."""
    out = np.zeros(ok.size, dtype=bool)
    for order, side in ((np.flatnonzero(ok), -1), (np.flatnonzero(ok)[::-1], 1)):
        for k in order.tolist():
            j = k + side
            if 0 <= j < ok.size and (fixed[j] or (out[j] and ok[j])):
                out[k] = True
    return out & ok


def spread_slow_down(slowed: np.ndarray, checked: np.ndarray, factor: np.ndarray,
                     breaking: Callable[[np.ndarray, np.ndarray], np.ndarray],
                     hold: Callable[[np.ndarray, np.ndarray], np.ndarray], steps: FeedSteps,
                     ratios: Callable[[np.ndarray, np.ndarray], np.ndarray]) -> Generator[np.ndarray, None, np.ndarray]:
    """Follow the slow-down of the blocks ``slowed`` along the chain (module docstring), one step
    at a time: a generator that yields the feed factors after each step that slows blocks and
    returns the final ones (``StopIteration.value``). The planner may suspend it between steps
    (another candidate's bound is lower) and resume it where it stopped: the steps are those of
    an uninterrupted walk.

    Args:
        slowed: ``(M,)`` bool, the blocks just slowed (their factors already in ``factor``).
        checked: ``(M,)`` bool, the blocks checked alone so far; updated in place.
        factor: ``(M, 3)`` feed factors of the plan (not changed; the result is a new array).
        breaking: ``(factor, corners) -> (M,)`` bool, the blocks in the windows of ``corners``
            that break a limit at those factors (:meth:`CornerWindows.breaking`).
        hold: ``(factor, which) -> (M,)`` feed multipliers under which the blocks ``which`` alone
            keep the limits at those factors (``_fir_limits.hold_block_limits``).
        steps, ratios: a block in such a window first takes the feed of :class:`FeedSteps` (a
            step from its slowed neighbours), kept where ``ratios(factor, corners)``
            (:meth:`CornerWindows.ratios`) finds the windows of those steps within the limits;
            phase 1 (``hold``) otherwise, and after :data:`MAX_STEPS` such feeds.

    Yields:
        The feed factors after each step (a new array each time).

    Returns:
        The feed factors with every slow-down that the chain's windows call for applied.
    """
    M = slowed.size
    ahead = np.full(M, np.nan)  # multipliers of blocks checked ahead of the step that reaches them
    run = 1
    new = np.asarray(slowed, dtype=bool)
    fixed = new.copy()  # the blocks whose feeds this spread has set
    stepped = np.zeros(M, dtype=np.int64)
    span = 1  # blocks proposed beyond each walking block (doubled while every proposal holds)
    thr = 1.0 + LIMIT_RTOL + THRESHOLD_GUARD
    while True:
        ks = np.flatnonzero(new)
        corners = np.unique(np.concatenate([ks - 1, ks]))
        corners = corners[(corners >= 0) & (corners < M - 1)]
        near = breaking(factor, corners) & ~checked if corners.size else np.zeros(M, dtype=bool)
        if not near.any():
            return factor
        walk = near.copy()
        if span > 1:
            # the blocks beyond each one of a walk (set on one side only), proposed in the same step
            for n in np.flatnonzero(near).tolist():
                left, right = n > 0 and fixed[n - 1], n < M - 1 and fixed[n + 1]
                if left != right:
                    d = 1 if left else -1
                    stop = min(max(n + d * span, -1), M)
                    for k in range(n + d, stop, d):
                        if checked[k] or fixed[k]:
                            break
                        walk[k] = True
        missing = walk & np.isnan(ahead)
        if missing.any():
            # phase 1 for every block in such a window (a step's feed is kept only where it is
            # higher), and ahead for the blocks within ``run`` of each one, in one call
            mark = np.zeros(M + 1, dtype=np.int64)
            m = np.flatnonzero(missing)
            np.add.at(mark, np.maximum(m - run, 0), 1)
            np.add.at(mark, np.minimum(m + run + 1, M), -1)
            batch = ((np.cumsum(mark)[:M] > 0) | walk) & ~checked & np.isnan(ahead)
            ahead[batch] = hold(factor, batch)[batch]
            run = min(2 * run, M)
        g = np.ones(M)
        prop, within, unset = steps(factor, walk & (stepped < MAX_STEPS), fixed)
        prop = np.where(prop > ahead, prop, np.nan)  # short blocks alone may run faster than a step allows
        ok = _connected(np.isfinite(prop), fixed | within)
        if ok.any():
            ok = _connected(_checked_steps(ok, prop, factor, fixed, ratios, thr), fixed | within)
            rejected = np.isfinite(prop) & ~ok
            if rejected.any():
                # steps too close in time for the isolated-step bound (pulses shorter than
                # T_d): the rejected blocks keep the feed of their slowest set neighbour, a
                # plateau from which a later block steps
                trial = factor * np.where(ok, prop, 1.0)[:, None]
                level = steps.levels(trial, rejected, fixed | ok)
                again = np.isfinite(level)
                if again.any():
                    again = _connected(_checked_steps(again, level, trial, fixed | ok, ratios, thr), fixed | ok | within)
                    prop = np.where(again, level, prop)
                    ok |= again
            # the run doubles while its blocks beyond the first all took a feed (step or plateau)
            span = min(2 * span, MAX_WALK) if not np.any(walk & ~near & ~ok & ~within) else 1
            g[ok] = prop[ok]
            stepped[ok] += 1
            fixed |= ok
            ahead[ok] = np.nan  # its factors change: an alone check made before no longer holds
        # a block already within its steps' bound, or with no neighbour set yet, waits for its
        # neighbours' new feeds, unless no block got one (then phase 1 for all)
        alone = near & ~ok & ~within & ~unset if ok.any() else near
        fixed |= within & ok.any()
        if alone.any():
            checked |= alone
            fixed |= alone
            g = np.where(alone, ahead, g)
        new = g < 1.0
        if not new.any():
            return factor
        factor = factor * g[:, None]
        yield factor
