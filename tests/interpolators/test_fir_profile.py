"""The planner's concrete-array schedule and profile (``_fir_profile``) and its local re-checks
(``_fir_verify.RoundChecks``) against independent computations.

References: the moving average of a piecewise-constant function integrated exactly from its steps
(Sencer 2015 eq 1: ``y(t) = (1 / T) integral_{t - T}^t x``); eq 14's two closed-form branches as
printed in ``_fir_overlap``'s docstring; the JAX build (``_fir_blocks.build_profile``, another
implementation: a merge by searches, XLA's sums); full checks on the whole profile. Nothing is
compared with the planner's earlier output."""

import jax.numpy as jnp
import numpy as np
import pytest

from research.interpolators import _fir_profile
from research.interpolators._fir_blocks import PulseTable, build_profile
from research.interpolators._fir_overlap import overlap_time
from research.interpolators._fir_kernels import verified_bound
from research.interpolators._fir_verify import RoundChecks, path_deviations, vertex_distances
from research.paths import Polyline
from research.paths.library import random_program
from research.paths.toolpath import ToolPath
from research.piecewise import NumpyPiecewise


def test_moving_average_is_the_window_mean_of_the_steps():
    """One filter on random steps (zero-length pieces included): the value at any time is the exact
    mean of the steps over the last ``T`` (integrated step by step here)."""
    rng = np.random.default_rng(0)
    widths = np.where(rng.random(40) < 0.3, 0.0, rng.uniform(0.001, 0.05, 40))
    breaks = np.concatenate([[0.0], np.cumsum(widths)])
    values = rng.normal(size=(40, 2))
    T = 0.037
    b, _, c = _fir_profile._moving_average(breaks, np.zeros_like(breaks), values[:, None, :], T)
    t = rng.uniform(0.0, breaks[-1] + T, 300)
    got = NumpyPiecewise(b, c)(t)
    lo = np.clip(t[:, None] - T, breaks[None, :-1], breaks[None, 1:])
    hi = np.clip(t[:, None], breaks[None, :-1], breaks[None, 1:])
    want = (hi - lo) @ values / T
    assert np.max(np.abs(got - want)) <= 1e-12 * np.max(np.abs(values))


@pytest.mark.parametrize("delays", [(0.06, 0.03), (0.05, 0.03, 0.02)])
def test_profile_matches_the_jax_build(delays):
    """Lines and arcs, random head/tail shares, feeds and gaps: the same starts, ends and corner
    instants (to rounding) and the same position (to 1e-9 mm) as ``build_profile``; the motion ends
    on the path's end point."""
    rng = np.random.default_rng(4)
    tp = random_program(np.random.default_rng(2), arcs=True)
    assert tp.is_arc.any() and (~tp.is_arc).any()
    table = PulseTable.from_path(tp)
    M, Mp = tp.n_blocks, table.m_pad
    d = np.asarray(delays)
    head, tail = rng.uniform(0.0, 0.4, M), rng.uniform(0.0, 0.4, M)
    frac, factor = table.pieces(head, tail, rng.uniform(0.3, 1.0, (M, 3)), rng.uniform(0.5, 1.0, table.arc_pieces.size))
    piece_tv = np.concatenate([tp.lengths, np.ones(Mp - M + 1)])[table.block] / (150.0 * factor)
    gaps = np.concatenate([rng.uniform(0.0, d.sum(), M - 1), np.zeros(Mp - M + 1)])
    args = (tp.start, table.geo, table.block, table.gap, frac, piece_tv, gaps, d)
    starts, ends, breaks, coeffs, centre = _fir_profile.profile(*args)
    s_j, e_j, pos_j, c_j = build_profile(*(jnp.asarray(a) for a in args))
    for got, want in ((starts, s_j), (ends, e_j), (centre, c_j)):
        np.testing.assert_allclose(got, np.asarray(want), rtol=1e-12, atol=1e-12)
    t = np.linspace(0.0, float(breaks[-1]), 4001)
    ours = NumpyPiecewise(breaks, coeffs)
    theirs = NumpyPiecewise(np.asarray(pos_j.breaks), np.asarray(pos_j.coeffs))
    assert np.max(np.abs(ours(t) - theirs(t))) <= 1e-9
    assert np.max(np.abs(ours(t, 1) - theirs(t, 1))) <= 1e-7  # mm/s
    np.testing.assert_allclose(ours(np.array([breaks[-1]]))[0], tp.ends[-1], atol=1e-9)


@pytest.mark.parametrize("n_filters", [1, 2, 3])
def test_schedule_span_is_the_built_profiles_first_and_last_break(n_filters):
    """``schedule_span`` (no filter run) against the profile built by the filters: the same block
    starts, ends and corner instants, and a span equal, bit for bit, to the built profile's first
    and last break; on random programs of lines and arcs with random shares, feeds and gaps (full
    overlaps, so empty gap pieces, included), and through ``plan_fir(refine=False)``, whose plan
    keeps the span and builds the profile only when read."""
    from research.interpolators import plan_fir

    rng = np.random.default_rng(40 + n_filters)
    for trial in range(40):
        tp = random_program(rng, arcs=bool(trial % 2))
        table = PulseTable.from_path(tp)
        M, Mp = tp.n_blocks, table.m_pad
        d = rng.uniform(0.002, 0.12, n_filters)
        head, tail = rng.uniform(0.0, 0.4, M), rng.uniform(0.0, 0.4, M)
        frac, factor = table.pieces(head, tail, rng.uniform(0.3, 1.0, (M, 3)),
                                    rng.uniform(0.5, 1.0, table.arc_pieces.size))
        piece_tv = np.concatenate([tp.lengths, np.ones(Mp - M + 1)])[table.block] / (rng.uniform(20, 300) * factor)
        gaps = np.where(rng.random(M - 1) < 0.5, 0.0, rng.uniform(0.0, d.sum(), M - 1))
        gaps = np.concatenate([gaps, np.zeros(Mp - M + 1)])
        args = (table.geo, table.block, table.gap, frac, piece_tv, gaps, d, table.joins)
        starts, ends, breaks, _, centre = _fir_profile.profile(tp.start, *args)
        s2, e2, span, c2 = _fir_profile.schedule_span(*args)
        for got, want in ((s2, starts), (e2, ends), (c2, centre)):
            np.testing.assert_array_equal(got, want)
        assert span[0] == breaks[0] and span[1] == breaks[-1]
        plan = plan_fir(tp, rng.uniform(20, 300), d, rng.uniform(0.01, 0.2), refine=False)
        built = plan.position.breaks  # the profile built on first read, from the plan's inputs
        assert float(plan.cycle_time) == float(built[-1] - built[0])


def test_overlaps_follow_eq14_and_the_jax_inversion():
    """Two filters: eq 14's branches, ``(24 T1 T2 eps / (F sin(b/2)))^(1/3)`` up to ``2 T2`` and
    ``T2 + sqrt(4 T1 eps / (F sin(b/2)) - T2^2 / 3)`` beyond (with ``|dF| = 2 F sin(b/2)``); full
    overlap where even ``T_d`` keeps the tolerance. Three and four filters: the JAX inversion of
    ``H2`` (an optimistix bisection stopped at 1e-13 relative) to 1e-12, and the corner error of
    the overlap found, ``|dF| H2(T_k / 2)`` by the JAX form of ``H2`` (``_fir_chain``), equal to
    the tolerance to 1e-14 relative (the compiled search runs to the float resolution)."""
    T1, T2 = 0.06, 0.03
    F, eps = 200.0, np.array([1e-4, 5e-3, 0.05, 1.0, 2.0, 10.0])
    sin_half = np.full(eps.size, np.sin(np.radians(45.0)))
    got = _fir_profile.overlaps(eps, 2.0 * F * sin_half, np.array([T2, T1]))  # any order of delays
    first = np.cbrt(24.0 * T1 * T2 * eps / (F * sin_half))
    second = T2 + np.sqrt(np.maximum(4.0 * T1 * eps / (F * sin_half) - T2**2 / 3.0, 0.0))
    want = np.where(first <= 2.0 * T2, first, np.minimum(second, T1 + T2))
    assert np.any(first <= 2 * T2) and np.any((first > 2 * T2) & (second < T1 + T2))  # both branches
    np.testing.assert_allclose(got, want, rtol=1e-12)
    assert got[-1] == T1 + T2
    from research.interpolators._fir_chain import kernel_second_integral

    dF = np.linspace(1.0, 300.0, 7)
    for delays in (np.array([0.05, 0.03, 0.02]), np.array([0.02, 0.05, 0.011, 0.03])):
        Tk = _fir_profile.overlaps(0.01, dF, delays)
        np.testing.assert_allclose(Tk, np.asarray(overlap_time(0.01, dF, delays)), rtol=1e-12)
        inside = Tk < delays.sum()
        assert inside.sum() >= 5
        error = dF[inside] * np.asarray(kernel_second_integral(0.5 * Tk[inside], delays))
        np.testing.assert_allclose(error, 0.01, rtol=1e-14)


def _zigzag_profile(feed_scale):
    rng = np.random.default_rng(5)
    pts = np.cumsum(np.column_stack([rng.uniform(0.5, 3.0, 80), rng.uniform(-1.0, 1.0, 80)]), axis=0)
    tp = ToolPath.from_polyline(Polyline(pts))
    table = PulseTable.from_path(tp)
    M, Mp = tp.n_blocks, table.m_pad
    d = np.array([0.06, 0.03])
    frac, factor = table.pieces(np.zeros(M), np.zeros(M), np.repeat(feed_scale[:, None], 3, axis=1))
    piece_tv = np.concatenate([tp.lengths, np.ones(Mp - M + 1)])[table.block] / (100.0 * factor)
    gaps = np.concatenate([np.full(M - 1, 0.01), np.zeros(Mp - M + 1)])
    starts, ends, breaks, coeffs, centre = _fir_profile.profile(tp.start, table.geo, table.block, table.gap, frac,
                                                                piece_tv, gaps, d)
    durations = np.where(table.gap, np.append(gaps, 0.0)[table.block], frac * piece_tv)
    return tp, table, NumpyPiecewise(breaks, coeffs), starts[:M], centre[: M - 1], durations, float(d.sum())


def test_round_checks_redo_only_the_changed_stretch_and_agree_with_full_checks():
    """First call: exactly the full checks. After slowing two blocks: every vertex error equals the
    full recomputation on the new profile (to 1e-9 mm: unchanged windows are the old output shifted
    in time) and fewer path samples are taken. The sampled deviations of stretches not redone were
    taken on the grid of an earlier check, shifted against the new one: each is within the
    sampling bound ``v_max check_period / 2`` of a full check's (the distance to the path changes
    at most at the trajectory's speed), and a corner flagged by one check only is within it of
    the tolerance."""
    scale = np.ones(80)
    tp, table, pos, starts, centre, durations, Td = _zigzag_profile(scale)
    tol = np.full(80, 0.02)
    checks = RoundChecks(tp, tol, table.block, Td, 1e-3)
    errors, dev, at_v, at_b = checks(pos, starts, centre, durations, True)
    np.testing.assert_array_equal(errors, vertex_distances(pos, tp.vertices, centre, 0.5 * Td, verified_bound(0.02)))
    assert (dev, at_v, at_b) == path_deviations(pos, tp, starts, centre, Td, tol, 1e-3)
    assert len(at_v) > 5  # the tolerance is broken at some corners: a real check
    full_samples = checks.samples
    scale[[30, 31]] = 0.5
    tp, table, pos, starts, centre, durations, Td = _zigzag_profile(scale)
    errors, dev, at_v, _ = checks(pos, starts, centre, durations, True)
    np.testing.assert_allclose(errors, vertex_distances(pos, tp.vertices, centre, 0.5 * Td, verified_bound(0.02)),
                               rtol=0, atol=1e-9)
    assert checks.samples < 0.5 * full_samples
    dev_full, at_full, _ = path_deviations(pos, tp, starts, centre, Td, tol, 1e-3)
    bound = 0.5 * 1e-3 * np.max(np.linalg.norm(pos(np.linspace(0.0, pos.breaks[-1], 20001), 1), axis=1))
    assert abs(dev - dev_full) <= bound
    for j in set(at_v) | set(at_full):
        a, b = at_v.get(j, tol[0]), at_full.get(j, tol[0])
        assert abs(a - b) <= bound


def test_round_checks_adopted_by_another_candidate_act_as_a_next_round():
    """Another candidate of the same plan (same pulse table) adopting a check's snapshot checks only
    where its input differs, exactly as a next round of the first candidate would: on the same
    profile it takes no path samples and returns the same results; on a profile with two blocks
    slowed it returns what the first candidate's own next round returns, bit for bit, with the
    same number of samples."""
    scale = np.ones(80)
    tp, table, pos, starts, centre, durations, Td = _zigzag_profile(scale)
    tol = np.full(80, 0.02)
    first = RoundChecks(tp, tol, table.block, Td, 1e-3)
    own = first(pos, starts, centre, durations, True)
    snap = first.snapshot()
    same = RoundChecks(tp, tol, table.block, Td, 1e-3)
    same.adopt(snap)
    again = same(pos, starts, centre, durations, True)
    assert same.samples == 0
    np.testing.assert_array_equal(again[0], own[0])
    assert again[1:] == own[1:]
    scale[[30, 31]] = 0.5
    tp, table, pos, starts, centre, durations, Td = _zigzag_profile(scale)
    other = RoundChecks(tp, tol, table.block, Td, 1e-3)
    other.adopt(snap)
    adopted = other(pos, starts, centre, durations, True)
    next_round = first(pos, starts, centre, durations, True)
    np.testing.assert_array_equal(adopted[0], next_round[0])
    assert adopted[1:] == next_round[1:] and other.samples == first.samples > 0


def test_profile_of_the_first_blocks_is_the_plan_until_their_input_ends():
    """``plan_fir``'s first bound of a competing candidate (``prefix_bound``) checks vertex errors
    on the profile of the input of its first K blocks alone. The output at ``t`` averages the input
    over ``[t - T_d, t]`` (Sencer 2015 eq 1), so up to the instant ``T_cut`` that input ends (block
    K's start) it is the whole plan's; after it, it is not (the input stops). Checked on a random
    line-and-arc program: positions and vertex errors of the corners whose search window ends by
    ``T_cut`` are the whole profile's, bit for bit (the same pieces in the same order)."""
    rng = np.random.default_rng(3)
    tp = ToolPath.from_polyline(Polyline([[0.0, 0.0], [5.0, 0.0]]))
    for _ in range(40):  # lines of 0.5-3 mm at turns up to 60 deg, every third block an arc
        end, ang = tp.ends[-1], rng.uniform(-np.pi / 3, np.pi / 3)
        if len(tp.sweeps) % 3 == 2:
            radius = rng.uniform(2.0, 10.0)
            centre = end + radius * np.array([-np.sin(ang), np.cos(ang)])
            tp = tp.then_arc(centre + (end - centre) @ np.array([[np.cos(0.5), np.sin(0.5)], [-np.sin(0.5), np.cos(0.5)]]),
                             centre, ccw=True)
        else:
            step = rng.uniform(0.5, 3.0) * np.array([np.cos(ang), np.sin(ang)])
            tp = ToolPath(tp.start, np.vstack([tp.ends, end + step]), np.vstack([tp.centers, [[np.nan, np.nan]]]),
                          np.vstack([tp.normals, [[np.nan] * 3]]), np.concatenate([tp.sweeps, [0.0]]))
    assert tp.is_arc.sum() > 5
    table = PulseTable.from_path(tp)
    M, Mp = tp.n_blocks, table.m_pad
    d = np.array([0.06, 0.03])
    Td = float(d.sum())
    frac, factor = table.pieces(np.zeros(M), np.zeros(M), np.ones((M, 3)), np.ones(table.arc_span.shape[0]))
    piece_tv = np.concatenate([tp.lengths, np.ones(Mp - M + 1)])[table.block] / (40.0 * factor)
    gaps = np.concatenate([np.random.default_rng(4).uniform(0.0, Td, M - 1), np.zeros(Mp - M + 1)])
    starts, _, breaks, coeffs, centre = _fir_profile.profile(tp.start, table.geo, table.block, table.gap, frac,
                                                             piece_tv, gaps, d)
    whole = NumpyPiecewise(breaks, coeffs)
    K = M // 2
    c = int(table.first_motion[K])
    p_starts, _, p_breaks, p_coeffs, p_centre = _fir_profile.profile(tp.start, table.geo[:c], table.block[:c],
                                                                     table.gap[:c], frac[:c], piece_tv[:c], gaps, d)
    part = NumpyPiecewise(p_breaks, p_coeffs)
    t_cut = p_starts[K]
    assert t_cut == starts[K]
    t = np.linspace(0.0, t_cut, 2001)
    np.testing.assert_array_equal(part(t), whole(t))  # the same pieces, computed in the same order
    later = np.linspace(t_cut + 0.2 * Td, t_cut + Td, 50)  # the input has stopped: not the plan
    assert np.max(np.abs(part(later) - whole(later))) > 1e-6
    np.testing.assert_array_equal(p_centre[: K - 1], centre[: K - 1])
    j = np.flatnonzero(centre[: K - 1] + 0.5 * Td <= t_cut)
    assert j.size > 3
    np.testing.assert_array_equal(vertex_distances(part, tp.vertices[j], centre[j], 0.5 * Td),
                                  vertex_distances(whole, tp.vertices[j], centre[j], 0.5 * Td))


@pytest.mark.parametrize("arcs", [False, True])
def test_plan_holds_its_profile_inputs_within_their_float_count(arcs):
    """The returned plan's arrays stay within the floats its representation needs: ``3 M + 2 (M - 1)
    + (M - 1) d + n`` for the schedule (starts, pulses, feeds; overlaps, corner instants; vertices;
    delays) and ``2 P + M_pad + n + d + 2`` for the profile's inputs (piece shares and pulse
    lengths, gaps, delays, start point, first and last break), the pieces' geometry being the
    path's own table (not copied; on arcs, the table whose sub-arcs the planner cut where its
    windows end). The coefficients that ``position`` builds are more than that
    whole bound (so a plan holding them fails), and the built profile agrees with the plan: its
    span is the cycle time, bit for bit, it ends on the path's end point, at rest, and matches the
    JAX build of the same inputs."""
    import jax

    from research.interpolators import _fir_settle, fir

    if arcs:
        tp = random_program(np.random.default_rng(2), arcs=True)
        assert tp.is_arc.any()
    else:  # a random walk of 200 short lines
        steps = np.random.default_rng(7).uniform(-1.0, 1.0, (200, 2))
        tp = ToolPath.from_polyline(Polyline(np.cumsum(np.vstack([[0.0, 0.0], steps]), axis=0)))
    delays = (0.06, 0.03)
    plan = fir.plan_fir(tp, 150.0, delays, 0.05)
    table = plan.profile.pieces.table
    own = _fir_settle._pulse_table(tp)
    if arcs:  # the path's table with its sub-arcs cut where the look-ahead's windows end
        assert table.arc_pieces.size > own.arc_pieces.size
        np.testing.assert_array_equal(table.block[table.first_motion], np.arange(tp.n_blocks))
    else:
        assert table is own
    M, d, n, P, Mp = tp.n_blocks, tp.dim, len(delays), table.block.size, table.m_pad
    bound = 8 * (3 * M + 2 * (M - 1) + (M - 1) * d + n + 2 * P + Mp + n + d + 2)
    held = sum(np.asarray(x).nbytes for x in jax.tree_util.tree_leaves(plan))
    assert held <= bound
    pos = plan.position
    assert plan.position is pos  # built once, kept
    assert np.asarray(pos.coeffs).nbytes > bound
    assert float(pos.end - pos.start) == float(plan.cycle_time)
    np.testing.assert_allclose(pos.evaluate_numpy(np.array([float(pos.end)]))[0], tp.ends[-1], atol=1e-9)
    assert np.max(np.abs(pos.evaluate_numpy(np.array([float(pos.end)]), nu=1))) <= 1e-9
    p = plan.profile
    _, _, pos_j, _ = build_profile(*(jnp.asarray(a) for a in (tp.start, table.geo, table.block, table.gap, p.fraction,
                                                                p.piece_tv, p.gaps, p.delays)))
    t = np.linspace(float(pos.start), float(pos.end), 500)
    np.testing.assert_allclose(pos.evaluate_numpy(t), np.asarray(pos_j(jnp.asarray(t))), atol=1e-9)


def test_profile_build_holds_no_oversized_buffer_and_no_spent_input():
    """Memory of one exact profile build (issue "a faster, near-optimal FIR planner": memory per
    segment). On a plan of 2,000 short lines through two filters, the build's peak traced memory is
    at most the input pulses + the first filter's pieces + 8/7 of the position's (each counted
    here from the shapes the stages return, called one by one) + 64 kB: a filter's input is not
    held once the next one is built, and a buffer sized for all ``2 K + 1`` merged pieces is kept
    only where it is more than 7/8 used (here the first filter fills its buffer: its input has no
    empty piece)."""
    import tracemalloc

    from research.interpolators import fir

    steps = np.random.default_rng(11).uniform(-1.0, 1.0, (2000, 2))
    tp = ToolPath.from_polyline(Polyline(np.cumsum(np.vstack([[0.0, 0.0], steps]), axis=0)))
    d = np.array([0.06, 0.03])
    inp = fir.plan_fir(tp, 150.0, tuple(d), 0.05).profile
    t = inp.pieces.table
    args = (tp.start, t.geo, t.block, t.gap, inp.fraction, inp.piece_tv, inp.gaps, d, t.joins)
    joins = np.zeros(t.block.size, dtype=bool) if t.joins is None else t.joins
    b0, l0, c0, _ = _fir_profile._input_pulses(t.geo, t.block, t.gap, inp.fraction, inp.piece_tv, inp.gaps, joins)
    b1, l1, c1 = _fir_profile._moving_average(b0, l0, c0, d[0])
    _, _, breaks, coeffs, _ = _fir_profile.profile(*args)  # warm (compiled)
    size = lambda *xs: sum(x.size * x.itemsize for x in xs)  # noqa: E731  (what the arrays show, not their buffers)
    bound = size(b0, l0, c0) + size(b1, l1, c1) + 8 / 7 * size(breaks, breaks, coeffs) + 64e3
    # the input pulses keep no empty piece after the first (a gap at full overlap, a head or tail of
    # share 0; none is lengthened by the next one here): the first filter's pieces then nearly
    # fill its buffer of 2 K + 1
    assert np.all((b0[2:] - b0[1:-1]) + (l0[2:] - l0[1:-1]) > 0)
    assert 8 * c1.shape[0] >= 7 * (2 * c0.shape[0] + 1)
    b0 = l0 = c0 = b1 = l1 = c1 = breaks = coeffs = None
    tracemalloc.start()
    try:
        _fir_profile.profile(*args)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert peak <= bound, (peak, bound)


@pytest.mark.parametrize("arcs", [False, True])
def test_empty_input_pieces_change_no_bit_of_the_profile(arcs):
    """``_input_pulses`` leaves out empty pieces (gaps at full overlap, heads and tails of share 0):
    the filters must pass them without trace. Empty pieces with random coefficients inserted at
    random places of a plan's input pulses (a break repeated with its low part) give the same
    position profile, breaks and coefficients bit for bit, through both filters (the first
    averaging, the last integrating: ``_fir_profile.profile``'s order)."""
    from research.interpolators import fir

    rng = np.random.default_rng(5)
    path = random_program(np.random.default_rng(3), arcs=arcs)
    plan = fir.plan_fir(path, 120.0, (0.06, 0.03), 0.05)
    inp = plan.profile
    t = inp.pieces.table
    joins = np.zeros(t.block.size, dtype=bool) if t.joins is None else t.joins
    b0, l0, c0, _ = _fir_profile._input_pulses(t.geo, t.block, t.gap, inp.fraction, inp.piece_tv, inp.gaps, joins)
    at = np.sort(rng.choice(np.arange(1, c0.shape[0] + 1), size=c0.shape[0] // 2))  # before piece at - 1 ends
    b1, l1 = np.insert(b0, at, b0[at]), np.insert(l0, at, l0[at])
    c1 = np.insert(c0, at, rng.normal(size=(at.size,) + c0.shape[1:]), axis=0)
    d = np.array([0.06, 0.03])
    start = np.asarray(inp.start, dtype=np.float64)

    def position(b, lo, c):
        b, lo, c = _fir_profile._moving_average(b, lo, c, d[0])
        return _fir_profile._filter(b, lo, c, d[1], start, True)

    for x, y in zip(position(b0, l0, c0), position(b1, l1, c1)):
        np.testing.assert_array_equal(x, y)
