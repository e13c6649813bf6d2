"""The mirror search's feeds (``_fir_mirror_feeds``) and the nearest-point search its passes use
(``_fir_verify.nearest_instants``), each against an independent computation."""

import numpy as np
import pytest

from research.interpolators._fir_mirror_feeds import (LEAST_STEP, LIMIT_EXPONENT, LIMIT_REACH, RAISE_STEP,
                                                      curvature_caps, limit_factors, raise_factors, shrink_caps,
                                                      span_ratios, vertex_curvature)
from research.interpolators._fir_profile import _subsets
from research.interpolators._fir_piece_peaks import PiecePeaks
from research.interpolators._fir_verify import nearest_instants
from research.limits import AxisLimits
from research.paths import Polyline
from research.paths.toolpath import ToolPath
from research.piecewise import NumpyPiecewise

LIMITS = AxisLimits(np.array([150.0, 300.0]), np.array([2000.0, 5000.0]), np.array([8e4, 2e5]))


DELAYS = np.array([0.06, 0.03])
SIGMA = np.sqrt(np.sum(DELAYS**2) / 12.0)  # the kernel's rms half-width [s]


def caps_of(tp, feed, corners, limits):
    return curvature_caps(tp, feed, vertex_curvature(tp, feed, corners, DELAYS), DELAYS, limits)


@pytest.mark.parametrize("radius, n, feed", [(50.0, 400, 200.0), (10.0, 90, 150.0), (3.0, 60, 60.0)])
def test_a_regular_polygon_is_capped_by_its_weighted_turn(radius, n, feed):
    """A regular polygon inscribed in a circle of radius ``R`` (chords ``c = 2 R sin(theta / 2)``):
    vertex ``j`` away turns the tangent by ``2 sin(theta / 2)`` along a normal rotated by ``j theta``
    from this vertex's, so the triangle (half-width ``b = sqrt(6) F sigma``, weights ``1 - |j| c /
    b``) sums to ``2 sin(theta / 2) sum_j w_j cos(j theta)`` along the vertex's inward normal (the
    ``sin`` parts cancel in pairs), over ``b``. Blocks away from the ends are capped by the
    acceleration cap of that curvature on each axis, the jerk cap and the velocity cap, whichever is
    least. Summed here vertex by vertex, not by the running sums of the code."""
    theta = 2 * np.pi / n
    a = np.linspace(0.0, 2 * np.pi, n + 1)
    path = Polyline(np.stack([radius * np.cos(a), radius * np.sin(a)], axis=1))
    tp = ToolPath.from_polyline(path)
    c = 2 * radius * np.sin(theta / 2)
    caps = caps_of(tp, np.full(n, feed), np.zeros(n - 1, dtype=bool), LIMITS)
    b = np.sqrt(6.0) * feed * SIGMA
    k = int(np.floor(b / c))
    j = np.arange(-k, k + 1)
    size = 2 * np.sin(theta / 2) * np.sum((1 - np.abs(j) * c / b) * np.cos(j * theta)) / b
    normal = np.abs(np.stack([np.cos(a[1:-1]), np.sin(a[1:-1])], axis=1))
    at_vertex = np.minimum(np.min(np.sqrt(LIMITS.acceleration[None] / (size * np.maximum(normal, 1e-300))), axis=1),
                           np.cbrt(np.min(LIMITS.jerk) / size**2))
    expected = np.full(n, feed)
    expected[:-1] = np.minimum(expected[:-1], at_vertex)
    expected[1:] = np.minimum(expected[1:], at_vertex)
    m = int(np.floor(feed * SIGMA / c))  # the velocity cap's chord reaches m whole chords each side
    direction = np.abs(np.stack([-np.sin(a[:-1] + theta / 2), np.cos(a[:-1] + theta / 2)], axis=1))
    expected = np.minimum(expected, np.min(LIMITS.velocity[None] / np.maximum(direction, 1e-300), axis=1))
    inner = slice(max(k, m) + 1, n - max(k, m) - 1)  # blocks whose reach holds whole chords on each side
    np.testing.assert_allclose(caps[inner], expected[inner], rtol=1e-9)
    assert size == pytest.approx(1.0 / radius, rel=(b / radius) ** 2 + 2 * (c / b) ** 2)


def test_rounded_chords_read_as_the_curve_they_follow():
    """A circle of R 20 mm in 20 um chords whose vertices are rounded to 2.54 um (4-decimal inch
    output): the chords zigzag by up to ~10 deg, and one vertex's turn over its chords would read as
    a radius of 0.1 mm; over the reach the turns cancel, and the caps stay within 10 % of those of
    the exact circle's (the same chords unrounded)."""
    R, n = 20.0, 6000
    a = np.linspace(0.0, np.pi, n + 1)
    exact = np.stack([R * np.cos(a), R * np.sin(a)], axis=1)
    rounded = np.round(exact / 2.54e-3) * 2.54e-3
    feed = np.full(n, 200.0)
    caps = [caps_of(ToolPath.from_polyline(Polyline(p)), feed, np.zeros(n - 1, dtype=bool), LIMITS)
            for p in (exact, rounded)]
    turns = ToolPath.from_polyline(Polyline(rounded)).turning_angles()
    assert np.degrees(turns.max()) > 5.0
    inner = slice(n // 10, -n // 10)
    np.testing.assert_allclose(caps[1][inner], caps[0][inner], rtol=0.1)


def test_corners_and_no_limits_take_no_curvature_cap():
    """A right-angle corner flagged as an eq 13/14 dwell corner caps neither block (its dwell holds
    its error); the lines keep their velocity caps ``min_a V_a / |t_a|``; without limits the caps
    are the commanded feed. Unflagged, the corner's turn ``(-1, 1)`` over ``b = sqrt(6) 400 sigma``
    (the larger feed's triangle) caps both blocks."""
    tp = ToolPath.from_polyline(Polyline([[0.0, 0.0], [10.0, 0.0], [10.0, 10.0]]))
    feed = np.array([400.0, 120.0])
    np.testing.assert_array_equal(caps_of(tp, feed, np.array([True]), LIMITS), [150.0, 120.0])
    np.testing.assert_array_equal(caps_of(tp, feed, np.array([True]), None), feed)
    kappa = 1.0 / (np.sqrt(6.0) * 400.0 * SIGMA)  # per axis [1/mm]: the vertex's own step, weight 1
    cap = min(np.sqrt(2000.0 / kappa), np.cbrt(8e4 / (2 * kappa**2)))
    capped = caps_of(tp, feed, np.array([False]), LIMITS)
    np.testing.assert_allclose(capped, [min(150.0, cap), min(120.0, cap)], rtol=1e-12)


def test_an_arc_block_takes_its_radius():
    """A G2 quarter arc of R 8 mm: ``min(F, min V, sqrt(min A R), (min J R^2)^(1/3))``."""
    tp = ToolPath.from_polyline(Polyline([[0.0, 0.0], [0.0, 8.0]]))
    tp = tp.then_arc(np.array([8.0, 16.0]), np.array([8.0, 8.0]), ccw=False)
    caps = caps_of(tp, np.array([500.0, 500.0]), np.array([True]), LIMITS)
    R = 8.0
    assert caps[1] == pytest.approx(min(150.0, np.sqrt(2000.0 * R), np.cbrt(8e4 * R**2)), rel=1e-12)


def kernel_shifts(delays):
    """The shifts ``limit_factors`` reads the kernel at: ``_fir_profile._subsets``' subset sums."""
    return _subsets(tuple(float(d) for d in delays))[0]


def test_kernel_shifts_are_the_subset_sums():
    np.testing.assert_allclose(np.sort(kernel_shifts([0.06, 0.03])), [0.0, 0.03, 0.06, 0.09])
    assert kernel_shifts([0.05, 0.02, 0.01]).size == 8
    np.testing.assert_allclose(np.sort(kernel_shifts([0.05])), [0.0, 0.05])


def test_limit_factors_lower_the_blocks_in_use_at_the_shifted_instants():
    """Blocks of 10 ms pulses end to end; a violation at 95 ms with ratio 1.5 under delays 40/20 ms
    reaches the blocks in use within ``LIMIT_REACH * 20 ms`` (1 ms) of 95, 55, 75 and 35 ms (blocks
    9, 5, 7, 3) by ``1.5^-1/4``; one at ratio 1.0001 takes at least :data:`LEAST_STEP`; the others
    keep 1. With pulses of 0.2 ms the same reach spans the 11 blocks around each instant, and in
    a dwell (5 ms pulses every 10 ms, 97 ms: after block 9's pulse) the block before it."""
    delays = np.array([0.04, 0.02])
    starts = np.arange(12) * 0.01
    f = limit_factors(starts, np.full(12, 0.01), np.array([0.095]), np.array([1.5]), delays)
    lowered = np.flatnonzero(f < 1.0)
    np.testing.assert_array_equal(lowered, [3, 5, 7, 9])
    np.testing.assert_allclose(f[lowered], 1.5 ** -LIMIT_EXPONENT)
    g = limit_factors(starts, np.full(12, 0.01), np.array([0.0055]), np.array([1.0001]), delays)
    np.testing.assert_allclose(g[0], 1.0 - LEAST_STEP)
    assert np.all(g[1:] == 1.0)
    short = np.arange(1000) * 2e-4
    h = limit_factors(short, np.full(1000, 2e-4), np.array([0.0951]), np.array([1.5]), delays)
    reach = LIMIT_REACH * 0.02
    for t in (0.0951, 0.0551, 0.0751, 0.0351):
        span = np.flatnonzero((short <= t + reach) & (short + 2e-4 >= t - reach))
        assert np.all(h[span] < 1.0) and span.size == 11
    assert np.sum(h < 1.0) == 44
    dwell = limit_factors(starts, np.full(12, 0.005), np.array([0.097 + 0.04 + 0.02]), np.array([1.5]), delays)
    assert dwell[9] < 1.0 and dwell[10] == 1.0


@pytest.mark.parametrize("rows, axes", [(4, 3), (4, 2), (9, 3), (9, 2), (5, 3)])
def test_nearest_instants_of_a_line_are_the_projections(rows, axes):
    """On ``p(t) = p0 + v t`` the nearest point to ``V`` is at ``t = (V - p0) . v / |v|^2``: random
    points within reach of the search window, found to 1e-9 s; for every compiled form of the
    search (coefficient rows and axes as constants, the line padded with zero rows; 5 rows: the
    generic form)."""
    rng = np.random.default_rng(3)
    p0, v = np.array([1.0, -2.0, 0.5])[:axes], np.array([120.0, 35.0, -10.0])[:axes]
    pos = NumpyPiecewise(np.array([0.0, 2.0]), np.array([[p0, v] + [np.zeros(axes)] * (rows - 2)]))
    t_true = rng.uniform(0.2, 1.8, 50)
    side = rng.normal(size=(50, axes))
    side -= np.outer(side @ v / (v @ v), v)  # across the line: the projection stays at t_true
    vertices = p0 + np.outer(t_true, v) + 0.3 * side
    centre = t_true + rng.uniform(-0.03, 0.03, 50)
    np.testing.assert_allclose(nearest_instants(pos, vertices, centre, 0.045), t_true, atol=1e-9)


@pytest.mark.parametrize("radius", [5.0, 20.0, 80.0])
def test_shrink_caps_hold_eq8s_shrink_near_the_tolerance(radius):
    """On a circle of radius ``R`` (curvature ``1 / R``) the cap is the feed at which eq 8's
    second-order shrink ``F^2 var / (2 R)`` is the tolerance; eq 8's exact shrink ``R (1 - prod
    sinc(F T_i / 2R))`` at that feed (computed here) is the tolerance to within its fourth-order
    term (a few % at these feeds); straight vertices cap nothing."""
    eps = 0.05
    kappa = np.array([[1.0 / radius, 0.0], [0.0, 0.0]])
    caps = shrink_caps(kappa, np.array([eps, eps]), DELAYS)
    F = caps[0]
    exact = radius * (1.0 - np.prod([np.sinc(F * T / (2 * radius) / np.pi) for T in DELAYS]))
    assert exact == pytest.approx(eps, rel=0.05)
    assert F == pytest.approx(np.sqrt(2 * eps * radius / SIGMA**2), rel=1e-12)
    assert caps[2] == np.inf


def test_a_jerk_peak_lowers_only_the_blocks_that_push_it():
    """Under two filters the jerk is ``(v(t) - v(t - T_1) - v(t - T_2) + v(t - T_1 - T_2)) / (T_1
    T_2)``. Blocks moving along +x, a jerk peak of +1.5 on x at 95 ms (delays 40/20 ms): the terms
    at 95 and 35 ms push it up, those at 55 and 75 ms down, so only blocks 9 and 3 are lowered. The
    same instant's peak of another derivative (its jerk row 0) lowers all four; a peak of -1.5
    lowers blocks 5 and 7."""
    delays = np.array([0.04, 0.02])
    starts = np.arange(12) * 0.01
    tangents = np.tile([1.0, 0.0], (12, 1))
    up = limit_factors(starts, np.full(12, 0.01), np.array([0.095]), np.array([1.5]), delays,
                       (np.array([[1.5, 0.2]]), tangents))
    np.testing.assert_array_equal(np.flatnonzero(up < 1.0), [3, 9])
    other = limit_factors(starts, np.full(12, 0.01), np.array([0.095]), np.array([1.5]), delays,
                          (np.zeros((1, 2)), tangents))
    np.testing.assert_array_equal(np.flatnonzero(other < 1.0), [3, 5, 7, 9])
    down = limit_factors(starts, np.full(12, 0.01), np.array([0.095]), np.array([1.5]), delays,
                         (np.array([[-1.5, 0.0]]), tangents))
    np.testing.assert_array_equal(np.flatnonzero(down < 1.0), [5, 7])


@pytest.mark.parametrize("seed", range(3))
def test_span_ratios_and_raise_factors_read_each_blocks_output_span(seed):
    """A random cubic profile (60 pieces of 1-5 ms, two axes, growing along time so that some
    spans hold a peak above a limit and some do not) and 20 blocks of random pulses under delays of
    8 / 3 ms: each block's ratio is the largest ``PiecePeaks`` ratio of the pieces overlapping
    ``[start, end + T_1 + T_2]``, found here by a loop over the blocks; the factors of
    :func:`raise_factors` are ``min(r^-LIMIT_EXPONENT, 1 + RAISE_STEP)``, 1 where ``r >= 1``."""
    rng = np.random.default_rng(seed)
    breaks = np.concatenate([[0.0], np.cumsum(rng.uniform(1e-3, 5e-3, 60))])
    coeffs = rng.normal(size=(60, 4, 2)) * np.array([1.0, 30.0, 300.0, 1e4])[None, :, None]
    coeffs *= np.linspace(0.05, 2.0, 60)[:, None, None]
    position = NumpyPiecewise(breaks, coeffs)
    per_piece = PiecePeaks(position, LIMITS).per_piece
    starts = np.sort(rng.uniform(-0.02, breaks[-1], 20))
    pulses = rng.uniform(1e-4, 8e-3, 20)
    delays = np.array([0.003, 0.008])
    r = span_ratios(starts, pulses, PiecePeaks(position, LIMITS), delays)
    expected = np.zeros(20)
    for k in range(20):
        overlap = (breaks[1:] > starts[k]) & (breaks[:-1] < starts[k] + pulses[k] + 0.011)
        expected[k] = per_piece[overlap].max(initial=0.0)
    np.testing.assert_allclose(r, expected, rtol=1e-12)
    assert np.any(r < 1.0) and np.any(r > 1.0)
    below = np.where(r < 1.0, r, 1.0)
    np.testing.assert_allclose(raise_factors(r, RAISE_STEP), np.minimum(np.maximum(below, 1e-300) ** -LIMIT_EXPONENT,
                                                                         1.0 + RAISE_STEP))
    steps = rng.uniform(0.0, 0.1, 20)  # one largest raise per block
    np.testing.assert_allclose(raise_factors(r, steps), np.minimum(np.maximum(below, 1e-300) ** -LIMIT_EXPONENT,
                                                                   1.0 + steps))
