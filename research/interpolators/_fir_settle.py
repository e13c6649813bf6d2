"""Verification rounds and the branch and bound of one path's candidate plans: the core of
``fir.plan_fir`` on a path without pauses (beyond Sencer 2015; the method is in ``fir``'s module
docstring, "Verification and repair").

:func:`plan_blocks` takes the look-ahead's candidates (``_fir_lookahead``), settles each one round
by round (the exact profile, its vertex errors and path samples, ``_fir_verify``; the tolerance
repairs, ``_fir_repair``; with axis limits the corner bisections, blocks alone and chain
slow-downs of ``_fir_limits`` and ``_fir_limit_spread``), keeps the fastest verified plan and
returns its fields for ``fir.FIRPlan``.
"""

from __future__ import annotations

import functools
import heapq
import itertools
from types import SimpleNamespace

import jax
import jax.numpy as jnp
import numpy as np

from research._device import device_array, device_arrays
from research.errors import ConvergenceError, ParameterError
from research.interpolators._fir_blocks import PulseTable, build_profile
from research.interpolators._fir_feed import arc_feed_caps
from research.interpolators._fir_kernels import verified_bound
from research.interpolators._fir_candidate_kernels import predicted_cycle
from research.interpolators._fir_limits import (
    BISECTION_STEPS,
    LIMIT_RTOL,
    CornerBisection,
    alone_block_ratios,
    arc_limit_caps,
    blocks_in_windows,
    end_ramp_scale,
    feed_caps,
    futile_stops,
    hold_block_limits,
    isolated_step,
    window_slow_down,
)
from research.interpolators._fir_limit_spread import CornerWindows, FeedSteps, spread_slow_down
from research.interpolators._fir_lookahead import arc_cuts, look_ahead, with_table, without_dwells
from research.interpolators._fir_staircase import capped_staircase
from research.interpolators import _fir_profile
from research.interpolators._fir_overlap import corner_speed_change, overlap_time
from research.interpolators._fir_repair import Repairs
from research.interpolators._fir_round_peaks import RoundPeaks
from research.interpolators._fir_verify import RoundChecks, charged_repairs, profile_rounding, stop_rounding
from research.interpolators._fir_verify import vertex_distances
from research.paths.toolpath import ToolPath
from research.piecewise import NumpyPiecewise

_SCALING_ROUNDS = 6  # rounds that shrink overlaps / feeds before violators become exact stops
_LIMIT_ROUNDS = BISECTION_STEPS + 2  # bisections of the overlaps of corners that break axis limits
#: hard bound on verification rounds: the scaling rounds, the limit rounds, one exact-stop round
#: and rounds that slow arcs whose own deviation exceeds the tolerance (geometric, <= 0.7 a round);
#: with limits, ``M - 1`` more for corners that become exact stops one by one (``_fir_limits``)
MAX_ROUNDS = _LIMIT_ROUNDS + 24
#: the first check of a candidate that competes with others looks at the vertex errors of its first
#: ``M // _PREFIX_SHARE`` blocks first (``plan_fir``'s ``prefix_bound``), on paths of at least
#: ``_PREFIX_SHARE * _PREFIX_MIN_BLOCKS`` blocks
_PREFIX_SHARE = 8
_PREFIX_MIN_BLOCKS = 32
#: sent to a candidate suspended with its profile (``plan_fir``'s ``settle``) to release it; of
#: the candidates suspended with their profiles while another goes on, the ``_HELD_PROFILES`` of
#: least bound keep them. Swept (benchmarks/README.md, branch fir-mem2): 0 instead of 1 lowers the
#: peak by 0.7-1.0 kB/segment (one profile) for 1-3 more profile builds a plan on bench_fir's and
#: bench_cam's paths, 4-9 % slower at 10^4 segments
_RELEASE = object()
_HELD_PROFILES = 1
_NO_BISECTION = SimpleNamespace(scale=1.0, bound_scale=1.0)  # plan_fir's CornerBisection without limits


def plan_blocks(tp: ToolPath, feed, delays, tolerance, refine: bool, limits, check_period: float,
                traced: bool, turn: bool):
    """:func:`plan_fir` on a path without pauses, block by block (its inputs checked; ``traced``:
    an input is a JAX tracer; ``turn``: ``corner_speed == "turn"``). Returns ``(fields, (fraction, piece_tv, first_motion))``: the
    arguments of ``fir.FIRPlan`` in order (the plan), the share of its block's pulse and the pulse
    length [s] of each input piece ``(P,)`` (``_fir_profile.ProfileInputs``; the pulse lengths
    traced where the plan is) and the first piece of each block ``(M,)`` (of the plan's table: its
    sub-arcs may be cut), which map a merged plan back to its blocks (``_fir_straight.split_plan``)."""
    M = tp.n_blocks
    table = _pulse_table(tp)
    Mp = table.m_pad
    # the rounds decide on concrete arrays (``_fir_profile``: NumPy and Numba, no JAX dispatch); the
    # plan returned is rebuilt with JAX only where an input is a tracer (its differentiable form)
    xp = jnp if traced else np
    delays = xp.asarray(delays, dtype=np.float64).reshape(-1)
    feeds_cmd = xp.broadcast_to(xp.asarray(feed, dtype=np.float64), (M,))
    tol_block = xp.broadcast_to(xp.asarray(tolerance, dtype=np.float64), (M,))
    tol_vertex = xp.minimum(tol_block[:-1], tol_block[1:])
    d_np, F_np, tb_np = (np.asarray(_primal(x), dtype=np.float64) for x in (delays, feeds_cmd, tol_block))
    tv_np = np.minimum(tb_np[:-1], tb_np[1:])
    limit_v = verified_bound(tv_np)  # the verification's bound on vertex errors
    Td_np = float(d_np.sum())
    t_in, t_out = tp.tangents()

    # feed factors (NumPy, decided on primal values): (M, 3) for the head, body and tail of each block
    base = _arc_factor(tp, d_np, tb_np, F_np)
    if limits is not None:  # one limit per axis (checked by plan_fir)
        safe_feed = np.where(tp.is_arc, arc_limit_caps(tp.radii, d_np, limits), feed_caps(tp.lengths, t_in, d_np, limits))
    ahead = None  # the look-ahead's candidates at ``base``, made on the table before its sub-arcs are cut
    if refine and M > 1 and tp.is_arc.any() and limits is None:
        # sub-arcs cut where the candidates' windows end (``_fir_lookahead.arc_cuts``): a window
        # reaching into an arc slows the stretch it covers, not the whole sub-arc it ends in. Not
        # under limits: there the branch and bound started ~5x the candidates (their bounds lie
        # closer together) for 5-10 % shorter cycles at 1.65x the planning (benchmarks/README.md)
        ahead = look_ahead(tp, table, F_np, base, d_np, tv_np, t_in, t_out, turn)
        table = table.cut_arcs(tp, arc_cuts(ahead))
    head, tail = np.zeros(M), np.zeros(M)
    full = np.zeros(M - 1, dtype=bool)
    others = np.zeros(M - 1)  # tolerance taken by the other direction changes of a dwell corner's window
    feeds_np = np.concatenate([F_np, np.ones(Mp - M + 1)])
    pad_b = Mp - M  # per-block inputs padded to the bucketed block count (one compiled JAX kernel)
    lengths_np, cum_np, motion_ends_np, tangents_np = _padded(tp, table)
    windows = CornerWindows(table, tp.lengths, F_np, t_in, t_out, tv_np, d_np, limits, turn) if limits is not None else None
    steps = FeedSteps(F_np, t_in, tp.is_arc, d_np, limits) if limits is not None else None

    def timing(factor, head, tail, full, shrink, others, arc_rel, top=True):
        """Piece shares, pulse lengths, block top feeds (None unless ``top``) and overlaps of a
        plan (no filtering)."""
        frac, piece_factor = table.pieces(head, tail, factor, arc_rel)
        cruise = np.maximum.reduceat(piece_factor[: table.last_motion[-1] + 1], table.first_motion) if top else None
        piece_tv, overlaps = _fir_profile.timing(lengths_np, feeds_np, table.block, piece_factor, motion_ends_np,
                                                 tangents_np, full, shrink, others, tv_np, d_np, turn)
        return frac, piece_tv, cruise, overlaps

    d_sorted = np.sort(d_np)[::-1]
    h_full = float(_fir_profile._h_full(tuple(d_sorted.tolist()))) if d_np.size <= 2 else 0.0
    no_arc = np.full(table.block.size, -1, dtype=np.int64)  # sub-arc index of every piece (-1: none)
    arc_of = no_arc.copy()
    arc_of[table.arc_pieces] = np.arange(table.arc_pieces.size)
    no_rel = np.zeros(0)

    def predicted_time(candidate, shrink=None) -> float:
        """Cycle time of a candidate (or of a repaired one, with its overlap ``shrink``) before
        verification: a lower bound on its verified time, because repairs only shrink overlaps and
        lower feeds (one compiled pass for one or two filters, ``_fir_candidate_kernels.predicted_cycle``)."""
        shrink = np.ones(M - 1) if shrink is None else shrink
        if d_np.size > 2:
            frac, piece_tv, _, overlaps = timing(*candidate[:4], shrink, *candidate[4:], top=False)
            return float(np.sum(frac * piece_tv) + np.sum(Td_np - overlaps) + Td_np)
        factor, head, tail, full, others, arc_rel = candidate
        arcs, rel = (no_arc, no_rel) if arc_rel is None else (arc_of, arc_rel)
        return float(predicted_cycle(tp.lengths, F_np, table.block, table.role, table.fraction, arcs, rel, factor,
                                     head, tail, table.first_motion,
                                     table.last_motion, t_in, t_out, full, shrink, others, tv_np, d_sorted, h_full, turn))

    def timing_gaps(*candidate, top=True):
        """:func:`timing` and the dwell after each block (0 after the last and on padding)."""
        frac, piece_tv, cruise, overlaps = timing(*candidate, top=top)
        return frac, piece_tv, cruise, overlaps, np.concatenate([Td_np - overlaps, np.zeros(Mp - M + 1)])

    def schedule(factor, head, tail, full, shrink, others, arc_rel, build=True):
        """``(feeds, overlaps, pulse lengths, pulse starts, position, corner instants, inputs, input
        durations, timing)`` on concrete arrays (the position a :class:`NumpyPiecewise`). Without
        ``build``, for a plan that checks nothing: the position only its first and last break
        ``(2,)`` (``_fir_profile.schedule_span``), no durations, and the timing ``(fraction,
        pulse lengths, gaps)`` that the plan returned keeps (:func:`timing_gaps`'s; None when built:
        a round's state does not hold it)."""
        frac, piece_tv, cruise, overlaps, gaps = timing_gaps(factor, head, tail, full, shrink, others, arc_rel)
        if not build:
            starts, ends, span, centre = _fir_profile.schedule_span(table.geo, table.block, table.gap, frac, piece_tv,
                                                                    gaps, d_np, table.joins)
            return (F_np * cruise, overlaps, ends[:M] - starts[:M], starts[:M], span, centre[: M - 1],
                    (factor, head, tail, full, shrink, others, arc_rel), None, (frac, piece_tv, gaps))
        starts, ends, breaks, coeffs, centre = _fir_profile.profile(tp.start, table.geo, table.block, table.gap, frac,
                                                                    piece_tv, gaps, d_np, table.joins)
        durations = _fir_profile.input_durations(table, frac, piece_tv, gaps)
        return (F_np * cruise, overlaps, ends[:M] - starts[:M], starts[:M], NumpyPiecewise(breaks, coeffs),
                centre[: M - 1], (factor, head, tail, full, shrink, others, arc_rel), durations, None)

    def traced_plan(factor, head, tail, full, shrink, others, arc_rel):
        """The JAX form of :func:`schedule` (differentiable through ``feed``, ``delays``, ``tolerance``)."""
        frac, piece_factor = table.pieces(head, tail, factor, arc_rel)
        cruise = np.maximum.reduceat(piece_factor[: table.last_motion[-1] + 1], table.first_motion)
        corner = np.stack([np.pad(np.asarray(full, dtype=np.float64), (0, pad_b), constant_values=1.0),
                           np.pad(shrink, (0, pad_b), constant_values=1.0), np.pad(others, (0, pad_b))])
        tol_vertex_p = jnp.concatenate([tol_vertex, jnp.ones(pad_b)])  # padding: any tolerance > 0 (finite gradients)
        lengths_p = jnp.asarray(lengths_np)
        feeds_p = jnp.concatenate([feeds_cmd, jnp.ones(Mp - M + 1)])
        blk = jnp.asarray(table.block)
        overlaps, starts, ends, position, centre, piece_tv = _traced_build(
            lengths_p, feeds_p, blk, jnp.asarray(piece_factor), jnp.asarray(motion_ends_np), jnp.asarray(tangents_np),
            jnp.asarray(corner), tol_vertex_p, delays, jnp.asarray(tp.start), jnp.asarray(table.geo),
            jnp.asarray(table.gap), jnp.asarray(frac), jnp.arange(Mp - 1) < M - 1, turn)
        return (feeds_cmd * jnp.asarray(cruise), overlaps[: M - 1], ends[:M] - starts[:M], starts[:M], position,
                centre[: M - 1]), (frac, piece_tv)

    def prefix_bound(factor, head, tail, full, shrink, others, arc_rel, K, limit_v, repairs):
        """Lower bound on a candidate's first repaired prediction from the vertex errors of its
        first ``K`` blocks (None if none violates): the profile of the input up to block ``K``'s
        start is the plan's own until that instant (the output at ``t`` averages the input over
        ``[t - T_d, t]``), so the corners whose search window ``centre +- T_d / 2`` ends by then
        have their errors of the full check; their repairs bound the first round's
        (``_fir_repair``: a subset of the violators at the same errors). With ``limits`` as well:
        the first round's limit repairs only lower feed factors (every factor ``<= 1``, so a piece
        the bound slows ends no faster) and its corner bisections enter the prediction at their
        brackets' upper ends, at most the overlap the bound keeps. (The candidates this drops
        before their first limit check no longer bring in the limit-capped candidates of
        ``verify``; on 125 limit-holding plans, 625 timing arrays, no plan changed.)"""
        c = int(table.first_motion[K])  # the pieces of blocks 0 .. K - 1 and their gaps
        if d_np.size > 2:  # the JAX inversion of eq 13/14 on the padded shapes of every corner
            frac, piece_tv, _, _, gaps = timing_gaps(factor, head, tail, full, shrink, others, arc_rel, top=False)
        else:  # elementwise: the timing of those pieces and of corners 0 .. K - 1 alone (the same values)
            frac, piece_factor = table.pieces(head, tail, factor, arc_rel)
            piece_tv, overlaps = _fir_profile.timing(lengths_np, feeds_np, table.block[: c + 1], piece_factor[: c + 1],
                                                     motion_ends_np[:, : K + 1], tangents_np[:, : K + 1], full[:K],
                                                     shrink[:K], others[:K], tv_np[:K], d_np, turn)
            gaps = np.concatenate([Td_np - overlaps, np.zeros(Mp - K)])
        starts, _, breaks, coeffs, centre = _fir_profile.profile(tp.start, table.geo[:c], table.block[:c],
                                                                 table.gap[:c], frac[:c], piece_tv[:c], gaps, d_np,
                                                                 None if table.joins is None else table.joins[:c])
        j = np.flatnonzero(centre[: K - 1] + 0.5 * Td_np <= starts[K])
        errors = np.zeros(M - 1)
        prefix = NumpyPiecewise(breaks, coeffs)
        rounding = profile_rounding(prefix, tp.ends[K - 1])  # it ends at rest there
        errors[j] = vertex_distances(prefix, tp.vertices[j], centre[j], 0.5 * Td_np, limit_v[j] + rounding)
        viol = errors > limit_v + rounding
        if not viol.any():
            return None
        f, sh = repairs.bound(viol, errors, False, factor, shrink)
        return predicted_time((f, head, tail, full, others, arc_rel), sh)

    last_check = None  # the last complete check of any candidate (RoundChecks.snapshot)
    rival = np.inf  # the least bound of the other candidates (and the best verified time), set by verify
    alone_memo = {}  # a block's phase 1 multiplier by its pieces and safe multiplier (settle's hold)
    key_width = int(np.max(table.last_motion - table.first_motion, initial=0)) + 2  # its motion pieces and gap

    def settle(candidate, several=False, slow_futile=False, on_futile=None):
        """Verify and repair one candidate plan (``candidate()`` builds its new arrays ``(factor,
        head, tail, full, others, arc_rel)`` when it starts), one round per step: a generator that yields the
        ``(predicted time, limit repaired so far, holds its profile)`` after each failed round and
        returns ``(state, rounds, deviation, limit_repaired)``. Suspended after the vertex errors
        (its profile kept for the path samples), it releases the profile when sent
        :data:`_RELEASE` and rebuilds it on resuming. It also yields inside a round's chain walk
        (``_fir_limit_spread.spread_slow_down``) once the walk's prediction passes the least bound
        of the other candidates (``rival``, weighed after 1, 2, 4, ... of its walk steps), and
        resumes the same walk there. The prediction is a lower bound on the final time:
        repairs only shrink overlaps and lower feeds, and a bisecting corner is predicted at its
        bracket's upper end (:attr:`CornerBisection.bound_scale`), above which it never ends.
        ``several``: other candidates compete (worth a first bound from the first blocks,
        :func:`prefix_bound`, before the whole profile). ``slow_futile``: a corner above a limit
        whose exact stop is predicted to lower nothing (``_fir_limits.futile_stops``) has its
        window's blocks slowed instead of its overlap bisected; without it, ``on_futile(bound)`` is
        called once, in the first round in which such corners would have their windows slowed
        (no block slowed alone that round), with that settle's prediction after the repair (the
        planner then settles the same candidate that way as well and keeps the faster plan: the
        prediction rests on isolated steps, and on random programs the bisection was faster about
        as often)."""
        nonlocal last_check
        factor, head, tail, full, others, arc_rel = candidate()  # ``factor``: its own, repaired in place
        candidate, shrink = None, np.ones(M - 1)
        # without limits no corner bisects: its multipliers stay 1 (no (M - 1,) arrays per candidate)
        bisection = CornerBisection(M - 1) if limits is not None else _NO_BISECTION
        round_peaks = RoundPeaks(table, limits, Td_np) if limits is not None else None
        checked, repaired = np.zeros(M, dtype=bool), False
        checks = RoundChecks(tp, tb_np, table.block, Td_np, check_period, table.fraction, table.joins)  # redone only where the profile changed
        checks.adopt(last_check)  # from another candidate's last complete check: redone where they differ
        walked, next_look = 0, 1  # steps of this candidate's chain walks, and the next one weighed
        repairs = Repairs(full, head, tail, tv_np, tb_np, F_np, tp.lengths, Td_np, d_np.size, cum_np)

        def hold(fac, which):
            """``_fir_limits`` phase 1 at feed factors ``fac``: multipliers under which the blocks
            ``which`` alone (every corner an exact stop) keep the limits. A block is checked alone
            once per plan for the same pieces (shares and feed factors) and safe multiplier
            (``alone_memo``): the candidates share most blocks, and a block's result depends on
            its own pieces only (up to the rounding of its time offset in the build)."""
            def alone(g, blocks, decisions):  # their pieces only (the others are not read)
                idx, _ = table.block_pieces(np.flatnonzero(blocks))
                frac, piece_factor = np.zeros(table.block.size), np.ones(table.block.size)
                frac[idx], piece_factor[idx] = table.pieces_at(idx, head, tail, fac, arc_rel, g)
                return alone_block_ratios(table, blocks, frac, piece_factor, lengths_np, feeds_np, tp.start, d_np, limits,
                                          decisions=decisions)
            safe = safe_feed / (F_np * fac.max(axis=1))
            ks = np.flatnonzero(which)
            idx, owner = table.block_pieces(ks)
            frac, piece_factor = table.pieces_at(idx, head, tail, fac, arc_rel)
            keys = _block_keys(ks, safe[ks], owner, frac, piece_factor, key_width)
            g = np.ones(M)
            todo = np.zeros(M, dtype=bool)
            for k, key in zip(ks.tolist(), keys):
                known = alone_memo.get(key)
                if known is None:
                    todo[k] = True
                else:
                    g[k] = known
            if todo.any():
                found = hold_block_limits(alone, safe, todo)
                g[todo] = found[todo]
                for k, key in zip(ks.tolist(), keys):
                    if todo[k]:
                        alone_memo[key] = float(found[k])
            return g

        def futile(fac, corners):
            """``_fir_limits.futile_stops`` of ``corners`` at feed factors ``fac`` (each block's piece
            facing the corner, ``FeedSteps.facing_feeds``)."""
            facing = steps.of(head, tail)
            a, b = corners, corners + 1
            return futile_stops(facing.facing_feeds(fac, a, 1)[:, None] * t_out[a],
                                facing.facing_feeds(fac, b, -1)[:, None] * t_in[b], steps.step)

        def breaking(fac, corners):  # the blocks in the corners' windows above a limit at ``fac`` (_fir_limit_spread)
            return windows.breaking(corners, head, tail, fac, arc_rel, full, shrink * bisection.scale, others)

        def corner_ratios(fac, corners):  # the corners' window ratios at ``fac`` (_fir_limit_spread)
            return windows.ratios(corners, head, tail, fac, arc_rel, full, shrink * bisection.scale, others)

        if limits is not None and M == 1:
            g = hold(factor, np.ones(1, dtype=bool))
            factor, repaired = factor * g[:, None], bool(g[0] < 1.0)
        K = M // _PREFIX_SHARE
        if refine and several and K >= _PREFIX_MIN_BLOCKS:
            # the vertex errors of the first blocks alone, on the profile of their input: a loser
            # (errors everywhere) falls behind the others for a share of a profile and its check
            bound = prefix_bound(factor, head, tail, full, shrink, others, arc_rel, K, limit_v, repairs)
            if bound is not None:
                yield bound, repaired, False
        state = schedule(factor, head, tail, full, shrink, others, arc_rel, build=refine or limits is not None)
        rounds, deviation = 0, float("nan")
        if refine or limits is not None:
            max_rounds = MAX_ROUNDS + (2 * M if limits is not None else 0)
            tol_due = True  # the tolerance state changed since the last tolerance check
            for rounds in range(1, max_rounds + 1):
                (pulse_np, starts_np, pos_np, centre_np), durations = state[2:6], state[7]
                # the tolerance up to the rounding of this profile (_fir_verify.profile_rounding)
                checks.slack = profile_rounding(pos_np, tp.ends[-1])
                bound_v = limit_v + checks.slack
                too_fast, slowed = False, False
                if limits is not None and M > 1:
                    # recomputed where the input changed since the last round (_fir_round_peaks)
                    ratios, own = round_peaks(pos_np, starts_np, pulse_np, state[1], *state[6][:3], state[6][6])
                    bad, own_bad = ratios > 1.0 + LIMIT_RTOL, own > 1.0 + LIMIT_RTOL
                    # corners above a limit that bisection may still repair and whose exact stop is
                    # predicted to lower nothing (futile_stops): the slow_futile settle slows their
                    # windows' blocks instead, and checks no block alone for them (phase 1)
                    c = np.flatnonzero(bad & (bisection.scale > 0.0))
                    c = c[futile(factor, c)] if c.size and (slow_futile or on_futile is not None) else c[:0]
                    windows_of = bad
                    if slow_futile and c.size:
                        windows_of = bad.copy()
                        windows_of[c] = False
                    near = (blocks_in_windows(windows_of, starts_np, pulse_np, Td_np) | own_bad) & ~checked
                    g = hold(factor, near) if near.any() else 1.0
                    checked |= near
                    # the slow_futile settle's window slow-down this round (where no block alone is slowed)
                    g_fork = None if not c.size or np.any(g < 1.0) else \
                        window_slow_down(c, 0.98 / ratios[c], starts_np, pulse_np, Td_np)
                    if slow_futile and g_fork is not None:
                        # slow every block those corners' windows cover (peaks scale with feed),
                        # each by its corner's ratio; until the first such corner the rounds are
                        # those of the plain settle
                        g = g_fork
                    elif bad.any() and not near.any() and np.all(bisection.scale[bad] == 0.0):
                        # exact stops still above a limit (blocks checked alone before, in other
                        # windows): slow every block those windows cover, as peaks scale with feed
                        g = np.where(blocks_in_windows(bad, starts_np, pulse_np, Td_np), 0.98 / np.max(ratios[bad]), 1.0)
                    if g_fork is not None and on_futile is not None:
                        # the first round in which the slow_futile settle would slow windows (not
                        # blocks alone: that settle checks alone a subset of the blocks checked here,
                        # so none is slowed alone there either). Its prediction after that repair
                        # bounds it where its rounds so far are these (repairs only lower feeds and
                        # shrink overlaps; a block above a limit of its own takes 0.98 / ratio at
                        # most); where futile corners came up in earlier rounds, which phase 1 took,
                        # the two settles parted there and the bound is an estimate that only orders
                        # the queue. A candidate whose futile corners only ever meet phase 1 is not
                        # settled twice (measured: a 1,000-chord circle under limits far below the
                        # envelope, four such second settles, 0.31 -> 1.78 s, the same plan).
                        g_low = np.where(own_bad, np.maximum(g_fork, 0.98 / np.maximum(own, 1.0)), g_fork)
                        on_futile(predicted_time((factor * g_low[:, None], head, tail, full, others, arc_rel),
                                                 shrink * bisection.bound_scale))
                        on_futile = None
                    if own_bad.any() and not near.any():  # checked alone before, above a limit again
                        g = np.where(own_bad, 0.98 / np.maximum(own, 1.0), g)
                    if np.any(g < 1.0):  # slowed blocks: check the corners again before bisecting
                        factor = factor * np.reshape(g, (-1, 1))  # new array: the state's inputs are the old
                        # their feed steps' corners at once, along the chain (not one block a round)
                        walk = spread_slow_down(np.reshape(g, -1) < 1.0, checked, factor, breaking, hold,
                                                steps.of(head, tail), corner_ratios)
                        while True:
                            try:
                                factor = next(walk)
                            except StopIteration as done:
                                factor, walk, done = done.value, None, None
                                break
                            walked += 1
                            if walked < next_look:
                                continue
                            # a long walk (a chain slowed block by block) is weighed against the
                            # other candidates after 1, 2, 4, ... of this candidate's steps: once
                            # its prediction passes the least bound among them (rival), it is
                            # suspended between two steps and resumed there, the same walk
                            next_look = 2 * walked
                            low = predicted_time((factor, head, tail, full, others, arc_rel),
                                                 shrink * bisection.bound_scale)
                            if not low > rival:
                                continue
                            if not tol_due:  # this round reads no profile after its walk
                                state = pos_np = pulse_np = starts_np = centre_np = durations = None
                                yield low, True, False
                            elif (yield low, True, True) is _RELEASE:  # rebuilt for the round's check
                                inputs, state = state[6], None
                                pos_np = pulse_np = starts_np = centre_np = durations = None
                                yield low, True, False
                                state = schedule(*inputs)
                                (pulse_np, starts_np, pos_np, centre_np), durations = state[2:6], state[7]
                        too_fast = slowed = True
                    else:
                        too_fast = bisection.update(ratios)
                    repaired |= too_fast
                viol, arc_slow, errors = np.zeros(M - 1, dtype=bool), np.zeros(M), np.zeros(M - 1)
                # The tolerance is checked in every round that may return the plan (its limits hold)
                # and in every round after a change other than a corner bisection; a round after a
                # bisection step alone, whose limits still break, is rebuilt without it. So the
                # returned plan is always fully checked. Skipping is expected to miss nothing: a
                # bisection only sets overlaps in [0, planned], and the corner error grows with the
                # overlap (eq 13/14); so does the sampled path deviation on a two-block corner
                # (position = v - u_k A(t) + u_k+1 B(t) with A, B >= 0 the filtered remainders,
                # B shrinking pointwise as the gap grows, and the distance to the two rays
                # nondecreasing in A and B), while windows of three or more blocks and arcs have no
                # such proof -- hence the final check rather than trusting it.
                if tol_due or not too_fast:
                    if refine:
                        errors = checks.vertices(pos_np, starts_np, centre_np, durations, M > 1)
                        stops = state[1] == 0.0  # exact stops: the exact profile passes through their vertices
                        checks.slack = max(checks.slack, stop_rounding(errors, stops))
                        checks.stops = stops  # no blend there: samples by them are their blocks' own
                        bound_v = limit_v + checks.slack
                        if M > 1 and np.any(errors > bound_v):
                            # the vertex errors first: a bound from their repairs alone (a lower bound
                            # on the whole round's) can rule the candidate out before its path samples
                            # (suspended here, it keeps its profile for the samples unless released)
                            low_f, low_s = repairs.bound(errors > bound_v, errors, rounds > _SCALING_ROUNDS, factor, shrink)
                            low = predicted_time((low_f, head, tail, full, others, arc_rel), low_s * bisection.bound_scale)
                            low_f = low_s = None  # not held while suspended
                            if (yield low, repaired, True) is _RELEASE:
                                # released while others go on: drop the profile, rebuild it from
                                # the same inputs (identical arrays) when this one resumes
                                inputs, state = state[6], None
                                pos_np = pulse_np = starts_np = centre_np = durations = None
                                checks.swap_profile(None)
                                yield low, repaired, False
                                state = schedule(*inputs)
                                pos_np, starts_np, centre_np = state[4], state[3], state[5]
                                checks.swap_profile(pos_np, starts_np, centre_np)
                        # bounded between the samples only where the round may return the plan
                        # (RoundChecks.samples_check): no vertex error or limit broken already
                        deviation, at_vertex, at_block = checks.samples_check(
                            certify=not (too_fast or np.any(errors > bound_v)))
                        last_check = checks.snapshot()
                    viol = errors > bound_v
                    if refine:
                        for k, e in at_block.items():
                            arc_slow[k] = e
                        for j, e in at_vertex.items():
                            corners, arcs = charged_repairs(j, e, stops, centre_np, tv_np, tb_np, tp.is_arc, Td_np)
                            for i, e_i in corners:
                                viol[i], errors[i] = True, max(errors[i], e_i)
                            for k, e_k in arcs:
                                arc_slow[k] = max(arc_slow[k], e_k)
                tol_due = bool(viol.any() or arc_slow.any() or slowed)
                if not (viol.any() or too_fast or arc_slow.any()):
                    break
                if rounds == max_rounds:
                    raise ConvergenceError(
                        f"plan_fir: {int(viol.sum())} vertices and {int((arc_slow > 0).sum())} arcs still violate the "
                        f"tolerance{' (or corners a limit)' if too_fast else ''} after {max_rounds} rounds",
                        residual=float(np.max(errors - bound_v, initial=0.0)), steps=rounds)
                late = rounds > _SCALING_ROUNDS
                # suspended in the branch and bound, a candidate keeps no profile and no round's
                # arrays; dropped before the repairs, which change ``factor`` and ``shrink`` in place
                # (the state's inputs are those arrays, not copies)
                state = inputs = pos_np = pulse_np = starts_np = centre_np = durations = at_vertex = at_block = None
                repairs.apply(viol, errors, arc_slow, late, factor, shrink)
                viol = errors = arc_slow = None
                yield predicted_time((factor, head, tail, full, others, arc_rel), shrink * bisection.bound_scale), repaired, False
                state = schedule(factor, head, tail, full, shrink * bisection.scale, others, arc_rel)
        return state, rounds, deviation, repaired

    def plans(factors):
        """The candidates at feed factors ``factors``, each ``(build, bound)``: ``build()`` makes its
        arrays (new ones on every call), ``bound`` its :func:`predicted_time` (None: not computed)."""
        nonlocal ahead
        if refine and M > 1:
            if ahead is not None and factors is base:  # made before the table was cut
                out, ahead = with_table(ahead, table, measure=predicted_time), None
                return out
            return look_ahead(tp, table, F_np, factors, d_np, tv_np, t_in, t_out, turn, measure=predicted_time)
        return [(lambda: (np.repeat(factors[:, None], 3, axis=1), head, tail, full, others, None), None)]

    def verify(candidates, capped):
        """Branch and bound, one verification round at a time: the candidate (or repaired candidate)
        of least bound goes next, until none could still beat the best verified plan; a candidate
        whose repairs push its bound past the best verified plan is dropped without rebuilding its
        profile. Once a candidate needs a limit repair, the candidates ``capped()`` (every block at
        its closed-form safe feed up front: slower blocks whose corners keep their overlap can beat
        exact stops; and one at the feeds the path's end ramps allow) join the same queue. Returns
        the best settled ``(state, rounds, deviation)``, the state without its profile (its first
        and last break in its place) and without its input durations (in their place the timing its
        schedule kept: ``(fraction, pulse lengths, gaps)`` for a plan that checked nothing, else
        None)."""
        nonlocal rival
        best, best_time = None, np.inf
        several = len(candidates) > 1
        # candidates to settle with slow_futile as well (settle's on_futile), each from its start,
        # queued at the larger of its plain settle's bound and the one on_futile gives
        forks = []
        fork_index = itertools.count(1 << 40)

        def settled(c, several):  # a candidate's settle generator (limits: forked on futile stops)
            if limits is None:
                return settle(c, several=several)
            return settle(c, several=several, on_futile=lambda low: forks.append((c, low)))

        queue = [(bound if several else 0.0, i, settled(c, several)) for i, (c, bound) in enumerate(candidates)]
        heapq.heapify(queue)
        extra, index = capped is not None, itertools.count(len(candidates))
        candidates = None  # the generators hold the candidates (their arrays are built when started)

        def add_capped():
            for c, bound, ways in capped():
                bound = predicted_time(c()) if bound is None else bound
                if "plain" in ways:
                    heapq.heappush(queue, (bound, next(index), settled(c, False)))
                if "futile" in ways:  # settled with slow_futile from its start (see capped)
                    heapq.heappush(queue, (bound, next(index), settle(c, slow_futile=True)))
                if "last" in ways:  # the same, once every other candidate is settled or ruled out
                    last.append((bound, next(index), settle(c, slow_futile=True)))

        held = {}  # index -> (bound, steps) of the candidates suspended with their profiles
        # candidates settled after all the others (capped's "last"): never the best verified plan
        # while those go on, so they rule none of them out (a candidate whose own rounds would fork
        # a better settle is not dropped before it forks); they only add plans
        last = []
        while (queue and queue[0][0] < best_time) or last:
            if not (queue and queue[0][0] < best_time):
                for item in last:
                    heapq.heappush(queue, item)
                last.clear()
                continue
            bound, i, steps = heapq.heappop(queue)
            rival = min(queue[0][0], best_time) if queue else best_time
            held.pop(i, None)
            holds = False
            try:
                step, repaired, holds = next(steps)
                heapq.heappush(queue, (max(bound, step), i, steps))
            except StopIteration as done:
                state, rounds, deviation, repaired = done.value
                breaks = state[4] if isinstance(state[4], np.ndarray) else state[4].breaks  # the span alone: unchecked
                t = float(breaks[-1] - breaks[0])
                if t < best_time:  # kept without its profile (rebuilt from the inputs when used)
                    best, best_time = (state[:4] + ((breaks[0], breaks[-1]), state[5], state[6], state[8]), rounds,
                                       deviation), t
                state = breaks = done = None
            while forks:  # the same candidate settled with slow_futile, from its start
                c, low = forks.pop()
                heapq.heappush(queue, (max(bound, low), next(fork_index), settle(c, several=several, slow_futile=True)))
            if extra and repaired:
                extra = False
                add_capped()
            if holds and queue[0][1] != i:  # suspended with its profile while another goes next:
                # the _HELD_PROFILES of least bound among such keep theirs (the likeliest to resume)
                held[i] = (max(bound, step), steps)
                if len(held) > _HELD_PROFILES:
                    j = max(held, key=lambda k: (held[k][0], k))
                    held.pop(j)[1].send(_RELEASE)
        return best

    capped = None
    if limits is not None and np.any(safe_feed < F_np * base):
        scale = end_ramp_scale(tp, F_np * base, t_in, t_out, d_np, limits)

        def capped():
            """``[(candidate, bound, ways)]``: the candidates with every block at its safe feed
            alone (``ways`` ``("plain",)``: settled as the others), and where the path's start and
            end ramps break a limit, the one of least bound among those of the whole path at its
            feeds scaled by ``end_ramp_scale`` (``("plain", "futile")``) and the blocks at feeds
            capped window by window and joined by staircases of isolated steps
            (``_fir_staircase``, ``("futile",)``). A chain of short blocks runs inside one motion,
            where a block peaks far below its own start and stop (its safe feed alone), and the
            ramps at the path's ends are what a uniform feed must keep. These two are settled with
            ``slow_futile`` from their start: their corners sit just above a limit, where a window
            slow-down of ``0.98 / ratio`` costs ~2 % and phase 1 would take the blocks down to
            their safe feeds alone (the staircase settled plainly fell back to them: 0.05x the
            envelope, 142 s against 66 s, benchmarks/README.md). One uniform candidate, not all: on
            the quick CAM file at 0.5x the envelope all of them cost 3.6x the planning time for the
            same plan (benchmarks/README.md).

            And a second staircase (``("last",)``: settled with ``slow_futile`` once every other
            candidate is settled or ruled out) under the feeds of the look-ahead candidate without
            dwells (``_fir_lookahead.without_dwells``: every window within the tolerance at full
            overlap): the first staircase's ceiling is the commanded feed, so where the tolerance
            binds below the limits its windows break the tolerance and the repairs (windows scaled
            by ``sqrt(eps / error)``, then the feed steps they make) cost it a third and more
            (quick CAM file at 0.1x the envelope: 32.3 -> 53.3 s). Settled last, it never rules a
            candidate out before that one forks a better settle (at 0.2x, settled with the others,
            it verified first at 30.30 s and dropped the candidate whose fork verifies at 26.94 s):
            it only adds a plan (benchmarks/README.md)."""
            out = [(c, b, ("plain",)) for c, b in plans(np.minimum(base, safe_feed / F_np))]
            if scale < 1.0 - LIMIT_RTOL:
                uniform = [(c, predicted_time(c()) if b is None else b) for c, b in plans(base * scale)]
                out.append(min(uniform, key=lambda cb: cb[1]) + (("plain", "futile"),))
                if M > 1:
                    out.append((staircase_candidate(F_np * base), None, ("futile",)))
                    if no_dwell is not None:
                        ceiling = F_np * np.minimum(base, no_dwell()[0].min(axis=1))
                        out.append((staircase_candidate(ceiling), None, ("last",)))
            return out

        def staircase_candidate(ceiling):
            """The blocks at their feeds ``ceiling`` ``(M,)`` [mm/s] capped window by window and
            joined by staircases of isolated steps (``_fir_staircase``), every corner at full overlap."""
            zeros, full1, ones1, zeros1 = np.zeros(M), np.ones(M - 1, dtype=bool), np.ones(M - 1), np.zeros(M - 1)
            corners = np.arange(M - 1)

            def factors(feeds):
                return np.repeat((feeds / F_np)[:, None], 3, axis=1)

            def read(feeds):
                return windows.with_blocks(corners, zeros, zeros, factors(feeds), None, full1, ones1, zeros1)

            step = float(np.min(isolated_step(d_np, limits)))
            factor = factors(capped_staircase(tp.lengths, ceiling, step, Td_np, read))
            return lambda: (factor.copy(), np.zeros(M), np.zeros(M), np.ones(M - 1, dtype=bool), np.zeros(M - 1), None)
    first = plans(base)
    # the look-ahead candidate without dwells, whose feeds cap the tolerance-aware staircase (capped)
    no_dwell = without_dwells(first) if capped is not None else None
    state, rounds, deviation = verify(first, capped)
    if traced:
        (feeds, overlaps, pulse, starts, profile, centre), pieces = traced_plan(*state[6])
        delays, vertices = device_array(delays), _device_vertices(tp)
    else:  # the concrete arrays in one transfer (research._device.device_arrays)
        feeds, overlaps, pulse, starts, centre, delays, vertices, span = device_arrays(
            *(state[i] for i in (0, 1, 2, 3, 5)), delays, _device_vertices(tp), np.array(state[4]))
        # the profile's inputs, not its coefficients (the same arrays when rebuilt: ``settle``'s release)
        if state[7] is not None:  # the timing its schedule kept (a plan that checked nothing)
            frac, piece_tv, gaps = state[7]
        else:
            frac, piece_tv, _, _, gaps = timing_gaps(*state[6])
        profile = _fir_profile.ProfileInputs(table, frac, piece_tv, gaps, d_np, tp.start, span)
        pieces = (frac, piece_tv)
    return (starts, pulse, overlaps, feeds, delays, profile, centre, vertices, float(deviation), int(rounds),
            tp.axes), pieces + (table.first_motion,)


@functools.partial(jax.jit, static_argnames="turn")
def _traced_build(lengths_p, feeds_p, blk, piece_factor, motion_ends, tangents, corner, tol_vertex, delays, start, geo,
                  gap, frac, real_corner, turn):
    """:func:`_timing_kernel` and ``build_profile`` in one compiled dispatch (the plan returned when
    an input is a tracer). ``real_corner``: ``(M_pad - 1,)`` True on the path's corners (the others
    are padding and get no gap); ``turn``: as :func:`_timing_kernel`. Returns ``(overlaps, block starts, block ends, position, centre)``
    on the padded shapes, and the pulse length [s] of every piece ``(P,)``."""
    piece_tv, overlaps = _timing_kernel(lengths_p, feeds_p, blk, piece_factor, motion_ends, tangents, corner, tol_vertex,
                                        delays, turn)
    gaps = jnp.concatenate([jnp.where(real_corner, jnp.sum(delays) - overlaps, 0.0), jnp.zeros(1)])
    starts, ends, position, centre = build_profile(start, geo, blk, gap, frac, piece_tv, gaps, delays)
    return overlaps, starts, ends, position, centre, piece_tv


@functools.partial(jax.jit, static_argnames="turn")
def _timing_kernel(lengths_p, feeds_p, blk, piece_factor, motion_ends, tangents, corner, tol_vertex, delays, turn):
    """Pulse length of every piece and overlap of every corner (padded shapes, one dispatch).

    Args:
        lengths_p, feeds_p: ``(M_pad + 1,)`` block lengths [mm] and commanded feeds [mm/s].
        blk, piece_factor: ``(P,)`` block and feed factor of every piece.
        motion_ends: ``(2, M_pad)`` first and last motion piece of each block.
        tangents: ``(2, M_pad, d)`` entry and exit tangents of each block.
        corner: ``(3, M_pad - 1)`` full-overlap flag, overlap shrink factor, tolerance other turns take.
        tol_vertex: ``(M_pad - 1,)`` tolerance at each vertex [mm]; ``delays``: ``(n,)`` [s].
        turn: the corners' speed change (``_fir_overlap.corner_speed_change``).

    Returns:
        ``(piece_tv (P,), overlaps (M_pad - 1,))`` [s]: ``L / F`` of each piece's block at the
        piece's feed, and ``T_k`` from eq 13/14 at the feeds either side of each corner.
    """
    piece_tv = lengths_p[blk] / (feeds_p[blk] * piece_factor)
    nb = motion_ends.shape[1]
    f_in = feeds_p[:nb] * piece_factor[motion_ends[0]]
    f_out = feeds_p[:nb] * piece_factor[motion_ends[1]]
    dF = corner_speed_change(f_out[:-1], f_in[1:], tangents[1, :-1], tangents[0, 1:], turn)
    Td = jnp.sum(delays)
    full, shrink, others = corner
    overlaps = jnp.where(full > 0, Td, overlap_time(jnp.maximum(tol_vertex - others, 0.0), dF, delays)) * shrink
    return piece_tv, overlaps


def _block_keys(ks: np.ndarray, safe: np.ndarray, owner: np.ndarray, frac: np.ndarray, piece_factor: np.ndarray,
                width: int):
    """One hashable key per block ``ks`` ``(K,)``: its index, its safe multiplier and the shares and
    feed factors of its pieces (``owner``: the position in ``ks`` of each piece's block), bit for
    bit (rows of floats read as bytes; NaN pads blocks of fewer pieces to ``width`` pieces, the
    most a block of the path has, so that the keys of every call can meet)."""
    counts = np.bincount(owner, minlength=ks.size)
    rows = np.full((ks.size, 2 + 2 * width), np.nan)
    rows[:, 0], rows[:, 1] = ks, safe
    col = np.arange(owner.size) - np.repeat(np.cumsum(counts) - counts, counts)
    rows[owner, 2 + col] = frac
    rows[owner, 2 + width + col] = piece_factor
    return np.ascontiguousarray(rows).view(np.dtype((np.void, rows.shape[1] * 8))).ravel().tolist()


def _padded(tp: ToolPath, table: PulseTable):
    """The path's per-block arrays on ``table``'s padded block count ``M_pad`` (the planner's
    timing takes them so): block lengths [mm] ``(M_pad + 1,)`` (1 on padding), arc length at each
    block start [mm] ``(M + 1,)``, first and last motion piece ``(2, M_pad)`` and entry and exit
    tangents ``(2, M_pad, d)`` (0 on padding). Made once per table (kept with the path's own
    table: every plan of the path reads them; not to be written)."""
    kept = tp._cache.get("padded")
    if kept is not None and kept[0] is table:
        return kept[1]
    M, Mp = tp.n_blocks, table.m_pad
    lengths, cum = np.ones(Mp + 1), np.zeros(M + 1)
    lengths[:M] = tp.lengths
    np.cumsum(tp.lengths, out=cum[1:])
    motion_ends = np.zeros((2, Mp), dtype=table.first_motion.dtype)
    motion_ends[0, :M], motion_ends[1, :M] = table.first_motion, table.last_motion
    tangents = np.zeros((2, Mp, tp.dim))
    tangents[0, :M], tangents[1, :M] = tp.tangents()
    arrays = (lengths, cum, motion_ends, tangents)
    if table is tp._cache.get("pulse_table"):
        tp._cache["padded"] = (table, arrays)
    return arrays


def _device_vertices(tp: ToolPath) -> jax.Array:
    """The path's corner vertices ``(M - 1, d)`` [mm] as a JAX array (a plan's ``vertices``), made
    once per path: a JAX array is immutable, so every plan of the path can hold the same one."""
    if "device_vertices" not in tp._cache:
        tp._cache["device_vertices"] = device_array(tp.vertices)
    return tp._cache["device_vertices"]


def _pulse_table(tp: ToolPath) -> PulseTable:
    cache = tp._cache
    if "pulse_table" not in cache:
        cache["pulse_table"] = PulseTable.from_path(tp)
    return cache["pulse_table"]


def _arc_factor(tp: ToolPath, delays, tol_block, feeds) -> np.ndarray:
    """Feed factors from the eq 8 radial error of each arc block (1 on lines)."""
    arc = tp.is_arc
    if not arc.any():
        return np.ones(tp.n_blocks)
    zero = arc & (tol_block <= 0)
    if zero.any():
        raise ParameterError(f"block {int(np.argmax(zero))} is an arc with tolerance 0: an FIR chain shrinks every "
                             "arc it averages (eq 8), so an arc needs a tolerance > 0 mm")
    caps = arc_feed_caps(tp.radii, delays, tol_block, feeds)
    return caps / feeds


def _primal(x):
    """The primal value of a JAX AD tracer (decisions are made on it); the value itself otherwise."""
    while isinstance(x, jax.core.Tracer):
        if not hasattr(x, "primal"):
            raise ParameterError("plan_fir with refine or limits decides on concrete values and cannot run under "
                                 "jax.jit; call it outside jit (jax.grad and jax.jacfwd work)")
        x = x.primal
    return x
