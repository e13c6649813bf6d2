"""A slowed block's feed step followed along the chain within one limit-holding round
(``_fir_limit_spread``), against independent computations: the whole path's profile and its
corner windows, the pulse table's own :meth:`PulseTable.pieces`, and closed-form feeds."""

import time

import numpy as np
import pytest

from research.interpolators import _fir_profile, plan_fir
from research.interpolators._fir_limit_spread import CornerWindows
from research.interpolators._fir_limits import LIMIT_RTOL, THRESHOLD_GUARD, blocks_in_windows, corner_limit_ratios
from research.interpolators._fir_piece_peaks import PiecePeaks
from research.limits import AxisLimits
from research.metrics import within_limits
from research.paths import Polyline
from research.paths.library import random_program
from research.paths.toolpath import ToolPath
from research.piecewise import NumpyPiecewise

from ._paths import turning_path


def _plan_inputs(tp, rng):
    """Random plan inputs of ``tp`` as the rounds hold them: feeds, line shares, feed factors (a few
    blocks slowed hard: the feed steps this module follows), sub-arc factors, full-overlap flags,
    overlap multipliers and tolerance shares."""
    from research.interpolators._fir_settle import _pulse_table

    table, M = _pulse_table(tp), tp.n_blocks
    F = rng.uniform(50.0, 300.0, M)
    head, tail = rng.uniform(0.0, 0.4, M), rng.uniform(0.0, 0.4, M)
    factor = rng.uniform(0.5, 1.0, (M, 3)) * np.where(rng.random(M) < 0.2, 0.1, 1.0)[:, None]
    arc_rel = rng.uniform(0.5, 1.0, table.arc_pieces.size) if table.arc_pieces.size else None
    full = rng.random(M - 1) < 0.5
    shrink = np.where(rng.random(M - 1) < 0.2, rng.uniform(0.0, 1.0, M - 1), 1.0)
    others = rng.uniform(0.0, 0.02, M - 1)
    tol = rng.uniform(0.01, 0.1, M - 1)
    return table, F, head, tail, factor, arc_rel, full, shrink, others, tol


def _random_windows_cases(seeds, path_seed, d):
    """``(tp, plan inputs of _plan_inputs, limits)`` of seeded random programs: lines of 0.2-12 mm
    turning up to 40 deg (windows over several blocks; even seeds) and lines with arcs (odd), under
    the FIR envelope of a random feed."""
    for seed in seeds:
        rng = np.random.default_rng(seed)
        if seed % 2:
            tp = random_program(rng, arcs=True)
        else:
            tp = ToolPath.from_polyline(turning_path(path_seed + seed, 60, (0.2, 12.0), 40.0))
        inputs = _plan_inputs(tp, rng)
        yield tp, inputs, AxisLimits.fir_envelope(tp.dim, float(rng.uniform(100.0, 250.0)), d)


def _whole_windows(tp, table, F, head, tail, factor, arc_rel, full, shrink, others, tol, d, limits):
    """``(M - 1,)`` corner-window ratios and the starts and pulse lengths of the whole path's
    profile, built as ``plan_fir``'s ``schedule`` builds it (every piece, every corner)."""
    M, Mp = tp.n_blocks, table.m_pad
    t_in, t_out = tp.tangents()
    pad = Mp - M
    frac, pf = table.pieces(head, tail, factor, arc_rel)
    lengths = np.concatenate([tp.lengths, np.ones(pad + 1)])
    feeds = np.concatenate([F, np.ones(pad + 1)])
    ends = np.stack([np.pad(table.first_motion, (0, pad)), np.pad(table.last_motion, (0, pad))])
    tangents = np.stack([np.pad(t_in, ((0, pad), (0, 0))), np.pad(t_out, ((0, pad), (0, 0)))])
    piece_tv, overlaps = _fir_profile.timing(lengths, feeds, table.block, pf, ends, tangents, full, shrink, others, tol, d,
                                             False)
    Td = float(np.sum(d))
    gaps = np.concatenate([Td - overlaps, np.zeros(pad + 1)])
    s, e, breaks, coeffs, _ = _fir_profile.profile(tp.start, table.geo, table.block, table.gap, frac, piece_tv, gaps, d)
    peaks = PiecePeaks(NumpyPiecewise(breaks, coeffs), limits)
    return corner_limit_ratios(peaks, s[:M], e[:M] - s[:M], Td), s[:M], e[:M] - s[:M]


@pytest.mark.parametrize("delays", [(0.06, 0.03), (0.05, 0.03, 0.01)])
def test_corner_windows_decide_as_the_whole_profile(delays):
    """Seeded random programs (lines of 0.2-12 mm, whose windows reach over several blocks; lines
    and arcs) with random plan inputs: the blocks that :meth:`CornerWindows.breaking` flags for a
    random set of corners are those of ``blocks_in_windows`` over the same corners' windows of the
    whole path's profile whose ratio is above ``1 + LIMIT_RTOL + THRESHOLD_GUARD``. Limits are set
    so that some windows break and some do not."""
    d = np.array(delays)
    Td = float(np.sum(d))
    thr = 1.0 + LIMIT_RTOL + THRESHOLD_GUARD
    broke = kept = 0
    rng = np.random.default_rng(7)
    for tp, inputs, limits in _random_windows_cases(range(700, 710), -620, d):
        M = tp.n_blocks
        table, F, head, tail, factor, arc_rel, full, shrink, others, tol = inputs
        ratios, starts, pulse = _whole_windows(tp, table, F, head, tail, factor, arc_rel, full, shrink, others, tol, d,
                                               limits)
        assert not np.any(np.abs(ratios - thr) < 1e-9)  # no window within rounding of the threshold
        t_in, t_out = tp.tangents()
        windows = CornerWindows(table, tp.lengths, F, t_in, t_out, tol, d, limits, False)
        for _ in range(4):
            corners = np.flatnonzero(rng.random(M - 1) < rng.choice([0.05, 0.3, 1.0]))
            got = windows.breaking(corners, head, tail, factor, arc_rel, full, shrink, others)
            flags = np.zeros(M - 1, dtype=bool)
            flags[corners] = ratios[corners] > thr
            np.testing.assert_array_equal(got, blocks_in_windows(flags, starts, pulse, Td))
            broke += int(flags.sum())
            kept += int(corners.size - flags.sum())
    assert broke > 20 and kept > 20


@pytest.mark.parametrize("delays", [(0.06, 0.03), (0.02, 0.01)])
def test_first_window_ranges_hold_each_windows_input(delays):
    """Seeded random programs (lines of 0.2-12 mm: windows over several blocks; lines and arcs)
    and random plan inputs (feed factors down to 0.05, dwells): the block ranges
    :meth:`CornerWindows._reach` starts from (the blocks within ``T_d`` of the corner at their
    commanded feeds, pulses end to end) hold each window's input as the profile built of them
    shows (``_read``'s before / after flags), so each window is read in one build. The four
    blocks around a corner it started from before did not, on these paths."""
    d = np.array(delays)
    short = 0
    for tp, inputs, limits in _random_windows_cases(range(750, 758), -660, d):
        M = tp.n_blocks
        table, F, head, tail, factor, arc_rel, full, shrink, others, tol = inputs
        t_in, t_out = tp.tangents()
        windows = CornerWindows(table, tp.lengths, F, t_in, t_out, tol, d, limits, False)
        corners = np.arange(M - 1)
        plan = (head, tail, factor, arc_rel, full, shrink, others)
        _, _, (back, ahead) = windows._read(corners, *windows._reach(corners), *plan)
        assert back.all() and ahead.all()
        _, _, (back4, ahead4) = windows._read(corners, np.maximum(corners - 1, 0), np.minimum(corners + 2, M - 1), *plan)
        short += int(np.sum(~back4 | ~ahead4))
    assert short > 0


def test_pieces_at_are_the_pieces_of_the_whole_table():
    """``PulseTable.pieces_at`` (a few blocks' pieces, with multipliers ``g``) against
    ``PulseTable.pieces`` of the whole table at ``factor * g``: the same floats."""
    from research.interpolators._fir_settle import _pulse_table

    for seed in range(10):
        rng = np.random.default_rng(900 + seed)
        tp = random_program(rng, arcs=bool(seed % 2))
        table, M = _pulse_table(tp), tp.n_blocks
        head, tail = rng.uniform(0.0, 0.4, M), rng.uniform(0.0, 0.4, M)
        factor, g = rng.uniform(0.2, 1.0, (M, 3)), rng.uniform(0.3, 1.0, M)
        arc_rel = rng.uniform(0.5, 1.0, table.arc_pieces.size) if table.arc_pieces.size else None
        frac, pf = table.pieces(head, tail, factor * g[:, None], arc_rel)
        idx, owner = table.block_pieces(np.flatnonzero(rng.random(M) < 0.5))
        got_frac, got_pf = table.pieces_at(idx, head, tail, factor, arc_rel, g)
        np.testing.assert_array_equal(got_frac, frac[idx])
        np.testing.assert_array_equal(got_pf, pf[idx])


@pytest.mark.parametrize("blocks", [1, 2, 5, 300])
def test_limits_below_the_envelope_on_a_line_cut_into_blocks_regression(blocks):
    """Regression: a 1,000 mm line cut into 300 collinear blocks, under limits below the FIR
    envelope (jerk 1e4 mm/s^3 with T1 T2 = 2e-4 s^2: a block starting from rest at most at
    2 mm/s, Sencer 2015 §2.1, a pulse peaks at F / (T1 T2)), was slowed one block a round from
    each end (151 rounds; 2,000 blocks: 1,001 rounds, 4.2 s) down to 2 mm/s on every block: 500.03 s,
    6.1x the time at the velocity limit; as one or two blocks it stayed at 500.03 s (a block runs at
    the feed of its own start all the way), as 5 at 333.36 s. Now the feed rises in steps of at most
    ``J T1 T2`` = 2 mm/s (an isolated velocity step ``dV`` peaks at ``dV / (T1 T2)`` in jerk and
    ``dV / T1`` in acceleration), within the line or along its blocks (``_fir_straight.ramp_pieces``,
    ``_fir_limit_spread``): few rounds, the limits held on the sampled trajectory, the velocity
    limit reached, and a cycle between ``L / v + T_d`` (the velocity limit all the way) and 1 %
    above it (model prediction: the ramps cost ``(n - 1) T_d / 2`` each for ``n = 7`` steps, 0.09 s
    together), whatever the cut."""
    lim = AxisLimits.uniform(2, velocity=12.2, acceleration=500.0, jerk=1e4)
    d = (0.02, 0.01)
    x = np.linspace(0.0, 1000.0, blocks + 1)
    plan = plan_fir(Polyline(np.column_stack([x, 0.0 * x])), 12.2, d, 1e-4, limits=lim)
    assert plan.rounds <= 3
    assert float(np.max(plan.feeds)) == pytest.approx(12.2, rel=1e-9)
    bound = 1000.0 / 12.2 + sum(d)
    assert bound <= float(plan.cycle_time) <= 1.01 * bound
    assert within_limits(plan.trajectory(1e-3), lim)


def test_slowed_chains_of_random_chords_hold_the_limits_near_the_velocity_limit():
    """Seeded random chains of 150 chords (0.5-5 mm, turning by up to 2 deg) under limits below
    the FIR envelope: the limits and the tolerance are held on the sampled trajectory (independent
    of the planner's exact peaks), and the cycle time is at most 1.2x ``L / v + T_d`` (1.73-2.21x before; model
    prediction: slow blocks only in the ramps and where the turns' steps need them)."""
    lim = AxisLimits.uniform(2, velocity=20.0, acceleration=400.0, jerk=2e4)
    d = (0.03, 0.015)
    for seed in range(3):
        path = turning_path(500 + seed, 150, (0.5, 5.0), 2.0)
        plan = plan_fir(path, 20.0, d, 0.01, limits=lim)
        tr = plan.trajectory(1e-3)
        assert within_limits(tr, lim)
        assert float(np.max(np.asarray(plan.corner_errors))) <= 0.01 * (1 + 1e-9) + 1e-9
        bound = float(path.arc_length[-1]) / 20.0 + sum(d)
        assert bound <= float(plan.cycle_time) <= 1.2 * bound


def test_slow_down_along_a_chain_costs_linear_time():
    """The same chain at 400 and 1,600 blocks: planning time (best of two, process time) grows at
    most 8x for 4x the blocks (it grew 16x, one block a round: N / 2 rounds of O(N) each)."""
    lim = AxisLimits.uniform(2, velocity=12.2, acceleration=500.0, jerk=1e4)

    def cost(n):
        x = np.linspace(0.0, 1000.0, n + 1)
        path = Polyline(np.column_stack([x, 0.0 * x]))
        best = np.inf
        for _ in range(2):
            t = time.process_time()
            plan_fir(path, 12.2, (0.02, 0.01), 1e-4, limits=lim)
            best = min(best, time.process_time() - t)
        return best

    cost(50)  # compiled kernels warm
    assert cost(1600) < 8.0 * cost(400)


def test_feed_steps_is_the_isolated_step_bound():
    """``FeedSteps`` on three collinear x-axis lines, the first slowed to 2 mm/s, the middle one in
    pieces (head at 0.5 of the body's feed): the middle block's multiplier puts its head (the piece
    facing the slowed block) at 2 + min(A T1, J T1 T2) mm/s (an isolated velocity step ``dV``
    peaks at ``dV / T1`` and ``dV / (T1 T2)``, Sencer 2015 §2.1), here the jerk's 2 mm/s; the last
    block, set from the middle one's new tail in the same call, by the same rule; a diagonal line's
    bound per axis is the step over the direction's component."""
    from research.interpolators._fir_limit_spread import FeedSteps

    lim = AxisLimits.uniform(2, velocity=100.0, acceleration=500.0, jerk=1e4)
    d = (0.02, 0.01)
    step = min(500.0 * d[0], 1e4 * d[0] * d[1])  # 2 mm/s
    F = np.full(3, 50.0)
    u = np.array([[1.0, 0.0]] * 3)
    factor = np.array([[0.04, 0.04, 0.04], [0.5, 1.0, 1.0], [1.0, 1.0, 1.0]])
    steps = FeedSteps(F, u, np.zeros(3, dtype=bool), d, lim).of(np.array([0.0, 0.3, 0.0]), np.zeros(3))
    g, within, unset = steps(factor, np.array([False, True, True]), np.array([True, False, False]))
    assert g[1] * F[1] * factor[1, 0] == pytest.approx(2.0 + step)  # the head: 4 mm/s
    assert g[2] * F[2] == pytest.approx(g[1] * F[1] * factor[1, 2] + step)  # 8 + 2 mm/s after the body at 8
    assert not within.any() and not unset.any()
    diag = np.array([[1.0, 0.0], [np.sqrt(0.5), np.sqrt(0.5)]])
    steps = FeedSteps(F[:2], diag, np.zeros(2, dtype=bool), d, lim).of(np.zeros(2), np.zeros(2))
    g, _, _ = steps(np.array([[0.04] * 3, [1.0] * 3]), np.array([False, True]), np.array([True, False]))
    # |x u_x - 2| <= 2 and |x u_y| <= 2: x <= 2 / sqrt(0.5) from the y axis
    assert g[1] * F[1] == pytest.approx(step / np.sqrt(0.5))



def _feed_steps_reference(steps, factor, which, fixed):
    """``FeedSteps.__call__`` as a plain Python loop over dictionaries (the form it was before it
    was compiled): runs right then left, each block set counting as fixed for the next."""
    M = steps.feeds.size
    out, within, unset = np.full(M, np.nan), np.zeros(M, dtype=bool), np.zeros(M, dtype=bool)
    g_set = {}
    ks = np.flatnonzero(which).tolist()
    u_all, step, vel = steps.u.tolist(), steps.step.tolist(), steps.velocity.tolist()

    def column(k, side):  # head / body / tail, the first not empty from that side
        body = 1.0 - steps.head[k] - steps.tail[k]
        if side < 0:
            return 0 if steps.head[k] > 0.0 else (1 if body > 0.0 else 2)
        return 2 if steps.tail[k] > 0.0 else (1 if body > 0.0 else 0)
    for n in ks + ks[::-1]:
        if n in g_set or steps.is_arc[n]:
            continue
        near = [k for k in (n - 1, n + 1) if 0 <= k < M and (fixed[k] or k in g_set)]
        unset[n] = not near
        if not near or any(steps.is_arc[k] for k in near):
            continue
        u = u_all[n]
        top = float(steps.feeds[n]) * float(np.max(factor[n]))
        lo, hi = 0.0, min(1.0, min(v / abs(u_i) for v, u_i in zip(vel, u) if u_i != 0.0) / top)
        for k in near:
            side = -1 if k < n else 1
            x = float(steps.feeds[n] * factor[n, column(n, side)])
            s = float(steps.feeds[k] * factor[k, column(k, -side)]) * g_set.get(k, 1.0)
            lo_k, hi_k = -np.inf, np.inf
            for u_i, uk_i, step_i in zip(u, u_all[k], step):
                V = s * uk_i
                if u_i == 0.0:
                    if abs(V) > step_i:
                        lo_k = np.inf
                        break
                    continue
                a, b = (V - step_i) / (u_i * x), (V + step_i) / (u_i * x)
                lo_k, hi_k = max(lo_k, min(a, b)), min(hi_k, max(a, b))
            if lo_k == np.inf:
                lo = np.inf
                break
            lo, hi = max(lo, lo_k), min(hi, hi_k)
        if not (lo <= hi and hi > 0.0):
            continue
        if hi < 1.0 - 1e-12:
            out[n] = g_set[n] = hi
        else:
            within[n], g_set[n] = True, 1.0
        unset[n] = False
    return out, within, unset


def test_compiled_feed_steps_are_the_python_loop_bit_for_bit():
    """``FeedSteps.__call__`` (compiled, ``_fir_feed_steps``) against the plain Python loop it
    replaced, on seeded random chains: 2-D and 3-D directions (some along an axis: components
    exactly 0), arcs among the lines, head and tail shares, feed factors 0.01-1, random blocks to
    set and fixed neighbours, one and two filters: every multiplier, flag and NaN the same, bit
    for bit."""
    from research.interpolators._fir_limit_spread import FeedSteps

    rng = np.random.default_rng(17)
    set_, within_ = 0, 0
    for trial in range(60):
        M, d = int(rng.integers(2, 40)), int(rng.integers(2, 4))
        u = rng.normal(size=(M, d))
        u[rng.random((M, d)) < 0.2] = 0.0
        u[np.all(u == 0.0, axis=1), 0] = 1.0
        u /= np.linalg.norm(u, axis=1, keepdims=True)
        delays = (0.03, 0.01) if trial % 2 else (0.02,)
        lim = AxisLimits(rng.uniform(50.0, 300.0, d), rng.uniform(100.0, 5000.0, d), rng.uniform(1e3, 1e6, d))
        steps = FeedSteps(rng.uniform(10.0, 300.0, M), u, rng.random(M) < 0.15, delays, lim)
        head = np.where(rng.random(M) < 0.4, rng.uniform(0.0, 0.5, M), 0.0)
        tail = np.where(rng.random(M) < 0.4, rng.uniform(0.0, 0.5, M), 0.0)
        steps = steps.of(head, tail)
        factor = rng.uniform(0.01, 1.0, (M, 3))
        which, fixed = rng.random(M) < 0.5, rng.random(M) < 0.3
        got = steps(factor, which, fixed)
        want = _feed_steps_reference(steps, factor, which, fixed)
        for x, y in zip(got, want):
            np.testing.assert_array_equal(x, y)
        set_, within_ = set_ + int(np.sum(~np.isnan(got[0]))), within_ + int(np.sum(got[1]))
    assert set_ > 50 and within_ > 10  # the cases exercised, not only NaN

def test_a_losing_candidates_chain_walk_is_suspended(monkeypatch):
    """A circle of radius 2 m in 4,000 chords under limits below the FIR envelope (jerk 1e4
    mm/s^3, T1 T2 = 2e-4 s^2: 2 mm/s from rest) at eps = 0.1 um. The winning candidate slows only
    the blocks of the path's two end ramps (a few walk steps); two look-ahead candidates of the
    same bound, whose corners are dwell corners (eq 13/14 overlaps at the tolerance), turn each
    feed step into a partial overlap that breaks the jerk limit at the next corner, and their walks
    would slow the whole circle block by block (3,925 walk steps, 5.4 s of 5.5 s planning, for plans
    of over 5,000 s that lose). A walk is weighed against the other candidates' bounds after 1, 2,
    4, ... steps and suspended once its prediction passes them (resumed where it stopped, the same
    walk), so the losers stop after a few steps: fewer than 100 steps in all (model prediction:
    O(log N) per candidate). The plan holds the limits and the tolerance on its sampled trajectory
    and its cycle is within 1 % above ``L / v + T_d`` (the velocity limit all the way)."""
    from research.interpolators import _fir_limit_spread

    calls = []
    original = _fir_limit_spread.FeedSteps.__call__

    def counted(self, factor, which, fixed):
        calls.append(1)
        return original(self, factor, which, fixed)

    monkeypatch.setattr(_fir_limit_spread.FeedSteps, "__call__", counted)
    lim = AxisLimits.uniform(2, velocity=12.2, acceleration=500.0, jerk=1e4)
    d = (0.02, 0.01)
    a = np.linspace(0.0, 2.0 * np.pi, 4001)
    path = Polyline(2000.0 * np.column_stack([np.cos(a), np.sin(a)]))
    plan = plan_fir(path, 12.2, d, 1e-4, limits=lim)
    assert 0 < len(calls) < 100
    bound = float(path.arc_length[-1]) / 12.2 + sum(d)
    assert bound <= float(plan.cycle_time) <= 1.01 * bound
    assert within_limits(plan.trajectory(1e-3), lim)
    assert float(np.max(np.asarray(plan.corner_errors))) <= 1e-4 * (1 + 1e-9) + 1e-9


def test_block_keys_tell_blocks_apart_bit_for_bit():
    """``_fir_settle._block_keys`` (phase 1's per-plan memo of blocks checked alone): two blocks get
    the same key exactly when their index, safe multiplier and every piece's share and feed factor
    are the same floats (an independent comparison of tuples), whatever their piece counts (a
    block of fewer pieces is not equal to one padded with zeros)."""
    from research.interpolators._fir_settle import _block_keys

    rng = np.random.default_rng(5)
    for _ in range(50):
        K = int(rng.integers(1, 40))
        ks = rng.integers(0, 6, K)
        counts = rng.integers(1, 4, K)
        owner = np.repeat(np.arange(K), counts)
        frac = rng.choice([0.0, 0.25, 0.5, 1.0], owner.size)
        pf = rng.choice([0.5, 1.0, 1.0 + 2.0**-52], owner.size)
        safe = rng.choice([0.3, 1.0], K)
        keys = _block_keys(ks, safe, owner, frac, pf, 3)
        tuples = [(int(ks[i]), float(safe[i]), tuple(frac[owner == i]), tuple(pf[owner == i])) for i in range(K)]
        for i in range(K):
            for j in range(K):
                assert (keys[i] == keys[j]) == (tuples[i] == tuples[j])
                assert (hash(keys[i]) == hash(keys[j])) or tuples[i] != tuples[j]


def test_releasing_suspended_candidates_changes_no_plan(monkeypatch):
    """A seeded circle of 1-4 deg chords under limits at 0.088x the FIR envelope (the stress sweep's
    program 2), whose candidates are suspended inside their chain walks and after their vertex
    errors: planned with the default of one held profile (the others released and rebuilt from
    the same inputs on resuming) and with every profile held, the plans are the same to the bit,
    and the default built more profiles (it released some)."""
    from research.interpolators import _fir_profile, _fir_settle

    rng = np.random.default_rng(1002)
    n, radius, step = int(rng.integers(30, 200)), rng.uniform(5.0, 60.0), rng.uniform(0.5, 4.0)
    th = np.radians(np.arange(n) * step) + rng.uniform(0.0, 2.0 * np.pi)
    path = Polyline(np.column_stack([radius * np.cos(th), radius * np.sin(th)]))
    eps, feed = float(rng.uniform(0.005, 0.1)), float(rng.uniform(50.0, 300.0))
    d = (0.06, 0.03)
    env = AxisLimits.fir_envelope(2, feed, d)
    s = float(np.exp(rng.uniform(np.log(0.05), 0.0)))
    limits = AxisLimits(env.velocity, s * env.acceleration, s * env.jerk)
    builds = []
    original = _fir_profile.profile

    def counted(*args, **kwargs):
        builds.append(1)
        return original(*args, **kwargs)

    monkeypatch.setattr(_fir_profile, "profile", counted)
    default = plan_fir(path, feed, d, eps, limits=limits)
    n_default = len(builds)
    monkeypatch.setattr(_fir_settle, "_HELD_PROFILES", 10**6)
    builds.clear()
    held = plan_fir(path, feed, d, eps, limits=limits)
    assert n_default > len(builds)
    assert float(default.cycle_time) == float(held.cycle_time)
    for a, b in ((default.feeds, held.feeds), (default.overlaps, held.overlaps), (default.start_times, held.start_times),
                 (default.pulse_times, held.pulse_times)):
        np.testing.assert_array_equal(np.asarray(a), np.asarray(b))
    assert within_limits(default.trajectory(1e-3), limits)


def test_staircase_joins_caps_by_isolated_steps():
    """``_fir_staircase.staircase`` on seeded random chains (block lengths 0.1-2 mm, caps 5-200 mm/s
    with dips): never above a block's cap, starts and ends within one step of rest, changes by at
    most one step between neighbours, and where the cap stays at C for longer than the ramps take,
    reaches C (model: levels of one step, each held T_d, so C / step levels)."""
    from research.interpolators._fir_staircase import staircase

    rng = np.random.default_rng(12)
    hold = 0.09
    for _ in range(30):
        M = int(rng.integers(50, 600))
        lengths = rng.uniform(0.1, 2.0, M)
        cap = np.where(rng.random(M) < 0.03, rng.uniform(5.0, 50.0, M), rng.uniform(150.0, 200.0))
        step = float(rng.uniform(5.0, 40.0))
        out = staircase(lengths, cap, step, hold)
        assert np.all(out <= cap) and np.all(out > 0.0)
        assert out[0] <= step * (1 + 1e-12) and out[-1] <= step * (1 + 1e-12)
        assert np.all(np.abs(np.diff(out)) <= step * (1 + 1e-12))
    lengths, C, step = np.full(2000, 0.5), 60.0, 10.0
    out = staircase(lengths, np.full(2000, C), step, hold)
    ramp = int(np.ceil(C / step)) * int(np.ceil(hold * C / 0.5))  # blocks of the longest ramp, generously
    assert np.all(out[ramp:-ramp] == C)


def test_tight_limits_run_a_circle_of_short_chords_above_the_feed_of_a_start_from_rest():
    """A circle of R 20 mm in 600 chords of 0.21 mm at F 200 mm/s, T 60/30 ms, limits at 0.05x the
    FIR envelope's acceleration and jerk (167 mm/s^2, 5,556 mm/s^3: one isolated step
    ``min(A T1, J T1 T2)`` = 10 mm/s, Sencer 2015 §2.1). Every chord alone starts from rest at
    most at 10 mm/s and phase 1 took the whole circle there (11.44 s, 11.0 mm/s on average); the
    feeds capped window by window and joined by staircases of isolated steps
    (``_fir_staircase``) run it at more than twice that on average, within the limits and the
    tolerance, and not faster than the curvature allows (model prediction: ``v^2 / R <= A`` gives
    ``sqrt(A R)`` = 57.7 mm/s)."""
    n, R, F = 600, 20.0, 200.0
    a = np.linspace(0.0, 2.0 * np.pi, n + 1)
    path = Polyline(R * np.column_stack([np.cos(a), np.sin(a)]))
    d = (0.06, 0.03)
    env = AxisLimits.fir_envelope(2, F, d)
    lim = AxisLimits(env.velocity, 0.05 * env.acceleration, 0.05 * env.jerk)
    plan = plan_fir(path, F, d, 0.05, limits=lim)
    L = 2.0 * np.pi * R
    step = float(np.min(0.05 * env.acceleration * d[0]))
    assert L / np.sqrt(float(np.min(lim.acceleration)) * R) <= float(plan.cycle_time) <= L / (2.0 * step)
    assert within_limits(plan.trajectory(1e-3), lim)
    assert float(np.max(np.asarray(plan.corner_errors))) <= 0.05 * (1 + 1e-9) + 1e-9


def test_tight_limits_where_the_tolerance_binds_run_a_circle_near_its_steady_feed():
    """A circle of R 20 mm in 0.5 mm chords at F 200 mm/s, T 60/30 ms, eps 50 um, limits at 0.1x
    the FIR envelope's acceleration and jerk (333 mm/s^2, 11,111 mm/s^3). Model prediction of the
    steady feed ``v*``: the least of the tolerance's (eq 8: the filtered circle's radius
    ``R prod sinc(w T_i / 2)``, ``w = v / R``, within eps of R: ~73 mm/s), the acceleration's
    (``v^2 / R <= A``: 81.6 mm/s) and the jerk's (``v^3 / R^2 <= J``: 164 mm/s) on each axis of a
    circle; reached from rest and back by isolated steps ``min(A T1, J T1 T2)`` (Sencer 2015 §2.1),
    each held ``T_d``, and run 2 % below a window's ratio (the repairs' ``0.98 / ratio``). The
    plan's cycle is within ``L / (0.98 v*) + (2 ceil(v* / step) + 1) T_d``. The staircase capped
    at the commanded feed broke the tolerance at every window and its repairs took the circle to
    5.54 s (the bound is 2.6 s); the one capped at the feeds of the look-ahead candidate without
    dwells runs it in 2.25 s."""
    from scipy.optimize import brentq

    R, chord, F, eps = 20.0, 0.5, 200.0, 0.05
    d = np.array([0.06, 0.03])
    n = int(2.0 * np.pi * R / chord)
    a = np.linspace(0.0, 2.0 * np.pi, n + 1)
    path = Polyline(R * np.column_stack([np.cos(a), np.sin(a)]))
    env = AxisLimits.fir_envelope(2, F, tuple(d))
    lim = AxisLimits(env.velocity, 0.1 * env.acceleration, 0.1 * env.jerk)
    A, J = float(np.min(lim.acceleration)), float(np.min(lim.jerk))
    radial = lambda v: R * (1.0 - np.prod(np.sinc(v / R * d / 2.0 / np.pi))) - eps  # noqa: E731  (np.sinc is sin(pi x) / (pi x))
    v_tol = brentq(radial, 1.0, F)
    v_star = min(F, v_tol, np.sqrt(A * R), (J * R * R) ** (1.0 / 3.0))
    step = min(A * d[0], J * d[0] * d[1])
    Td = float(d.sum())
    bound = path.length / (0.98 * v_star) + (2 * np.ceil(v_star / step) + 1) * Td
    plan = plan_fir(path, F, tuple(d), eps, limits=lim)
    assert float(plan.cycle_time) <= bound, (float(plan.cycle_time), bound, v_star)
    assert within_limits(plan.trajectory(1e-3), lim)
    assert float(np.max(np.asarray(plan.corner_errors))) <= eps * (1 + 1e-9) + 1e-9


def _seeded_circle(rng):
    """A circle of 30-200 chords of 0.5-4 deg, R 5-60 mm, with eps 5-100 um and F 50-300 mm/s
    (``benchmarks/fir_limits_stress.py``'s circles)."""
    n, radius, step = int(rng.integers(30, 200)), rng.uniform(5.0, 60.0), rng.uniform(0.5, 4.0)
    th = np.radians(np.arange(n) * step) + rng.uniform(0.0, 2.0 * np.pi)
    return Polyline(np.column_stack([radius * np.cos(th), radius * np.sin(th)])), float(rng.uniform(0.005, 0.1)), \
        float(rng.uniform(50.0, 300.0))


@pytest.mark.parametrize("kind", ["lines", "arcs", "circles"])
def test_the_tolerance_aware_staircase_only_adds_a_plan(kind, monkeypatch):
    """The staircase under the feeds of the look-ahead candidate without dwells is settled after
    every other candidate (``_fir_settle``'s capped ``"last"``), so it rules none of them out: on
    seeded random programs (lines; lines and arcs) and chord circles under limits at 0.05-0.5x the
    envelope's acceleration and jerk, the plan is never slower than the plan without that
    candidate (``without_dwells`` returning None); on the circles (chord chains, where it is
    meant to win) some are faster."""
    import research.interpolators._fir_settle as settle_module
    from tests.interpolators.test_fir_monotone import DELAYS, _program

    faster = 0
    for seed in range(5):
        rng = np.random.default_rng(500 + seed)
        path, eps, feed = _seeded_circle(rng) if kind == "circles" else _program(seed, kind == "arcs")
        s = float(np.exp(rng.uniform(np.log(0.05), np.log(0.5))))
        env = AxisLimits.fir_envelope(path.dim, feed, DELAYS)
        lim = AxisLimits(env.velocity, s * env.acceleration, s * env.jerk)
        with_it = float(plan_fir(path, feed, DELAYS, eps, limits=lim).cycle_time)
        with monkeypatch.context() as m:
            m.setattr(settle_module, "without_dwells", lambda candidates: None)
            without = float(plan_fir(path, feed, DELAYS, eps, limits=lim).cycle_time)
        assert with_it <= without * (1 + 1e-12), (seed, with_it, without)
        faster += with_it < without * (1 - 1e-9)
    assert faster >= 1 or kind != "circles"
