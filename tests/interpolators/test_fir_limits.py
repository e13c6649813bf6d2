"""Limit-holding FIR (``plan_fir(..., limits=...)``, ``_fir_limits``): post-hoc repair on exact peaks.

Expected values come from independent computations: the sampled-and-refined peaks of
``research.metrics`` (not the planner's exact roots), closed-form ratio functions for the
bisections, and the plain plan itself for "nothing to repair"."""

import numpy as np
import pytest

from research.errors import ConvergenceError
from research.interpolators import plan_fir
from research.interpolators._fir_limits import (
    BISECTION_STEPS,
    CornerBisection,
    blocks_in_windows,
    hold_block_limits,
)
from research.limits import AxisLimits
from research.metrics import corner_errors, limit_ratios, peak_axis_values
from research.paths import Polyline, named_path

from ._paths import turning_path

PAPER_DELAYS = (0.148, 0.089)


def random_path(seed: int, n: int = 6) -> Polyline:
    """Seeded 2-D path of ``n`` segments of 3-30 mm turning by up to +-120 deg."""
    return turning_path(seed, n, (3.0, 30.0), 120.0)


def test_never_slower_than_plain_where_plain_holds_zigzag():
    """Issue 19: on the zigzag the plain FIR keeps the nominal envelope (worst ratio 0.894 by the
    sampled check), and the limit-holding plan capped every block to 0.30 F up front (2.345 s
    against 1.807 s). Now it returns the plain plan."""
    path = named_path("zigzag")
    limits = AxisLimits.fir_envelope(2, 250.0, PAPER_DELAYS)
    plain = plan_fir(path, 250.0, PAPER_DELAYS, 0.5)
    assert max(float(np.max(r)) for r in limit_ratios(plain.trajectory(1e-3), limits).values()) <= 1.0
    held = plan_fir(path, 250.0, PAPER_DELAYS, 0.5, limits=limits)
    assert float(held.cycle_time) <= float(plain.cycle_time) * (1 + 1e-12)
    np.testing.assert_allclose(np.asarray(held.overlaps), np.asarray(plain.overlaps), rtol=1e-12)


@pytest.mark.parametrize("points,factor,expected", [
    ([[0.0, 0.0], [10.0, 0.0]], 1.0, True),  # start and stop: F / T1 and F / (T1 T2), at the envelope
    ([[0.0, 0.0], [10.0, 0.0]], 0.99, False),  # the same ramps, 1 % above
    ([[0.0, 0.0], [10.0, 0.0], [10.0, 10.0]], 1.0, True),  # 90 deg: |dV_x| = |dV_y| = F
    ([[0.0, 0.0], [10.0, 0.0], [0.0, 0.0]], 1.0, False),  # reversal: |dV_x| = 2 F
    ([[0.0, 0.0], [10.0, 0.0], [0.0, 0.0]], 2.0, True),
])
def test_steps_within_limits_closed_form(points, factor, expected):
    """Each velocity step alone through the FIR chain peaks at ``|dV_i| / T1`` and ``|dV_i| / (T1 T2)``
    (Sencer 2015 §2.1: "the acceleration and jerk of a step are F / T1 and F / (T1 T2)"): against
    acceleration and jerk limits ``factor`` times the envelope ``F / T1``, ``F / (T1 T2)`` at F = 200."""
    from research.interpolators._fir_limits import steps_within_limits
    from research.paths.toolpath import ToolPath

    tp = ToolPath.from_polyline(Polyline(points))
    env = AxisLimits.fir_envelope(2, 200.0, (0.06, 0.03))
    limits = AxisLimits(env.velocity, factor * env.acceleration, factor * env.jerk)
    assert steps_within_limits(tp, np.full(tp.n_blocks, 200.0), *tp.tangents(), np.array([0.06, 0.03]), limits) is expected


def test_plain_plan_returned_where_it_holds_the_limits_though_a_step_alone_would_not():
    """The first eight blocks of an arc-fitted CAM pass (``benchmarks/arc_programs.py``: G2/G3 of
    R 7-110 mm with small kinks, 4 decimals) at F 200 mm/s, T 60/30 ms, eps 50 um, under the FIR
    envelope: an arc of R >= 20 mm starting from rest at F would break the envelope (its
    centripetal acceleration on top of the ramp), so the step prediction fails, but in the chain no
    arc starts from rest and the plan without limits keeps them (sampled and refined peaks here).
    The limit-holding planner repaired it all the same (0.4167 s against 0.4003 s); the plan
    without limits is now made where the prediction fails and returned where it holds them and is
    faster: never slower than the plain plan where that holds the limits."""
    from research.paths.gcode import parse_gcode

    prog = parse_gcode("G21 G90 G17 G94\nG1 X29.9364 Y0.0000 Z0.0000 F12000.0\n"
                       "G3 X29.5571 Y2.7378 I-7.4568 J0.3621\nG3 X28.4753 Y5.0455 I-10.6005 J-3.5619\n"
                       "G3 X27.5045 Y6.5028 I-17.1298 J-10.3592\nG3 X26.0931 Y8.3917 I-88.4754 J-64.6377\n"
                       "G2 X24.7025 Y10.4391 I17.8985 J13.6527\nG2 X23.4303 Y13.1839 I13.2391 J7.8035\n"
                       "G2 X22.9831 Y14.5455 I29.2202 J10.3513\nG3 X22.0426 Y17.5553 I-77.4033 J-22.5351\nM2\n",
                       start=(29.9364, 0.0, 0.0))
    tp = prog.blocks
    env = AxisLimits.fir_envelope(3, 200.0, (0.06, 0.03))
    plain = plan_fir(tp, 200.0, (0.06, 0.03), 0.05)
    assert all(np.all(r <= 1 + 1e-6) for r in limit_ratios(plain.trajectory(1e-3), env).values())
    held = plan_fir(tp, 200.0, (0.06, 0.03), 0.05, limits=env)
    assert float(held.cycle_time) <= float(plain.cycle_time) * (1 + 1e-12)
    assert all(np.all(r <= 1 + 1e-6) for r in limit_ratios(held.trajectory(1e-3), env).values())


def test_a_plan_a_little_above_the_limits_is_scaled_not_repaired():
    """Four tangent arcs of R 300 mm (0.03 rad each, alternating) between two 5 mm lines at F 200
    mm/s, T 60/30 ms, eps 50 um, under the FIR envelope: the plan without limits breaks it by
    0.04 % (its start from rest on a 25 ms line, sampled and refined here), and the repairs took
    the end lines to 100 mm/s: 0.4635 s against 0.3200 s. The same plan at its feeds over that
    ratio keeps the limits; the result keeps them and is within 0.1 % of the plan without limits."""
    from research.paths.toolpath import ToolPath

    tp = ToolPath.from_polyline(Polyline([[-5.0, 0.0], [0.0, 0.0]]))
    heading = 0.0
    for k in range(4):
        sense = 1.0 if k % 2 else -1.0
        centre = tp.ends[-1] + 300.0 * sense * np.array([-np.sin(heading), np.cos(heading)])
        heading += sense * 0.03
        tp = tp.then_arc(centre - 300.0 * sense * np.array([-np.sin(heading), np.cos(heading)]), centre, ccw=sense > 0)
    end = tp.ends[-1] + 5.0 * np.array([np.cos(heading), np.sin(heading)])
    tp = ToolPath(tp.start, np.vstack([tp.ends, end]), np.vstack([tp.centers, [[np.nan, np.nan]]]),
                  np.vstack([tp.normals, [[np.nan] * 3]]), np.concatenate([tp.sweeps, [0.0]]))
    env = AxisLimits.fir_envelope(2, 200.0, (0.06, 0.03))
    plain = plan_fir(tp, 200.0, (0.06, 0.03), 0.05)
    worst = max(float(np.max(r)) for r in limit_ratios(plain.trajectory(1e-3), env).values())
    assert 1.0 + 1e-5 < worst < 1.001
    held = plan_fir(tp, 200.0, (0.06, 0.03), 0.05, limits=env)
    assert all(np.all(r <= 1 + 1e-6) for r in limit_ratios(held.trajectory(1e-3), env).values())
    assert float(held.cycle_time) <= 1.001 * float(plain.cycle_time)


def test_plain_plan_returned_where_it_holds_the_limits():
    """Where every velocity step alone keeps the limits and the plan without limits keeps them
    (sampled check here), the limit-holding call returns that very plan: a circle of 1 deg chords
    (R 40 mm, F 200 mm/s, T 60/30 ms) under its FIR envelope. Where the steps alone keep them but
    two of them add (a U-turn of two right angles 5 ms apart: ``|dV_x| = F`` each, 2.0x the
    acceleration limit in the plain plan), the limits are repaired as before."""
    th = np.radians(np.arange(0.0, 360.0 + 1e-9, 1.0))
    circle = Polyline(40.0 * np.column_stack([np.cos(th), np.sin(th)]))
    env = AxisLimits.fir_envelope(2, 200.0, (0.06, 0.03))
    plain = plan_fir(circle, 200.0, (0.06, 0.03), 0.05)
    assert max(float(np.max(r)) for r in limit_ratios(plain.trajectory(1e-3), env).values()) <= 1.0
    held = plan_fir(circle, 200.0, (0.06, 0.03), 0.05, limits=env)
    for a, b in ((held.feeds, plain.feeds), (held.overlaps, plain.overlaps), (held.start_times, plain.start_times)):
        np.testing.assert_array_equal(np.asarray(a), np.asarray(b))
    u_turn = Polyline([[0.0, 0.0], [10.0, 0.0], [10.0, 1.0], [0.0, 1.0]])
    plain = plan_fir(u_turn, 200.0, (0.06, 0.03), 0.5)
    assert max(float(np.max(r)) for r in limit_ratios(plain.trajectory(1e-3), env).values()) > 1.9
    held = plan_fir(u_turn, 200.0, (0.06, 0.03), 0.5, limits=env)
    assert all(np.all(r <= 1 + 1e-6) for r in limit_ratios(held.trajectory(1e-3), env).values())


@pytest.mark.parametrize("seed", [0, 1])
def test_own_peaks_as_limits_change_nothing(seed):
    """Limits equal to the plain plan's own peaks (measured by sampling) are held by it, so the
    limit-holding plan is never slower (20/10 ms: short blocks peak lower inside the motion than
    alone, which an up-front cap ignored: cam30 0.834 s against 0.499 s)."""
    path = random_path(seed, 8)
    plain = plan_fir(path, 250.0, (0.02, 0.01), 0.5)
    limits = AxisLimits(*(peak_axis_values(plain.trajectory(1e-3), nu) for nu in (1, 2, 3)))
    held = plan_fir(path, 250.0, (0.02, 0.01), 0.5, limits=limits)
    assert float(held.cycle_time) <= float(plain.cycle_time) * (1 + 1e-12)


@pytest.mark.parametrize("seed", [2, 3, 4])
def test_random_tight_limits_are_held_with_the_tolerance(seed):
    """Limits below the FIR envelope on some axes (velocity under F, acceleration and jerk under
    the nominal ones): every peak within its limit (sampled check, 1e-6) and every corner within eps."""
    rng = np.random.default_rng(seed)
    path = random_path(seed)
    F, eps = 250.0, 0.2
    limits = AxisLimits(rng.uniform(0.5, 1.2, 2) * F, rng.uniform(0.5, 1.2, 2) * F / PAPER_DELAYS[0],
                        rng.uniform(0.5, 1.2, 2) * F / (PAPER_DELAYS[0] * PAPER_DELAYS[1]))
    plan = plan_fir(path, F, PAPER_DELAYS, eps, limits=limits)
    tr = plan.trajectory(1e-3)
    assert all(np.all(r <= 1 + 1e-6) for r in limit_ratios(tr, limits).values())
    assert np.max(corner_errors(tr, path)) <= eps * (1 + 1e-6)


def test_corner_bisection_converges_from_below():
    """A ratio that exceeds the limit above a multiplier s* (here 1 + (s - s*)): the bisection ends
    within 2^-BISECTION_STEPS of s*, on the safe side, after BISECTION_STEPS + 1 rounds."""
    s_star = np.array([0.3, 0.77, 0.999])
    bis = CornerBisection(3)
    rounds = 0
    while bis.update(1.0 + (bis.scale - s_star)):
        rounds += 1
        assert rounds <= BISECTION_STEPS + 2
    assert rounds == BISECTION_STEPS + 1
    assert np.all(bis.scale <= s_star) and np.all(s_star - bis.scale <= 2.0**-BISECTION_STEPS)


def test_corner_bisection_bound_never_below_the_final_multiplier():
    """``bound_scale`` bounds the planner's branch and bound: in every round it must be at least
    the multiplier the bisection ends at (the current ``scale``, a bracket midpoint, is not: it
    falls below s* and rises again) and must never rise. Same closed-form ratio as above, plus a
    corner that never breaks its limit (bound 1 throughout)."""
    s_star = np.array([0.3, 0.77, 0.999, 2.0])
    bis = CornerBisection(4)
    bounds, scales = [bis.bound_scale.copy()], [bis.scale.copy()]
    while bis.update(1.0 + (bis.scale - s_star)):
        bounds.append(bis.bound_scale.copy())
        scales.append(bis.scale.copy())
    bounds, scales = np.array(bounds), np.array(scales)
    assert np.all(bounds >= bis.scale[None, :])
    assert np.all(np.diff(bounds, axis=0) <= 0.0)
    assert np.any(scales < bis.scale[None, :])  # the midpoint alone would not bound the final plan
    assert np.all(bounds[:, 3] == 1.0)


def test_corner_bisection_goes_to_exact_stop_and_reports_a_stuck_corner():
    """A corner above the limit at every overlap > 0 (the diamond's continuing axis doubles its
    jerk for any T_k < 2 T_2) ends as an exact stop; above it even then, ConvergenceError."""
    bis = CornerBisection(1)
    while bis.update(np.where(bis.scale > 0, 1.41, 0.7)):
        pass
    assert bis.scale[0] == 0.0
    with pytest.raises(ConvergenceError, match="as exact stops"):
        bis.update(np.array([1.2]))


def test_block_feed_bisection():
    """Blocks alone whose ratio is r0 * g at feed multiplier g: the checked ones end at the largest
    safe g within 2^-10 (lower bracket 0.5 / r0 given as 'safe'), the others keep 1."""
    r0 = np.array([2.0, 1.25, 3.0, 0.8])
    which = np.array([True, True, False, True])
    asked = []

    def alone(g, blocks, decisions):
        asked.append(blocks.copy())
        return np.where(blocks, r0 * g, 0.0)

    g = hold_block_limits(alone, 0.5 / r0, which)
    assert g[2] == 1.0 and g[3] == 1.0
    # ``which`` first, then only the blocks being bisected (0 and 1)
    np.testing.assert_array_equal(asked[0], which)
    assert all(np.array_equal(b, [True, True, False, False]) for b in asked[1:])
    assert np.all(r0[:2] * g[:2] <= 1.0) and np.all(1.0 / r0[:2] - g[:2] <= 2.0**-10)


def _bisection(ratio_of, lo):
    """The multipliers of BISECTION_STEPS plain bisections of ``[lo, 1]`` per block (the search
    ``hold_block_limits`` ran before the secant-guided one): the last midpoint found within
    ``1 + 1e-9``, else ``lo``."""
    lo, hi = lo.copy(), np.ones(lo.size)
    for _ in range(BISECTION_STEPS):
        mid = 0.5 * (lo + hi)
        ok = ratio_of(mid) <= 1.0 + 1e-9
        lo, hi = np.where(ok, mid, lo), np.where(ok, hi, mid)
    return lo


def test_largest_safe_is_the_bisections_multiplier_in_fewer_builds():
    """Seeded blocks whose ratio grows with the feed multiplier g as a power law ``c g^p`` (p 1,
    the jerk of a pulse longer than T_2, Sencer 2015 §2.1; 0.5-3 otherwise) or a floor then a power
    law (a short pulse's acceleration does not fall with its feed): ``_largest_safe`` returns, bit
    for bit, what ten plain bisections of ``[lo, 1]`` return (an independent loop), in two builds
    where p = 1, and never in more than SECANT_STEPS + BISECTION_STEPS."""
    from research.interpolators._fir_limits import SECANT_STEPS, _largest_safe

    rng = np.random.default_rng(7)
    n = 400
    p = np.where(rng.random(n) < 0.5, 1.0, rng.uniform(0.5, 3.0, n))
    c = rng.uniform(1.01, 8.0, n)
    floor = np.where(rng.random(n) < 0.3, rng.uniform(0.2, 0.99, n), 0.0)
    lo = np.where(rng.random(n) < 0.5, rng.uniform(0.05, 0.9, n) * c ** (-1.0 / p), 1.0 / c)
    bad = rng.random(n) < 0.9

    def ratio_of(g):
        return np.maximum(c * g**p, floor)

    builds = []

    def alone(g, blocks, decisions):
        assert decisions  # the search reads comparisons only
        builds.append(blocks.copy())
        assert np.all(g[~blocks] == 1.0)
        return np.where(blocks, ratio_of(g), 0.0)

    got = _largest_safe(alone, bad, lo.copy(), ratio_of(np.ones(n)))
    np.testing.assert_array_equal(got[bad], _bisection(ratio_of, lo)[bad])
    np.testing.assert_array_equal(got[~bad], lo[~bad])
    counts = np.sum(builds, axis=0)
    assert counts.max() <= SECANT_STEPS + BISECTION_STEPS
    assert np.all(counts[bad & (p == 1.0)] <= 2)
    assert counts[bad].mean() < 0.5 * BISECTION_STEPS


def test_largest_safe_where_the_ratio_falls_somewhere():
    """Blocks whose ratio dips below the limit again at higher feeds (a pulse whose pieces' lengths
    meet the delays): the multiplier returned is within the limits and the next point of the
    bisection's grid above it is not (a local largest, as the bisection's own result is)."""
    from research.interpolators._fir_limits import _largest_safe

    rng = np.random.default_rng(11)
    n = 300
    c = rng.uniform(1.5, 4.0, n)
    dip_at, dip_w = rng.uniform(0.4, 0.8, n), rng.uniform(0.01, 0.08, n)  # ratio(1) > 1.49: above the limit
    lo = 0.5 / c

    def ratio_of(g):
        return c * g * (1.0 - 0.8 * np.exp(-(((g - dip_at) / dip_w) ** 2)))

    got = _largest_safe(lambda g, b, decisions: np.where(b, ratio_of(g), 0.0), np.ones(n, dtype=bool), lo.copy(),
                        ratio_of(np.ones(n)))
    assert np.all(ratio_of(got) <= 1.0 + 1e-9)
    step = (1.0 - lo) * 2.0**-BISECTION_STEPS
    nxt = got + step
    assert np.all((ratio_of(nxt) > 1.0 + 1e-9) | (nxt > 1.0 - 0.5 * step))


def test_blocks_in_windows():
    """Blocks 0..3 of 1 s pulses with 0.5 s windows, starting every 1.2 s (T_d = 0.5 s): corner 1's
    window [2.2, 2.9] meets the spans of blocks 1 [1.2, 2.7] and 2 [2.4, 3.9] only."""
    starts = np.array([0.0, 1.2, 2.4, 3.6])
    flags = np.array([False, True, False])
    np.testing.assert_array_equal(blocks_in_windows(flags, starts, np.ones(4), 0.5), [False, True, True, False])


def test_block_own_span_is_held_regression():
    """Three blocks shorter than F T_d under the FIR envelope (F 200 mm/s, 60/30 ms, eps 0.1 mm): the
    look-ahead slows the middle block in pieces, and inside its own span, ``[start + T_d, end]``, which
    no corner window covers, the y jerk reached 1.71x the limit while both corner windows held (0.88,
    0.98). The limits are checked here on the sampled trajectory (``metrics.limit_ratios``, independent
    of the planner's exact peaks), and the own-span peaks the planner now checks match it."""
    from research.interpolators._fir_limits import own_span_ratios
    from research.interpolators._fir_piece_peaks import PiecePeaks
    from research.piecewise import NumpyPiecewise

    path = Polyline([[0.0, 0.0], [3.3178550046703728, 3.029993981949344],
                     [-0.5165014642632135, 12.576291872869268], [0.6828367036815275, 18.055260773669232]])
    delays = np.array([0.06, 0.03])
    limits = AxisLimits.fir_envelope(2, 200.0, delays)
    plan = plan_fir(path, 200.0, delays, 0.1, limits=limits)
    ratios = limit_ratios(plan.trajectory(1e-4), limits)
    assert all(np.all(r <= 1 + 1e-6) for r in ratios.values()), ratios
    pos = NumpyPiecewise(np.asarray(plan.position.breaks), np.asarray(plan.position.coeffs))
    own = own_span_ratios(PiecePeaks(pos, limits), np.asarray(plan.start_times), np.asarray(plan.pulse_times),
                          float(np.sum(delays)))
    assert np.all(own <= 1 + 1e-9)
    assert np.max(np.asarray(plan.corner_errors)) <= 0.1 * (1 + 1e-6)


@pytest.mark.parametrize("degree", [3, 5, 8])
def test_piece_peaks_match_per_piece_polynomial_roots(degree):
    """``PiecePeaks`` (each axis at its own roots of the next derivative) against an independent
    computation piece by piece and axis by axis with ``numpy.polynomial.Polynomial`` (the extrema
    of each derivative at the piece's ends and at the real roots of the next one in ``[0, h]``),
    on seeded random profiles of three axes; and its windows against the largest piece they meet."""
    from numpy.polynomial import Polynomial

    from research.interpolators._fir_piece_peaks import PiecePeaks
    from research.piecewise import NumpyPiecewise

    rng = np.random.default_rng(degree)
    K, A = 40, 3
    h = rng.uniform(0.005, 0.05, K)
    h[7] = 1e-14  # a degenerate piece: not counted
    breaks = np.concatenate([[0.0], np.cumsum(h)])
    coeffs = rng.normal(size=(K, degree + 1, A)) * (10.0 ** rng.uniform(-1, 4, (K, 1, A)))
    limits = AxisLimits(velocity=np.array([50.0, 80.0, 30.0]), acceleration=np.array([2e3, 5e3, 1e3]),
                        jerk=np.array([1e5, 3e5, 5e4]))
    peaks = PiecePeaks(NumpyPiecewise(breaks, coeffs), limits)
    lim = [limits.velocity, limits.acceleration, limits.jerk]
    want = np.zeros(K)
    for k in range(K):
        if h[k] <= 1e-12:
            continue
        for a in range(A):
            p = Polynomial(coeffs[k, :, a])
            for order in (1, 2, 3):
                d = p.deriv(order)
                r = d.deriv().roots() if d.degree() > 0 else np.zeros(0)
                r = r[(np.abs(r.imag) <= 1e-9 * np.maximum(1.0, np.abs(r.real)))].real
                t = np.concatenate([[0.0, h[k]], r[(r >= 0) & (r <= h[k])]])
                want[k] = max(want[k], np.max(np.abs(d(t))) / lim[order - 1][a])
    np.testing.assert_allclose(peaks.per_piece, want, rtol=1e-9)
    assert peaks.per_piece[7] == 0.0
    lo = rng.uniform(0.0, breaks[-1], 30)
    hi = lo + rng.uniform(0.0, 0.2, 30)
    first = np.searchsorted(breaks, lo, side="right") - 1
    last = np.maximum(np.searchsorted(breaks, hi, side="left"), first + 1)
    np.testing.assert_array_equal(peaks.over(lo, hi), [np.max(peaks.per_piece[a:b]) for a, b in zip(first, last)])


@pytest.mark.parametrize("degree", [4, 5, 7, 8])
def test_window_maxima_equal_the_largest_exact_piece_ratio(degree):
    """``PiecePeaks.over`` above cubic degree seeks roots only in the pieces whose bound
    ``sum |c_m| h^m / limit`` exceeds the largest end value in the window
    (``_fir_piece_peaks.window_maxima``); the result must be, bit for bit, the largest exact ratio
    of the pieces each window meets (every piece's ratio computed, ``piece_ratios_at``), on seeded
    random profiles with zero coefficients, a jerk limit of inf, a degenerate piece, and windows
    from one piece to the whole profile, overlapping and in any order."""
    from research.interpolators._fir_piece_peaks import PiecePeaks, piece_ratios_at, window_interiors
    from research.piecewise import NumpyPiecewise

    rng = np.random.default_rng(80 + degree)
    K, A = 400, 3
    h = rng.uniform(1e-4, 0.02, K)
    h[11] = 1e-14
    breaks = np.concatenate([[0.0], np.cumsum(h)])
    coeffs = rng.normal(size=(K, degree + 1, A)) * (10.0 ** rng.uniform(-2, 4, (K, 1, A)))
    coeffs[rng.random((K, degree + 1, A)) < 0.2] = 0.0
    limits = AxisLimits(velocity=np.array([50.0, 80.0, 30.0]), acceleration=np.array([2e3, 5e3, 1e3]),
                        jerk=np.array([1e5, np.inf, 5e4]))
    limit = np.stack([limits.velocity, limits.acceleration, limits.jerk])
    h = np.diff(breaks)  # the piece lengths PiecePeaks reads
    exact = np.where(h > 1e-12, piece_ratios_at(coeffs, h, limit, np.arange(K)), 0.0)
    lo = np.concatenate([rng.uniform(0.0, breaks[-1], 60), [0.0, breaks[5]]])
    hi = np.concatenate([lo[:60] + rng.uniform(0.0, 0.3, 60) ** 2, [breaks[-1], breaks[5] + 1e-6]])
    got = PiecePeaks(NumpyPiecewise(breaks, coeffs), limits).over(lo, hi)  # lazy: no per_piece read before
    lo_i, hi_i = window_interiors(lo, hi)
    first = np.clip(np.searchsorted(breaks, lo_i, side="right") - 1, 0, K - 1)
    last = np.clip(np.searchsorted(breaks, hi_i, side="left"), first + 1, K)
    np.testing.assert_array_equal(got, [np.max(exact[a:b]) for a, b in zip(first, last)])


@pytest.mark.parametrize("degree", [1, 2, 3, 4, 5, 6, 8])
def test_compiled_piece_peaks_equal_the_numpy_form(degree):
    """The compiled pass of ``PiecePeaks`` against its whole-array NumPy form
    (``_peaks_reference.piece_ratios``): bit for bit to degree 4 (closed-form roots); above (pieces
    of arcs under filters), to 1e-12, since the reference takes the roots of the next derivative
    from companion-matrix eigenvalues and the compiled pass isolates them by the derivatives'
    roots. Random pieces with zero leading coefficients (roots of lower degree), zero
    derivatives, roots outside the piece and a jerk limit of inf."""
    from research.interpolators._fir_piece_peaks import piece_ratios_at

    from ._peaks_reference import piece_ratios

    rng = np.random.default_rng(40 + degree)
    K, A = 300, 3
    h = rng.uniform(1e-4, 0.05, K)
    coeffs = rng.normal(size=(K, degree + 1, A)) * (10.0 ** rng.uniform(-2, 4, (K, 1, A)))
    zero = rng.random((K, degree + 1, A)) < 0.2
    coeffs[zero] = 0.0
    limit = np.array([[50.0, 80.0, 30.0], [2e3, 5e3, 1e3], [1e5, np.inf, 5e4]])
    got, want = piece_ratios_at(coeffs, h, limit, np.arange(K)), piece_ratios(coeffs, h, limit)
    if degree <= 4:
        np.testing.assert_array_equal(got, want)
    else:
        np.testing.assert_allclose(got, want, rtol=1e-12)


@pytest.mark.parametrize("delays", [(0.06, 0.03), (0.05, 0.03, 0.01)])
def test_alone_block_ratios_match_the_whole_exact_stop_profile(delays):
    """Phase 1's local profile (only the blocks asked for) against an independent whole-path
    computation: the JAX build of the whole path with every corner an exact stop, each block's
    peaks over its span ``[start, end + T_d]`` (ended at the next block's start). Seeded random
    programs of lines and arcs, random head / tail shares, feed factors, sub-arc factors and
    multipliers ``g``, random block subsets: equal up to rounding; and asked for every block, the
    arrays of the whole path's exact-stop profile on the planner's NumPy build, bit for bit."""
    import jax.numpy as jnp

    from research.interpolators import _fir_profile
    from research.interpolators._fir_blocks import build_profile
    from research.interpolators._fir_limits import alone_block_ratios, block_peak_ratios
    from research.interpolators._fir_piece_peaks import PiecePeaks, corner_peak_ratios
    from research.interpolators._fir_settle import _pulse_table
    from research.paths.library import random_program
    from research.piecewise import NumpyPiecewise

    d = np.array(delays)
    Td = float(np.sum(d))
    for seed in range(12):
        rng = np.random.default_rng(300 + seed)
        tp = random_program(rng, arcs=bool(seed % 2))
        table, M = _pulse_table(tp), tp.n_blocks
        Mp = table.m_pad
        F = rng.uniform(20.0, 300.0, M)
        head, tail = rng.uniform(0.0, 0.4, M), rng.uniform(0.0, 0.4, M)
        factor = rng.uniform(0.3, 1.0, (M, 3)) * rng.uniform(0.2, 1.0, M)[:, None]  # a multiplier g folded in
        arc_rel = rng.uniform(0.5, 1.0, table.arc_pieces.size) if table.arc_pieces.size else None
        frac, piece_factor = table.pieces(head, tail, factor, arc_rel)
        lengths = np.concatenate([tp.lengths, np.ones(Mp - M + 1)])
        feeds = np.concatenate([F, np.ones(Mp - M + 1)])
        limits = AxisLimits.uniform(tp.dim, 100.0, 2e3, 6e4)
        piece_tv = lengths[table.block] / (feeds[table.block] * piece_factor)
        gaps = np.concatenate([np.full(M - 1, Td), np.zeros(Mp - M + 1)])
        starts, ends, position, _ = build_profile(jnp.asarray(tp.start), table.geo, table.block, table.gap, frac,
                                                  piece_tv, gaps, d)
        s, e = np.asarray(starts)[:M], np.asarray(ends)[:M]
        want = corner_peak_ratios(position, s, np.minimum(e + Td, np.append(s[1:], np.inf)), limits)
        for blocks in (rng.random(M) < 0.4, np.eye(M, dtype=bool)[M - 1], np.ones(M, dtype=bool)):
            got = alone_block_ratios(table, blocks, frac, piece_factor, lengths, feeds, tp.start, d, limits, prove=False)
            np.testing.assert_allclose(got[blocks], want[blocks], rtol=1e-11)
            assert np.all(got[~blocks] == 0.0)
        s2, e2, breaks, coeffs, _ = _fir_profile.profile(tp.start, table.geo, table.block, table.gap, frac, piece_tv,
                                                         gaps, d)
        whole = block_peak_ratios(PiecePeaks(NumpyPiecewise(breaks, coeffs), limits), s2[:M], e2[:M] - s2[:M], Td)
        np.testing.assert_array_equal(got, whole)


def _alone_inputs(tp, rng, feed, head=None, tail=None, factor=None):
    """The phase-1 inputs of ``alone_block_ratios`` for a program at feeds ``feed`` (random shares
    and factors unless given)."""
    from research.interpolators._fir_settle import _pulse_table

    table, M = _pulse_table(tp), tp.n_blocks
    Mp = table.m_pad
    head = rng.uniform(0.0, 0.4, M) if head is None else head
    tail = rng.uniform(0.0, 0.4, M) if tail is None else tail
    factor = rng.uniform(0.2, 1.0, (M, 3)) if factor is None else factor
    arc_rel = rng.uniform(0.5, 1.0, table.arc_pieces.size) if table.arc_pieces.size else None
    frac, piece_factor = table.pieces(head, tail, factor, arc_rel)
    lengths = np.concatenate([tp.lengths, np.ones(Mp - M + 1)])
    feeds = np.concatenate([np.broadcast_to(feed, (M,)), np.ones(Mp - M + 1)])
    return table, frac, piece_factor, lengths, feeds


@pytest.mark.parametrize("delays", [(0.06, 0.03), (0.05, 0.03, 0.01), (0.04, 0.04), (0.05,)])
def test_alone_bound_holds_on_random_staircases(delays):
    """``_fir_alone_bound.alone_bounds`` against the exact peaks of each block alone (the
    exact-stop profile, itself checked against the JAX build above): never below them, on seeded
    random programs with random head / tail shares and feed factors (level staircases of every
    order, zero-length heads and tails included); arcs get no bound."""
    from research.interpolators._fir_alone_bound import alone_bounds
    from research.interpolators._fir_limits import alone_block_ratios
    from research.paths.library import random_program

    d = np.array(delays)
    tight = 0
    for seed in range(40):
        rng = np.random.default_rng(700 + seed)
        tp = random_program(rng, arcs=bool(seed % 4 == 3))
        M = tp.n_blocks
        head = np.where(rng.random(M) < 0.2, 0.0, rng.uniform(0.0, 0.5, M))
        tail = np.where(rng.random(M) < 0.2, 0.0, rng.uniform(0.0, 0.5, M))
        table, frac, pf, lengths, feeds = _alone_inputs(tp, rng, rng.uniform(20.0, 400.0, M), head, tail)
        jerk = rng.uniform(2e3, 2e5, tp.dim) if d.size > 1 else np.full(tp.dim, np.inf)
        limits = AxisLimits(rng.uniform(50.0, 300.0, tp.dim), rng.uniform(500.0, 8e3, tp.dim), jerk)
        blocks = np.ones(M, dtype=bool)
        exact = alone_block_ratios(table, blocks, frac, pf, lengths, feeds, tp.start, d, limits, prove=False)
        bound = alone_bounds(table, blocks, frac, pf, lengths, feeds, d, limits)
        assert np.all(bound >= exact * (1 - 1e-12)), (seed, bound, exact)
        assert np.all(np.isinf(bound[tp.is_arc]))
        tight += int(np.sum(np.isclose(bound, exact, rtol=1e-9)))
    assert tight > 20  # often tight (28-128 of about 200 blocks): a level's own peak reaches the bound


@pytest.mark.parametrize("pulse", [0.2, 0.05, 0.08, 0.02])
def test_alone_bound_of_a_rectangular_pulse_is_the_paper_peak(pulse):
    """One line at one feed (a rectangular pulse of ``T_v = L / F``) under T1/T2 = 60/30 ms:
    velocity ``F |u|`` and acceleration ``F |u| / T1`` (Sencer 2015 §2.1) in the bound and in the
    exact peaks; jerk ``F |u| / (T1 T2)``, doubled where ``T1 - T2 < T_v < T1 + T2`` (the
    deceleration of the first filter's output meets the second's, as in ``feed_caps``)."""
    from research.interpolators._fir_alone_bound import alone_bounds
    from research.interpolators._fir_limits import alone_block_ratios
    from research.paths.toolpath import ToolPath

    T1, T2, F = 0.06, 0.03, 100.0
    u = np.array([0.6, 0.8])
    tp = ToolPath.from_polyline(Polyline(np.array([[0.0, 0.0], F * pulse * u])))
    rng = np.random.default_rng(0)
    table, frac, pf, lengths, feeds = _alone_inputs(tp, rng, F, np.zeros(1), np.zeros(1), np.ones((1, 3)))
    limits = AxisLimits.uniform(2, 1e9, 1e9, 1.0)  # the jerk ratio alone: |j| / 1
    doubled = T1 - T2 < pulse < T1 + T2
    want = (2.0 if doubled else 1.0) * F * 0.8 / (T1 * T2)
    blocks = np.ones(1, dtype=bool)
    got = alone_bounds(table, blocks, frac, pf, lengths, feeds, np.array([T1, T2]), limits)
    exact = alone_block_ratios(table, blocks, frac, pf, lengths, feeds, tp.start, np.array([T1, T2]), limits,
                               prove=False)
    np.testing.assert_allclose(got, [want], rtol=1e-12)
    np.testing.assert_allclose(exact, [want], rtol=1e-9)
    for limits, want in ((AxisLimits.uniform(2, 1.0, 1e9, 1e12), F * 0.8), (AxisLimits.uniform(2, 1e9, 1.0, 1e12), F * 0.8 / T1)):
        got = alone_bounds(table, blocks, frac, pf, lengths, feeds, np.array([T1, T2]), limits)
        np.testing.assert_allclose(got, [want], rtol=1e-12)


def _alone_cases(seeds):
    """``(tp, table, lengths, feeds, head, tail, rng)`` of seeded random programs (lines; lines and
    arcs on odd seeds) with random feeds and line shares, as phase 1 sees them."""
    from research.paths.library import random_program

    for seed in seeds:
        rng = np.random.default_rng(seed)
        tp = random_program(rng, arcs=bool(seed % 2))
        M = tp.n_blocks
        table, _, _, lengths, feeds = _alone_inputs(tp, rng, rng.uniform(50.0, 300.0, M))
        head, tail = rng.uniform(0.0, 0.4, M), rng.uniform(0.0, 0.4, M)
        yield tp, table, lengths, feeds, head, tail, rng


def test_phase_one_decides_alike_with_and_without_the_bound():
    """``hold_block_limits`` on random programs and limits near their peaks: the same multipliers
    (to the bit) whether ``alone_block_ratios`` leaves out the blocks its bound proves safe or builds
    them all, with some blocks left out and some repaired."""
    from research.interpolators._fir_alone_bound import alone_bounds
    from research.interpolators._fir_limits import PROVEN, alone_block_ratios

    d = np.array([0.06, 0.03])
    left_out = repaired = 0
    for tp, table, lengths, feeds, head, tail, rng in _alone_cases(range(900, 930)):
        M = tp.n_blocks
        factor = rng.uniform(0.3, 1.0, (M, 3))
        limits = AxisLimits.fir_envelope(tp.dim, float(rng.uniform(40.0, 200.0)), d)
        which = rng.random(M) < 0.8

        def ratios(g, blocks, prove, decisions):
            frac, pf = table.pieces(head, tail, factor * g[:, None], None if not table.arc_pieces.size
                                    else np.ones(table.arc_pieces.size))
            return alone_block_ratios(table, blocks, frac, pf, lengths, feeds, tp.start, d, limits, prove=prove,
                                      decisions=decisions)

        frac, pf = table.pieces(head, tail, factor, None if not table.arc_pieces.size else np.ones(table.arc_pieces.size))
        left_out += int(np.sum(which & (alone_bounds(table, which, frac, pf, lengths, feeds, d, limits) <= PROVEN)))
        safe = np.full(M, 0.3)
        g_with = hold_block_limits(lambda g, b, decisions: ratios(g, b, True, decisions), safe, which)
        g_without = hold_block_limits(lambda g, b, decisions: ratios(g, b, False, decisions), safe, which)
        np.testing.assert_array_equal(g_with, g_without)
        repaired += int(np.sum(g_without < 1.0))
    assert left_out > 10 and repaired > 10


def test_alone_ratios_for_decisions_compare_as_the_full_build(monkeypatch):
    """``alone_block_ratios(..., decisions=True)`` on seeded random programs at random feed
    multipliers, limits near the peaks (some blocks above them, some proven safe): every
    comparison with ``1 + LIMIT_RTOL`` is that of the build of every block (``prove=False``), and
    it builds fewer blocks than ``decisions=False``, which builds them all again whenever a block
    is above the limit."""
    from research.interpolators import _fir_limits
    from research.interpolators._fir_limits import LIMIT_RTOL, alone_block_ratios

    built = []
    original = _fir_limits._built_ratios

    def counted(table, blocks, *args):
        built.append(int(np.sum(blocks)))
        return original(table, blocks, *args)

    monkeypatch.setattr(_fir_limits, "_built_ratios", counted)
    d = np.array([0.06, 0.03])
    sizes = {False: 0, True: 0}
    above = 0
    for tp, table, lengths, feeds, head, tail, rng in _alone_cases(range(950, 970)):
        M = tp.n_blocks
        factor = rng.uniform(0.3, 1.0, (M, 3)) * rng.uniform(0.2, 1.0, M)[:, None]
        frac, pf = table.pieces(head, tail, factor, None if not table.arc_pieces.size else np.ones(table.arc_pieces.size))
        limits = AxisLimits.fir_envelope(tp.dim, float(rng.uniform(40.0, 200.0)), d)
        blocks = rng.random(M) < 0.8
        exact = alone_block_ratios(table, blocks, frac, pf, lengths, feeds, tp.start, d, limits, prove=False)
        for decisions in (False, True):
            n0 = len(built)
            got = alone_block_ratios(table, blocks, frac, pf, lengths, feeds, tp.start, d, limits, decisions=decisions)
            np.testing.assert_array_equal(got[blocks] > 1.0 + LIMIT_RTOL, exact[blocks] > 1.0 + LIMIT_RTOL)
            sizes[decisions] += sum(built[n0:])
        above += int(np.sum(exact[blocks] > 1.0 + LIMIT_RTOL))
    assert above > 10
    assert sizes[True] < sizes[False]
