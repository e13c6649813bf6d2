"""Vertices that do not turn, at tolerance 0 (``G61``, exact path): a line split at a point is the
same motion as the line (LinuxCNC's G61: "If two sequential moves are exactly co-linear movement
will not stop"; here also where the split point is rounded off the line by less than the
verification can see, ``VERIFY_ATOL``).

References: the unsplit program planned by the same planner (the FIR input of a line split at a
point, both halves at full overlap and one feed, is the line's input: one pulse, Sencer 2015 eq 5);
the window sum of ``_fir_feed``'s module docstring evaluated directly (``ChainError.displacement``).
Nothing is compared with the planner's earlier output."""

import numpy as np
import pytest

from research.interpolators import plan_fir
from research.interpolators._fir_feed import ChainError
from research.interpolators._fir_kernels import verified_bound
from research.paths import Polyline
from research.paths.gcode import parse_gcode


def _split_program(rng):
    """A random zigzag of 3-6 lines (0.2-5 mm) and the same path with one line split at a random
    point (computed in floating point: off the line by rounding), and a feed [mm/s]."""
    n = int(rng.integers(3, 7))
    pts = np.vstack([[0.0, 0.0], np.cumsum(np.column_stack([rng.uniform(0.2, 5.0, n), rng.uniform(-3.0, 3.0, n)]),
                                           axis=0)])
    i, u = int(rng.integers(0, n)), rng.uniform(0.05, 0.95)
    split = np.insert(pts, i + 1, pts[i] + u * (pts[i + 1] - pts[i]), axis=0)
    return Polyline(pts), Polyline(split), float(rng.uniform(50.0, 300.0))


@pytest.mark.parametrize("delays", [(0.06, 0.03), (0.05, 0.03, 0.02)])
def test_a_line_split_at_a_point_runs_as_the_line_at_tolerance_zero(delays):
    """Regression (measured: every one of 30 random programs +T_d, up to 30 % slower): the split
    point's rounding kink made it a turning vertex held to 0, and the look-ahead stopped it in
    every candidate. Now the split program's cycle time is the unsplit one's (1e-9 relative, 20
    programs) and every vertex error is within the verification's bound of 0."""
    rng = np.random.default_rng(3)
    for _ in range(20 if len(delays) == 2 else 6):
        whole, split, feed = _split_program(rng)
        a = plan_fir(whole, feed, delays, 0.0)
        b = plan_fir(split, feed, delays, 0.0)
        assert float(b.cycle_time) == pytest.approx(float(a.cycle_time), rel=1e-9)
        assert np.all(np.asarray(b.corner_errors) <= verified_bound(0.0))


def test_g61_program_with_collinear_moves_does_not_stop_between_them():
    """The same through G-code: under ``G61`` a square whose sides are each written as two
    collinear moves takes the time of the square of four moves (its corners stop, eq 13 at
    ``h = 0``; its split points do not)."""
    square = "G21 G90 G61\nG1 X20 Y0 F3000\nG1 X20 Y20\nG1 X0 Y20\nG1 X0 Y0\nM2\n"
    halves = "G21 G90 G61\nG1 X7 Y0 F3000\nG1 X20 Y0\nG1 X20 Y13\nG1 X20 Y20\nG1 X13 Y20\nG1 X0 Y20\nG1 X0 Y6\nG1 X0 Y0\nM2\n"
    times = []
    for text in (square, halves):
        prog = parse_gcode(text)
        times.append(float(plan_fir(prog.blocks, np.asarray(prog.block_feeds), (0.06, 0.03),
                                    np.asarray(prog.block_tolerance)).cycle_time))
    assert times[1] == pytest.approx(times[0], rel=1e-9)
    assert times[0] == pytest.approx(80.0 / 50.0 + 4 * 0.09, rel=1e-9)  # L / F + T_d per stop and at the end


def test_reach_free_feed_is_where_the_window_sum_leaves_zero():
    """``ChainError.reach_free_feed`` on random turn lists with straight (``du = 0``) entries:
    ``|d_j| = 0`` at the feed it returns (direct sum), ``> 0`` just above it (1e-6 relative),
    and 0 at a query on a turning entry."""
    rng = np.random.default_rng(8)
    delays = np.array([0.06, 0.03])
    for _ in range(10):
        s = np.sort(rng.uniform(0.0, 20.0, 12))
        du = rng.normal(size=(12, 2))
        straight = rng.random(12) < 0.4
        du[straight] = 0.0
        chain = ChainError(s, du, delays)
        j = np.flatnonzero(straight)
        if not j.size:
            continue
        q = s[j] - chain.origin
        f = chain.reach_free_feed(q, np.full(j.size, 1e6))
        assert np.all(f > 0)
        np.testing.assert_array_equal(chain(s[j], f), 0.0)
        assert np.all(chain(s[j], f * (1 + 1e-6)) > 0)
        turning = np.flatnonzero(~straight)
        np.testing.assert_array_equal(chain.reach_free_feed(s[turning] - chain.origin, np.full(turning.size, 1e6)), 0.0)


@pytest.mark.parametrize("gaps", [[0.0055], [0.0122, 0.0055], [0.0321, 0.0122, 0.0055]])
def test_split_points_microns_before_an_exact_stop_do_not_stop(gaps):
    """Regression (stress sweep, 2026-12-04): a line split 5.5-32 um before a corner that stops
    (tolerance 0, F 18.74 mm/s). The trajectory passes those points at a crawl into the stop, and
    the corner search's 6 Newton steps ended 0.37 um from one of them: the planner stopped it, then
    its neighbour (+0.09-0.18 s). Now a search above its tolerance goes on until it stops moving:
    the split program runs in the unsplit one's time and passes within the verification's 1 pm of
    every point."""
    A, B, C = np.array([0.3, -0.2]), np.array([6.5, 0.9]), np.array([6.9, 2.4])
    u = (B - A) / np.linalg.norm(B - A)
    whole = plan_fir(Polyline(np.array([A, B, C])), 18.74, (0.06, 0.03), 0.0)
    split = plan_fir(Polyline(np.array([A] + [B - g * u for g in gaps] + [B, C])), 18.74, (0.06, 0.03), 0.0)
    assert float(split.cycle_time) == pytest.approx(float(whole.cycle_time), rel=1e-9)
    assert np.all(np.asarray(split.corner_errors) <= verified_bound(0.0))


def _with_splits(rng, pts, exact: bool):
    """``pts`` with 1-3 points inserted on some segments: on axis-aligned or 45 deg segments at
    decimal fractions (``exact``: the same direction to the last bit) or at random fractions
    (off the line by rounding)."""
    out = [pts[0]]
    for a, b in zip(pts[:-1], pts[1:]):
        for u in np.sort(rng.choice([0.25, 0.5, 0.75] if exact else rng.uniform(0.02, 0.98, 3), int(rng.integers(0, 4)),
                                    replace=False)):
            out.append(a + u * (b - a))
        out.append(b)
    return np.array(out)


def _grid_zigzag(rng, n):
    """``n`` segments of 1-8 mm along the axes and diagonals (exact in binary at quarters)."""
    dirs = np.array([[1, 0], [0, 1], [-1, 0], [0, -1], [1, 1], [1, -1], [-1, 1], [-1, -1]], dtype=float)
    steps = dirs[rng.integers(0, 8, n)] * rng.integers(1, 9, n)[:, None]
    return np.vstack([[0.0, 0.0], np.cumsum(steps, axis=0)])


def test_straight_runs_merge_collinear_lines_of_one_feed_and_tolerance_only():
    """``straight_runs`` on hand-made paths: collinear pieces merge; a turn, a change of feed or
    tolerance, a point 2 pm off the line (above ``VERIFY_ATOL``) or a reversal do not; 0.5 pm off
    does."""
    from research.interpolators._fir_straight import straight_runs
    from research.paths.toolpath import ToolPath

    def runs(points, feeds=None, tol=None):
        tp = ToolPath.from_polyline(Polyline(np.asarray(points, dtype=float)))
        M = tp.n_blocks
        return straight_runs(tp, np.full(M, 100.0) if feeds is None else np.asarray(feeds, float),
                             np.full(M, 0.01) if tol is None else np.asarray(tol, float))

    assert runs([[0, 0], [1, 0], [2, 0], [3, 1]]).tolist() == [0, 0, 1]
    assert runs([[0, 0], [1, 0], [2, 0], [3, 0]]).tolist() == [0, 0, 0]
    assert runs([[0, 0], [1, 0], [2, 1]]) is None
    assert runs([[0, 0], [1, 0], [2, 0]], feeds=[100, 50]) is None
    assert runs([[0, 0], [1, 0], [2, 0]], tol=[0.01, 0.0]) is None
    assert runs([[0, 0], [1, 2e-9], [2, 0]]) is None
    assert runs([[0, 0], [1, 0.5e-9], [2, 0]]).tolist() == [0, 0]
    assert runs([[0, 0], [2, 0], [1, 0]]) is None  # a reversal: the vertex is off the chord


@pytest.mark.parametrize("exact", [True, False])
def test_a_program_with_straight_pieces_plans_as_the_program_without_them(exact):
    """Random axis-and-diagonal zigzags (seeds 0-11) with collinear points inserted, tolerance 0
    or 1-100 um, F 20-300 mm/s, two or three filters: the same cycle time as the program without
    the points (1e-9 relative), every vertex within the verification's bound of its tolerance, and
    the timing of the pieces consistent: each next pulse starts ``T_d - T_k`` after the last ends
    (eq 11), and no piece runs faster on average than its reported feed."""
    for seed in range(12):
        rng = np.random.default_rng(seed)
        pts = _grid_zigzag(rng, int(rng.integers(2, 6)))
        split = _with_splits(rng, pts, exact)
        if len(split) == len(pts):
            continue
        tol = 0.0 if rng.random() < 0.5 else float(np.exp(rng.uniform(np.log(1e-3), np.log(0.1))))
        feed = float(rng.uniform(20.0, 300.0))
        delays = (0.06, 0.03) if rng.random() < 0.6 else (0.05, 0.03, 0.02)
        whole = plan_fir(Polyline(pts), feed, delays, tol)
        plan = plan_fir(Polyline(split), feed, delays, tol)
        assert float(plan.cycle_time) == pytest.approx(float(whole.cycle_time), rel=1e-9), (seed, tol)
        assert np.all(np.asarray(plan.corner_errors) <= verified_bound(tol)), seed
        start, pulse, ov = (np.asarray(x) for x in (plan.start_times, plan.pulse_times, plan.overlaps))
        np.testing.assert_allclose(start[1:] - (start[:-1] + pulse[:-1]), sum(delays) - ov, rtol=0, atol=1e-12)
        lengths = np.linalg.norm(np.diff(split, axis=0), axis=1)
        assert np.all(lengths / pulse <= np.asarray(plan.feeds) * (1 + 1e-9)), seed


def test_under_limits_a_split_line_is_never_slower_than_the_line():
    """Regression (stress sweep, 2026-12-04: 73 programs with split lines under limits slower than
    without the splits, up to 25 %): a 3-D line of 3.3 mm at F 284.9 mm/s split at two thirds,
    then a corner (tolerance 0), under per-axis limits. Each piece was checked alone between exact
    stops, where the 2.2 mm piece doubles its jerk (a pulse shorter than ``T1 + T2``), and both
    pieces were slowed to 24-26 mm/s where the line keeps 36.5. Now the line's plan is a plan of the
    split program too: the same cycle time, and the same feed on both pieces."""
    from research.limits import AxisLimits

    P = np.array([[1293.8305501061616, 94.63045702679835, 204.7837026428307],
                  [1295.3914953652463, 97.32973325217489, 205.80439216625547],
                  [1297.5342806517579, 94.94667267061924, 202.57615694190073]])
    S = np.insert(P, 1, [1294.9317908053577, 96.53478571510855, 205.50379505984307], axis=0)
    lim = AxisLimits.uniform(3, 147.49652921271905, 505.94103410581585, 22066.381616880168)
    whole = plan_fir(Polyline(P), [284.89806036528256, 26.716836686196014], (0.06, 0.03), 0.0, limits=lim)
    split = plan_fir(Polyline(S), [284.89806036528256, 284.89806036528256, 26.716836686196014], (0.06, 0.03), 0.0,
                     limits=lim)
    assert float(split.cycle_time) <= float(whole.cycle_time) * (1 + 1e-9)
    feeds = np.asarray(split.feeds)
    assert feeds[0] == pytest.approx(float(np.asarray(whole.feeds)[0]), rel=1e-9) == feeds[1]


def test_collinear_moves_around_a_dwell_plan_as_the_moves_without_their_split_points():
    """``G61`` with ``G4``: two collinear moves, a dwell, two collinear moves and a corner take the
    time of one move, the dwell, one move and the corner; the pieces' pulses follow each other
    without a gap inside each straight run (full overlap, eq 11), and the trajectory samples."""
    split = "G21 G90 G61\nG1 X10 F3000\nG1 X20\nG4 P0.5\nG1 X30\nG1 X40\nG1 X40 Y10\nM2\n"
    whole = "G21 G90 G61\nG1 X20 F3000\nG4 P0.5\nG1 X40\nG1 X40 Y10\nM2\n"
    plans = []
    for text in (split, whole):
        p = parse_gcode(text)
        plans.append(plan_fir(p.blocks, np.asarray(p.block_feeds), (0.06, 0.03), np.asarray(p.block_tolerance),
                              pauses=p.block_pauses))
    assert float(plans[0].cycle_time) == pytest.approx(float(plans[1].cycle_time), rel=1e-12)
    np.testing.assert_allclose(np.asarray(plans[0].overlaps)[[0, 2]], 0.09, rtol=1e-12)
    start, pulse = np.asarray(plans[0].start_times), np.asarray(plans[0].pulse_times)
    np.testing.assert_allclose(start[[1, 3]], (start + pulse)[[0, 2]], rtol=0, atol=1e-12)
    assert plans[0].trajectory(1e-3).q.shape[0] == int(round(float(plans[0].cycle_time) / 1e-3)) + 1


def test_ramp_pieces_are_steps_the_axes_allow_each_lasting_the_filter_delay():
    """``ramp_pieces`` on a raster of long lines split into pieces (straight runs), under limits
    below the FIR envelope: each run's ends are cut into pieces whose commanded feeds rise by at most
    ``dV = min(A T1, J T1 T2)`` (per axis along the line) from rest to the feed and back, each ramp
    piece ``feed T_d`` long, the program's own vertices kept, and every piece on its block."""
    from research.interpolators._fir_straight import ramp_pieces, straight_runs
    from research.limits import AxisLimits
    from research.paths.toolpath import ToolPath

    pts = [[0.0, 0.0]]
    for row in range(4):
        xs = np.arange(5.0, 105.0, 5.0) if row % 2 == 0 else np.arange(95.0, -5.0, -5.0)
        pts += [[x, float(row)] for x in xs] + [[xs[-1], row + 1.0]]
    tp = ToolPath.from_polyline(Polyline(np.array(pts)))
    M = tp.n_blocks
    feeds, delays = np.full(M, 25.0), np.array([0.06, 0.03])
    lim = AxisLimits.uniform(2, 100.0, 500.0, 5000.0)  # jerk below the envelope's 25 / (T1 T2) = 13,900
    run = straight_runs(tp, feeds, np.full(M, 0.01))
    pieces, block, recipe = ramp_pieces(tp, run, feeds, delays, lim)
    piece_feeds = recipe.of(feeds)
    dV = min(500.0 * 0.06, 5000.0 * 0.06 * 0.03)  # axis-aligned lines: 9 mm/s
    assert np.all(np.diff(block) >= 0) and np.all(piece_feeds <= 25.0 + 1e-12)
    V = np.vstack([tp.start, tp.ends])
    P = np.vstack([pieces.start, pieces.ends])
    for k in range(M):  # every original vertex is a piece vertex, and the pieces lie on their block
        assert np.any(np.all(np.abs(P - V[k + 1]) < 1e-12, axis=1))
        seg, ab = P[1:][block == k] - V[k], V[k + 1] - V[k]
        assert np.allclose(seg[:, 0] * ab[1] - seg[:, 1] * ab[0], 0.0, atol=1e-9)
    same_run = run[block][1:] == run[block][:-1]
    ramp = piece_feeds < 25.0
    assert ramp.any()
    assert np.all(np.abs(np.diff(piece_feeds))[same_run] <= dV * (1 + 1e-12))  # steps along a line
    starts = np.concatenate([[True], ~same_run])  # first piece of each run
    ends = np.concatenate([~same_run, [True]])
    ramped = np.unique(run[block][ramp])
    assert np.all(piece_feeds[starts & np.isin(run[block], ramped)] <= dV * (1 + 1e-12))  # from rest
    assert np.all(piece_feeds[ends & np.isin(run[block], ramped)] <= dV * (1 + 1e-12))  # to rest
    lengths = np.linalg.norm(np.diff(P, axis=0), axis=1)
    assert np.all(lengths[ramp] <= piece_feeds[ramp] * delays.sum() * (1 + 1e-9))


def test_plans_under_limits_below_the_envelope_hold_limits_tolerance_and_timing():
    """Seeded random programs (lines, lines and arcs; two and three filters; tolerance 0 on some)
    under limits at 5-60 % of the FIR envelope's acceleration and jerk, where the plan is the
    fastest of the path as written, merged and cut into ramp pieces: the limits hold on the sampled
    trajectory (``research.metrics.within_limits``), every vertex is within the verification's
    bound of its tolerance, and each pulse starts ``T_d - T_k`` after the previous one ends (eq 11)."""
    from research.limits import AxisLimits
    from research.metrics import within_limits
    from research.paths.library import random_program

    for seed in range(16):
        rng = np.random.default_rng(900 + seed)
        tp = random_program(rng, arcs=seed % 2 == 1)
        feed = float(rng.uniform(20.0, 200.0))
        delays = (0.06, 0.03) if seed % 3 else (0.05, 0.03, 0.02)
        tol = float(rng.choice([0.0, 0.01, 0.1])) if seed % 2 == 0 else float(rng.choice([0.01, 0.1]))
        env = AxisLimits.fir_envelope(tp.dim, feed, delays)
        s = float(rng.uniform(0.05, 0.6))
        lim = AxisLimits(env.velocity, env.acceleration * s, env.jerk * s)
        plan = plan_fir(tp, feed, delays, tol, limits=lim)
        assert within_limits(plan.trajectory(1e-3), lim), seed
        assert np.all(np.asarray(plan.corner_errors) <= verified_bound(tol) + 1e-8), seed
        start, pulse, ov = (np.asarray(x) for x in (plan.start_times, plan.pulse_times, plan.overlaps))
        np.testing.assert_allclose(start[1:] - (start[:-1] + pulse[:-1]), sum(delays) - ov, rtol=0, atol=1e-9)


def _same_timing_and_profile(a, b) -> bool:
    """Two plans with the same pulse starts, pulse lengths, overlaps and profile coefficients, bit for bit."""
    return all(np.array_equal(np.asarray(x), np.asarray(y)) for x, y in (
        (a.start_times, b.start_times), (a.pulse_times, b.pulse_times), (a.overlaps, b.overlaps),
        (a.position.coeffs, b.position.coeffs)))


def test_a_path_planned_again_with_other_feeds_and_tolerances_plans_as_a_path_read_anew():
    """A path keeps its analysis between plans (``_fir_straight``'s collinear vertices, the runs
    and merged path of its last plan, its tangents and padded block arrays): random zigzags with
    collinear points (seeds 0-7), each planned on one path object under a sequence of feeds and
    tolerances that split and re-join its runs (uniform, per block from two values, back to
    uniform), give at every step the runs and the plan of a new object of the same points: the
    same run labels and the same timing, bit for bit."""
    from research.interpolators._fir_straight import straight_runs
    from research.interpolators.fir import _as_toolpath
    from research.paths.toolpath import ToolPath

    for seed in range(8):
        rng = np.random.default_rng(100 + seed)
        pts = _with_splits(rng, _grid_zigzag(rng, int(rng.integers(3, 7))), True)
        kept = Polyline(pts)
        M = len(pts) - 1
        steps = [(np.full(M, 100.0), np.full(M, 0.01)),
                 (rng.choice([80.0, 100.0], M), np.full(M, 0.01)),
                 (np.full(M, 100.0), rng.choice([0.0, 0.01], M)),
                 (np.full(M, 100.0), np.full(M, 0.01))]
        for feeds, tol in steps:
            again = straight_runs(_as_toolpath(kept), feeds, tol)  # the path object plan_fir keeps
            anew = straight_runs(ToolPath.from_polyline(Polyline(pts.copy())), feeds, tol)
            assert (again is None) == (anew is None) and (anew is None or again.tolist() == anew.tolist()), seed
            a = plan_fir(kept, feeds, (0.06, 0.03), tol, refine=False)
            b = plan_fir(Polyline(pts.copy()), feeds, (0.06, 0.03), tol, refine=False)
            assert _same_timing_and_profile(a, b), seed


def test_a_paths_tangents_are_copies():
    """``ToolPath.tangents`` is made once per path and handed out as copies: writing into what it
    returned leaves the next call's values (those of a path read anew) unchanged."""
    from research.paths.toolpath import ToolPath

    pts = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 2.0], [3.0, 3.0]])
    tp = ToolPath.from_polyline(Polyline(pts))
    t_in, t_out = tp.tangents()
    t_in[:] = np.nan
    t_out[:] = np.nan
    ref = ToolPath.from_polyline(Polyline(pts.copy())).tangents()
    for x, y in zip(tp.tangents(), ref):
        assert np.array_equal(x, y)


def test_a_path_with_arcs_planned_again_plans_as_a_path_read_anew():
    """Lines and arcs (G1 - G3 - G1 - G2 - G1, two split lines), planned on one path object
    without refinement, with it (the verification cuts the sub-arcs: a table of its own, not the
    path's kept one), and without again: each plan's timing and profile those of the same program
    read anew, bit for bit."""
    program = ("G21 G90 G17 G64 P0.01\nG1 X20 Y0 F6000\nG1 X40 Y0\nG3 X40 Y40 I0 J20\nG1 X20 Y40\nG1 X0 Y40\n"
               "G2 X-20 Y20 I0 J-20\nG1 X-20 Y0\nM2\n")
    kept = parse_gcode(program).blocks
    for refine in (False, True, False):
        a = plan_fir(kept, 100.0, (0.06, 0.03), 0.01, refine=refine)
        b = plan_fir(parse_gcode(program).blocks, 100.0, (0.06, 0.03), 0.01, refine=refine)
        assert _same_timing_and_profile(a, b), refine
