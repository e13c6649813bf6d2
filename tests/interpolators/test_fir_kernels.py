"""Compiled kernels of the FIR planner (``_fir_kernels``) against slow independent computations.

References computed here: the windowed displacement ``d_j(F)`` summed term by term from its
definition (``_fir_feed`` module docstring) with ``kernel_second_integral``; the corner distance by
dense sampling of the exact profile; the path distance by projecting every sample on every
segment. Nothing is compared with the planner's earlier output."""

import numpy as np
import pytest

from research.interpolators import plan_fir
from research.interpolators._fir_chain import kernel_second_integral
from research.interpolators._fir_feed import ChainError
from research.interpolators._fir_kernels import _displacement
from research.interpolators._fir_verify_kernels import sampled_line_distances
from research.interpolators._fir_verify import corner_distances, vertex_distances
from research.paths import Polyline
from research.piecewise import NumpyPiecewise


def slow_displacement(s, du, delays, sq, F):
    """``d_j(F) = F sum_i du_i H2(T_d / 2 - |s_i - s_j| / F)`` over ``|s_i - s_j| < F T_d / 2`` for
    queries ``sq``, ``F`` ``(J,)``: every term of every turn (``H2`` from ``_fir_chain``, 0 outside
    the window), no window search, no prefix sums. Returns ``(J, d)``."""
    Td = float(np.sum(delays))
    sq, F = np.atleast_1d(sq), np.atleast_1d(F)
    r = 0.5 * Td - np.abs(s[None, :] - sq[:, None]) / F[:, None]
    h2 = np.where(r > 0, np.asarray(kernel_second_integral(np.maximum(r, 0.0), np.asarray(delays))), 0.0)
    return F[:, None] * (h2 @ du)


@pytest.mark.parametrize("chunk", [7, 1024])  # windows over many chunks of the prefix sums (a prime size); one
@pytest.mark.parametrize("delays", [(0.06, 0.03), (0.05, 0.02, 0.01)])
@pytest.mark.parametrize("span", [2000.0, 40.0])  # sparse windows (direct sums), dense ones (prefix sums)
def test_window_displacement_matches_the_term_by_term_sum(delays, span, chunk, monkeypatch):
    monkeypatch.setattr("research.interpolators._fir_feed._CHUNK", chunk)
    rng = np.random.default_rng(7)
    T = 800
    s = np.sort(rng.uniform(0.0, span, T))
    du = rng.normal(0.0, 0.05, (T, 3))
    chain = ChainError(s, du, np.asarray(delays))
    sq = rng.uniform(0.0, span, 40)
    F = rng.uniform(5.0, 300.0, 40)
    got = chain.displacement(sq, F)
    want = slow_displacement(s, du, delays, sq, F)
    scale = np.max(np.abs(want))
    assert np.max(np.abs(got - want)) <= 1e-9 * scale


@pytest.mark.parametrize("chunk", [16, 1024])  # many chunks per window; one chunk spanning both stretches
@pytest.mark.parametrize("delays", [(0.06, 0.03), (0.05, 0.02, 0.01)])
def test_dense_windows_far_along_a_long_chain_keep_their_precision(delays, chunk, monkeypatch):
    """Two dense stretches of turns (800 each over 40 mm) 100 m of path apart, as on a long
    program with arcs: windows of many turns at either end match the term-by-term sum to 1e-9 of
    their size, with chunks of the prefix sums smaller than a window, and with a chunk that holds
    turns of both stretches (read turn by turn where it reaches far out). (With the prefix sums
    about one origin for the whole chain, midway between the two, the binomial re-centring
    cancelled ``(5e4 mm / 13.5 mm)^3 ~ 5e10`` ulps: errors of 1e-5 of the window's value here, and
    of the whole tolerance on a 26 m adaptive-clearing program.)"""
    monkeypatch.setattr("research.interpolators._fir_feed._CHUNK", chunk)
    rng = np.random.default_rng(3)
    s = np.concatenate([np.sort(rng.uniform(0.0, 40.0, 800)), 1e5 + np.sort(rng.uniform(0.0, 40.0, 800))])
    du = rng.normal(0.0, 0.05, (s.size, 3))
    chain = ChainError(s, du, np.asarray(delays))
    sq = np.concatenate([rng.uniform(0.0, 40.0, 20), 1e5 + rng.uniform(0.0, 40.0, 20)])
    F = rng.uniform(50.0, 300.0, 40)
    got = chain.displacement(sq, F)
    want = slow_displacement(s, du, delays, sq, F)
    assert chain._prefix is not None  # the dense windows took the prefix sums
    err = np.max(np.abs(got - want), axis=1)
    assert np.all(err <= 1e-9 * np.max(np.abs(want), axis=1))


@pytest.mark.parametrize("span", [2000.0, 40.0])  # sparse windows (no prefix sums made), dense ones
def test_prefix_sums_are_made_only_for_windows_of_many_turns(span):
    """Sparse windows (800 turns over 2000 mm, windows <= 300 mm/s x 0.045 s each side) are all
    summed directly: no prefix sums are made and the displacements and feeds are those of a chain
    that has them (the direct sums do not read them, bit for bit). Dense windows (over 40 mm) make
    them, and match the term-by-term sum."""
    rng = np.random.default_rng(5)
    T, delays = 800, np.array([0.06, 0.03])
    s = np.sort(rng.uniform(0.0, span, T))
    du = rng.normal(0.0, 0.05, (T, 3))
    sq, F = rng.uniform(0.0, span, 40), rng.uniform(5.0, 300.0, 40)
    lazy, eager = ChainError(s, du, delays), ChainError(s, du, delays)
    eager.prefix  # made up front
    d = lazy.displacement(sq, F)
    f = lazy.largest_feed(sq, F, 1e-3)
    assert (lazy._prefix is None) == (span == 2000.0)
    np.testing.assert_array_equal(d, eager.displacement(sq, F))
    np.testing.assert_array_equal(f, eager.largest_feed(sq, F, 1e-3))
    want = slow_displacement(s, du, delays, sq, F)
    assert np.max(np.abs(d - want)) <= 1e-9 * np.max(np.abs(want))


@pytest.mark.parametrize("chunk", [7, 1024])  # windows over many chunks of the prefix sums; one
@pytest.mark.parametrize("delays", [(0.06, 0.03), (0.05, 0.02, 0.01)])
@pytest.mark.parametrize("span", [2000.0, 40.0])  # direct sums, prefix sums
def test_window_slope_matches_central_differences_of_the_term_by_term_sum(delays, span, chunk, monkeypatch):
    """``d d_j / dF`` (the Newton search's slope) against ``(d_j(F (1 + h)) - d_j(F (1 - h))) / (2 F h)``
    of the independent sum, ``h = 1e-6`` (truncation ``O(h^2)``, rounding ``1e-16 / h``)."""
    monkeypatch.setattr("research.interpolators._fir_feed._CHUNK", chunk)
    rng = np.random.default_rng(11)
    T = 800
    s = np.sort(rng.uniform(0.0, span, T))
    du = rng.normal(0.0, 0.05, (T, 3))
    chain = ChainError(s, du, np.asarray(delays))
    h = 1e-6
    worst, scale = 0.0, 0.0
    for sq, F in zip(rng.uniform(0.0, span, 20), rng.uniform(5.0, 300.0, 20)):
        out, dout = np.zeros(3), np.zeros(3)
        _displacement(*chain._args(), sq - chain.origin, F, out, dout)
        fd = (slow_displacement(s, du, delays, sq, F * (1 + h)) - slow_displacement(s, du, delays, sq, F * (1 - h)))[0] / (2 * F * h)
        worst, scale = max(worst, float(np.max(np.abs(dout - fd)))), max(scale, float(np.max(np.abs(fd))))
    assert scale > 0 and worst <= 1e-6 * scale


def python_direct_sum(chain, sq, F):
    """``(d_j, d d_j / dF)`` of one query summed turn by turn in Python floats (IEEE doubles), in the
    order and with the operations the kernel's general loop states: per turn
    ``x = |s_i - q| / F``, then over the subset terms in order ``r1 = sign (1.0 r ... r)``
    (``p - 1`` factors), ``h += r1 r``, ``g += r1 (r + p x)`` where ``r = rho - x > 0``, and the
    sums ``out += (h norm F) du_i``, ``dout += (g norm) du_i`` in turn order."""
    q = sq - chain.origin
    R = F * float(np.max(chain.rho))
    first = int(np.searchsorted(chain.s, q - R, side="right"))
    last = int(np.searchsorted(chain.s, q + R, side="left"))
    d = chain.du.shape[1]
    out, dout = [0.0] * d, [0.0] * d
    for i in range(first, last):
        x = abs(float(chain.s[i]) - q) / F
        h = g = 0.0
        for rho, sign in zip(chain.rho.tolist(), chain.sign.tolist()):
            r = rho - x
            if r > 0.0:
                power = 1.0
                for _ in range(chain.p - 1):
                    power *= r
                r1 = sign * power
                h += r1 * r
                g += r1 * (r + chain.p * x)
        w, wd = h * chain.norm * F, g * chain.norm
        for k in range(d):
            out[k] += w * float(chain.du[i, k])
            dout[k] += wd * float(chain.du[i, k])
    return np.array(out), np.array(dout)


@pytest.mark.parametrize("delays, dim", [((0.06, 0.03), 3), ((0.06, 0.03), 2), ((0.04, 0.04), 3), ((0.05, 0.02, 0.01), 3)])
def test_direct_sums_are_the_turn_by_turn_loop_bit_for_bit(delays, dim):
    """The direct sums (the branch-free weights of three axes and two unequal filters, the general
    loop otherwise) give the plain Python loop's floats exactly, with and without the slope
    (``chain_displacements`` does not sum the slope); windows reach the chain's ends too."""
    rng = np.random.default_rng(17 + dim)
    T = 300
    s = np.cumsum(rng.uniform(0.05, 1.5, T))
    du = rng.normal(0.0, 0.1, (T, dim))
    chain = ChainError(s, du, np.asarray(delays))
    sq = np.concatenate([rng.uniform(s[0] - 5.0, s[-1] + 5.0, 60), s[rng.choice(T, 20, replace=False)]])
    F = rng.uniform(5.0, 300.0, sq.size)
    got = chain.displacement(sq, F)
    assert chain._prefix is None  # every window summed directly
    for j in range(sq.size):
        want, dwant = python_direct_sum(chain, float(sq[j]), float(F[j]))
        np.testing.assert_array_equal(got[j], want)
        out, dout = np.zeros(dim), np.zeros(dim)
        _displacement(*chain._args(), sq[j] - chain.origin, F[j], out, dout)
        np.testing.assert_array_equal(out, want)
        np.testing.assert_array_equal(dout, dwant)


def test_largest_feed_is_the_root_of_the_window_error():
    """The feed found keeps ``|d_j| <= eps`` and is within the search's resolution (2^-36 of the
    bracket, here below 1e-7 relative) of a feed that breaks it."""
    rng = np.random.default_rng(3)
    delays = np.array([0.06, 0.03])
    T = 400
    s = np.cumsum(rng.uniform(0.2, 2.0, T))
    du = rng.normal(0.0, 0.1, (T, 3))
    chain = ChainError(s, du, delays)
    sq = s[rng.choice(T, 30, replace=False)]
    hi = np.full(30, 200.0)
    tol = rng.uniform(0.005, 0.05, 30)
    f = chain.largest_feed(sq, hi, tol)
    e = np.linalg.norm(slow_displacement(s, du, delays, sq, f), axis=1)
    assert np.all(e <= tol * (1 + 1e-12))
    below = f < 200.0
    assert below.sum() >= 10  # the case is not trivial
    e_up = np.linalg.norm(slow_displacement(s, du, delays, sq[below], f[below] * (1 + 1e-7)), axis=1)
    assert np.all(e_up > tol[below])


def zigzag(n=60, seed=0):
    rng = np.random.default_rng(seed)
    pts = np.cumsum(np.column_stack([rng.uniform(0.5, 3.0, n), rng.uniform(-1.5, 1.5, n), rng.uniform(-0.2, 0.2, n)]),
                    axis=0)
    return Polyline(pts)


def test_vertex_distances_match_dense_sampling_and_the_jax_search():
    path = zigzag()
    plan = plan_fir(path, 150.0, (0.05, 0.02), 0.03, refine=False)
    pos = NumpyPiecewise(np.asarray(plan.position.breaks), np.asarray(plan.position.coeffs))
    half = 0.5 * 0.07
    centre = np.asarray(plan.corner_times)
    got = vertex_distances(pos, np.asarray(plan.vertices), centre, half)
    jax_form = np.asarray(corner_distances(plan.position, plan.vertices, plan.corner_times, half))
    np.testing.assert_allclose(got, jax_form, rtol=1e-12, atol=1e-15)
    for c in range(got.size):
        t = np.linspace(centre[c] - half, centre[c] + half, 4001)
        dense = np.min(np.linalg.norm(pos(t) - np.asarray(plan.vertices)[c], axis=1))
        assert got[c] <= dense * (1 + 1e-12) + 1e-15  # never above a sampled point's distance
        # and at the minimum, to the sampling's resolution: a sample at most half a step (h) off the
        # nearest instant is at most (F h / 2)^2 / (2 d) farther (the chord's sagitta at feed <= F)
        h = 2 * half / 4000
        assert got[c] >= dense - (150.0 * h / 2) ** 2 / (2 * max(got[c], 1e-6)) - 1e-12


def test_sampled_line_distances_match_projection_on_each_segment():
    path = zigzag(seed=1)
    plan = plan_fir(path, 150.0, (0.05, 0.02), 0.03, refine=False)
    pos = NumpyPiecewise(np.asarray(plan.position.breaks), np.asarray(plan.position.coeffs))
    starts = np.asarray(plan.start_times)
    Td = 0.07
    t = np.concatenate([np.linspace(float(pos.breaks[0]) - 0.1, float(pos.breaks[-1]) + 0.1, 3001), np.asarray(plan.corner_times)])
    a, b = path.points[:-1], path.points[1:]
    ab = b - a
    q, block, d2 = sampled_line_distances(pos.breaks, pos.coeffs, t, starts, 0.5 * Td, a, ab,
                                          1.0 / np.einsum("kd,kd->k", ab, ab))
    np.testing.assert_array_equal(q, pos(t))
    M = path.n_segments
    want_block = np.clip(np.searchsorted(starts, t - 0.5 * Td, side="right") - 1, 0, M - 1)
    np.testing.assert_array_equal(block, want_block)
    for c in range(3):
        k = np.clip(block - 1 + c, 0, M - 1)
        u = np.clip(np.sum((q - a[k]) * ab[k], axis=1) / np.sum(ab[k] ** 2, axis=1), 0.0, 1.0)
        np.testing.assert_allclose(d2[:, c], np.sum((q - a[k] - u[:, None] * ab[k]) ** 2, axis=1), rtol=1e-9, atol=1e-16)  # rounding of coordinates ~100 mm


def random_profile(rng, K, D, A):
    """A random piecewise polynomial: ``K`` pieces of 1-20 ms (every fifth of zero length, so
    repeated breaks), ``D`` coefficient rows, ``A`` axes."""
    durations = rng.uniform(1e-3, 2e-2, K)
    durations[rng.random(K) < 0.2] = 0.0
    breaks = 0.3 + np.concatenate([[0.0], np.cumsum(durations)])
    return NumpyPiecewise(breaks, rng.normal(0.0, 1.0, (K, D, A)) * 10.0 ** -np.arange(D)[None, :, None])


def awkward_times(rng, breaks, n):
    """Sample times that run forward in a grid beyond both ends of the breaks, then repeat a few
    times, jump back by a third of the span and run on, hit every break (repeated ones included),
    and end with random times in no order."""
    lo, hi = float(breaks[0]), float(breaks[-1])
    grid = np.linspace(lo - 0.05, hi + 0.05, n)
    back = grid[n // 2] - (hi - lo) / 3.0 + np.arange(n // 10) * (grid[1] - grid[0]) * 0.7
    return np.concatenate([grid, np.repeat(grid[n // 3: n // 3 + 5], 3), back, breaks,
                           rng.uniform(lo - 0.1, hi + 0.1, n // 10)])


@pytest.mark.parametrize("D, A", [(4, 3), (4, 2), (9, 2), (9, 3), (5, 3), (2, 4)])  # compiled constants, then generic
def test_sampled_line_distances_match_numpy_on_random_profiles(D, A):
    """The kernel against NumPy on random profiles: the position as ``NumpyPiecewise`` (bit for bit,
    the same Horner sums), the block by ``np.searchsorted`` and the distances by projecting on each
    segment, for times outside the breaks, repeated, going backwards and at the breaks."""
    rng = np.random.default_rng(11 + 7 * D + A)
    pos = random_profile(rng, 300, D, A)
    t = awkward_times(rng, pos.breaks, 1500)
    M, half = 60, 0.03
    starts = np.sort(rng.uniform(float(pos.breaks[0]) - 0.1, float(pos.breaks[-1]), M))
    starts[7] = starts[6]  # a zero-duration block
    a = rng.normal(0.0, 1.0, (M, A))
    ab = rng.normal(0.0, 1.0, (M, A))
    ab[3] = 0.0  # a zero-length block
    ab2 = np.sum(ab * ab, axis=1)
    inv = np.where(ab2 > 0, 1.0 / np.where(ab2 > 0, ab2, 1.0), 0.0)
    q, block, d2 = sampled_line_distances(pos.breaks, pos.coeffs, t, starts, half, a, ab, inv)
    np.testing.assert_array_equal(q, pos(t))
    want_block = np.clip(np.searchsorted(starts, t - half, side="right") - 1, 0, M - 1)
    np.testing.assert_array_equal(block, want_block)
    want = pos(t)
    for c in range(3):
        k = np.clip(want_block - 1 + c, 0, M - 1)
        u = np.clip(np.sum((want - a[k]) * ab[k], axis=1) / np.where(ab2[k] > 0, ab2[k], np.inf), 0.0, 1.0)
        np.testing.assert_allclose(d2[:, c], np.sum((want - a[k] - u[:, None] * ab[k]) ** 2, axis=1), rtol=1e-12, atol=1e-14)
    assert (np.diff(t) < 0).any() and (np.diff(t) == 0).any() and (t < pos.breaks[0]).any() and (t > pos.breaks[-1]).any()


def numpy_corner_distances(pos, vertices, centre, half, grid=9, steps=4):
    """The corner search of ``_fir_verify.corner_distances`` in NumPy on ``NumpyPiecewise``: the
    best of ``grid`` points over ``centre +- half``, then ``steps`` Newton steps on ``|p(t) - V|^2``
    (Gauss-Newton, curvature ``|v|^2``, where Newton's curvature is not positive) clipped to one
    grid step around it; the smaller of that point's and the grid's distance."""
    tg = centre[:, None] + half * np.linspace(-1.0, 1.0, grid)[None, :]
    d2 = np.sum((pos(tg) - vertices[:, None, :]) ** 2, axis=-1)
    t = tg[np.arange(centre.size), np.argmin(d2, axis=1)]
    lo, hi = t - 2.0 * half / (grid - 1), t + 2.0 * half / (grid - 1)
    for _ in range(steps):
        e, v, acc = pos(t) - vertices, pos(t, 1), pos(t, 2)
        slope, curvature, speed2 = np.sum(e * v, axis=1), np.sum(v * v + e * acc, axis=1), np.sum(v * v, axis=1)
        gauss = np.where(speed2 > 0, t - slope / np.where(speed2 > 0, speed2, 1.0), t)
        t = np.clip(np.where(curvature > 0, t - slope / np.where(curvature > 0, curvature, 1.0), gauss), lo, hi)
    return np.sqrt(np.minimum(np.sum((pos(t) - vertices) ** 2, axis=1), d2.min(axis=1)))


@pytest.mark.parametrize("D, A", [(4, 3), (4, 2), (9, 2), (9, 3), (10, 2), (2, 4)])  # compiled constants, then generic
def test_corner_distances_match_a_numpy_search_on_random_profiles(D, A):
    """``_fir_verify_kernels.corner_distances`` (compiled per row and axis count) against the same search
    in NumPy, with windows reaching beyond the breaks and corner instants not in order."""
    from research.interpolators._fir_verify_kernels import corner_distances as kernel

    rng = np.random.default_rng(3 + 5 * D + A)
    pos = random_profile(rng, 200, D, A)
    lo, hi = float(pos.breaks[0]), float(pos.breaks[-1])
    centre = np.concatenate([np.sort(rng.uniform(lo - 0.02, hi + 0.02, 150)), rng.uniform(lo, hi, 20)])
    vertices = pos(centre + rng.normal(0.0, 0.01, centre.size)) + rng.normal(0.0, 0.05, (centre.size, A))
    got = kernel(pos.breaks, pos.coeffs, vertices, centre, 0.04, 9, 4, np.full(centre.size, np.inf), 24)
    np.testing.assert_allclose(got, numpy_corner_distances(pos, vertices, centre, 0.04), rtol=1e-9, atol=1e-12)


def test_corner_search_refined_above_its_bound_is_closer_and_still_a_distance_to_the_trajectory():
    """With a bound of 0 every search takes up to 24 further Newton steps: each distance is at most
    the 4-step one, and at least the least distance to the trajectory over its search window
    sampled every 1e-6 s, less what the trajectory can move in half a sample (an upper bound is
    never below the true least distance). Distances within their bound are the 4-step ones."""
    from research.interpolators._fir_verify_kernels import corner_distances as kernel

    rng = np.random.default_rng(17)
    pos = random_profile(rng, 200, 4, 3)
    lo, hi = float(pos.breaks[0]), float(pos.breaks[-1])
    centre = np.sort(rng.uniform(lo + 0.05, hi - 0.05, 40))
    vertices = pos(centre + rng.normal(0.0, 0.01, centre.size)) + rng.normal(0.0, 0.002, (centre.size, 3))
    plain = kernel(pos.breaks, pos.coeffs, vertices, centre, 0.04, 9, 4, np.full(centre.size, np.inf), 24)
    refined = kernel(pos.breaks, pos.coeffs, vertices, centre, 0.04, 9, 4, np.zeros(centre.size), 24)
    assert np.all(refined <= plain)
    within = kernel(pos.breaks, pos.coeffs, vertices, centre, 0.04, 9, 4, plain + 1e-12, 24)
    np.testing.assert_array_equal(within, plain)
    for c in range(centre.size):
        t = np.arange(centre[c] - 0.04, centre[c] + 0.04, 1e-6)
        q = pos(t)
        speed = float(np.max(np.linalg.norm(np.diff(q, axis=0), axis=1))) / 1e-6
        least = float(np.min(np.linalg.norm(q - vertices[c], axis=1)))
        assert refined[c] >= least - 0.5e-6 * speed - 1e-12


def test_hinted_searches_are_searchsorted():
    """The kernels' galloping searches from a hint (``research._sorted_search.right_from`` and
    ``left_from``) give ``np.searchsorted(a, v, "right")`` and ``(..., "left")`` for any hint,
    including repeated entries (zero-length pieces) and values outside the array."""
    from research._sorted_search import left_from, right_from

    rng = np.random.default_rng(0)
    for _ in range(2000):
        n = int(rng.integers(0, 40))
        a = np.sort(rng.integers(0, 20, n).astype(np.float64))
        v = float(rng.integers(-2, 22)) + float(rng.choice([0.0, 0.5]))
        hint = int(rng.integers(-3, n + 4))
        assert right_from(a, v, hint) == np.searchsorted(a, v, side="right")
        assert left_from(a, v, hint) == np.searchsorted(a, v, side="left")
    for n in (0, 1, 2, 7, 100, 1000):  # empty and one-entry arrays; hints before, at, after the answer
        a = np.sort(np.round(rng.uniform(0.0, 10.0, n), 1))
        for v in np.concatenate([rng.uniform(-1.0, 11.0, 40), a[:: max(n // 10, 1)]]):
            for search, side in ((left_from, "left"), (right_from, "right")):
                want = np.searchsorted(a, v, side=side)
                for hint in (-5, 0, n // 2, n - 1, n + 3, int(want)):
                    assert search(a, v, hint) == want, (n, v, side, hint)


def test_scatter_max_is_numpys_maximum_at():
    from research.interpolators._fir_verify_kernels import scatter_max

    rng = np.random.default_rng(1)
    index, values = rng.integers(0, 50, 3000), rng.normal(size=3000)
    want = np.full(60, -np.inf)
    np.maximum.at(want, index, values)
    got = np.full(60, -np.inf)
    scatter_max(got, index, values)
    np.testing.assert_array_equal(got, want)


def test_range_min_matches_brute_force():
    """``_range_min_into`` (the look-ahead's range minima) against a double loop over ranges and cells, on seeded random ranges: empty
    (``first > last``), clipped at either end, wholly outside the cells (covering nothing: a range
    is intersected with the cells), single-cell, whole-path and ordinary ones, over cell counts
    that are and are not powers of two."""
    from research.interpolators._fir_candidate_kernels import _range_min_into

    def range_min(first, last, values, n, initial):
        out = np.array(initial, dtype=np.float64)
        _range_min_into(out, first.astype(np.int64), last.astype(np.int64), values.astype(np.float64))
        return out

    def brute(first, last, values, n, initial):
        out = np.array(initial, dtype=np.float64)
        for r in range(first.size):
            for k in range(n):
                if first[r] <= k <= last[r] and values[r] < out[k]:
                    out[k] = values[r]
        return out

    rng = np.random.default_rng(11)
    for n in (1, 2, 7, 16, 33, 100, 257):
        R = 60
        first = rng.integers(0, n, R)
        last = first + rng.integers(0, n, R)  # ordinary, some clipped at the right end
        kind = rng.integers(0, 6, R)
        first[kind == 1], last[kind == 1] = 0, n - 1  # whole path
        last[kind == 2] = first[kind == 2]  # single cell
        last[kind == 3] = first[kind == 3] - rng.integers(1, 4, np.sum(kind == 3))  # empty
        first[kind == 4] -= rng.integers(1, n + 3, np.sum(kind == 4))  # clipped at the left end
        out_of = kind == 5  # wholly outside the cells, left or right (empty once clipped)
        shift = np.where(rng.random(np.sum(out_of)) < 0.5, -(n + 5), n + 5)
        first[out_of] += shift
        last[out_of] = first[out_of] + rng.integers(0, 3, np.sum(out_of))
        values = rng.normal(size=R)
        initial = np.where(rng.random(n) < 0.3, np.inf, rng.normal(size=n) + 1.0)
        want = brute(first, last, values, n, initial)
        got = range_min(first, last, values, n, initial)
        np.testing.assert_array_equal(got, want)
        np.testing.assert_array_equal(range_min(first[:0], last[:0], values[:0], n, initial), initial)
    assert range_min(np.array([0]), np.array([3]), np.array([1.0]), 0, np.zeros(0)).shape == (0,)


@pytest.mark.parametrize("with_stops", [False, True])
def test_sample_charges_match_the_vectorised_rule(with_stops):
    """Distance, near corner, tolerance, violation, key and per-key maxima of path samples against
    the NumPy statement of the rule (the nearest of three squared distances; nearest corner instant
    within T_d / 2; lines charge their vertex, arcs their block; the samples within tolerance raise
    the maxima of the keys kept), with every key kept and with some; ``with_stops``: a third of the
    corners exact stops, by which a sample takes the block on its side of the corner instant."""
    from research.interpolators._fir_verify_kernels import charge_samples

    rng = np.random.default_rng(2)
    M, half = 40, 0.05
    centre = np.sort(rng.uniform(0.0, 4.0, M - 1))
    t = np.concatenate([np.sort(rng.uniform(-0.1, 4.1, 3000)), centre, [4.1]])
    block = rng.integers(0, M, t.size)
    tol = rng.uniform(0.01, 0.05, M)
    d2 = rng.uniform(0.0, 0.06, (t.size, 3)) ** 2
    arc = rng.random(M) < 0.3
    stopped = rng.random(M - 1) < 0.3 if with_stops else np.zeros(0, bool)
    dist = np.sqrt(d2.min(axis=1))
    k = np.clip(np.searchsorted(centre, t), 1, M - 1)
    j = np.where(np.abs(centre[k - 1] - t) <= np.abs(centre[np.minimum(k, M - 2)] - t), k - 1, np.minimum(k, M - 2))
    close = np.abs(centre[j] - t) <= half
    at_stop = close & (stopped[j] if with_stops else False)
    own = np.where(at_stop, np.where(t < centre[j], j, j + 1), block)  # the block whose tolerance and key
    close = close & ~at_stop
    want_limit = np.where(close, np.minimum(tol[own], np.minimum(tol[:-1], tol[1:])[j]), tol[own])
    want_key = np.where(close, j, np.where(~arc[own], np.clip(own, 0, M - 2), M - 1 + own))
    assert at_stop.any() == with_stops
    for redo, slack in ((np.zeros(0, bool), 0.0), (rng.random(2 * M - 1) < 0.5, 0.0), (np.zeros(0, bool), 3e-3)):
        # slack [mm]: the profile's own rounding, added to the bound (_fir_verify.profile_rounding)
        want_over = dist > (want_limit * (1 + 1e-9) + 1e-9) + slack
        assert close.any() and (~close).any() and (want_key >= M - 1).any() and want_over.any() and (~want_over).any()
        kept = np.ones(t.size, bool) if redo.size == 0 else redo[want_key]
        worst = np.full(2 * M - 1, -np.inf)
        near_max, over, o_dist, o_limit, o_key, o_keep, s_limit, s_key = charge_samples(
            t, d2, block, centre, tol, arc, half, redo, worst, slack, stopped)
        np.testing.assert_array_equal(s_limit, want_limit)
        np.testing.assert_array_equal(s_key, want_key)
        np.testing.assert_array_equal(over, np.flatnonzero(want_over))
        np.testing.assert_array_equal(o_dist, dist[want_over])
        np.testing.assert_array_equal(o_limit, want_limit[want_over])
        np.testing.assert_array_equal(o_key, want_key[want_over])
        np.testing.assert_array_equal(o_keep, kept[want_over])
        assert near_max == dist[~want_over].max()
        want_worst = np.full(2 * M - 1, -np.inf)
        np.maximum.at(want_worst, want_key[~want_over & kept], dist[~want_over & kept])
        np.testing.assert_array_equal(worst, want_worst)


def test_grid_times_are_the_numpy_runs():
    """The check's grid times in runs (``first[r] .. first[r] + count[r] - 1`` grid points, some
    runs empty), any chunk of them, against the NumPy gather of the run of each sample."""
    from research.interpolators._fir_verify_kernels import grid_times

    first = np.array([0, 7, 7, 30, 100], np.int64)
    count = np.array([5, 0, 12, 40, 3], np.int64)
    ends = np.cumsum(count)
    t0, t1, period = 0.25, 0.25 + 101 * 1e-3, 1e-3
    k = np.arange(ends[-1])
    run = np.searchsorted(ends, k, side="right")
    want = np.clip(t0 + (first[run] + (k - (ends[run] - count[run]))) * period, t0, t1)
    assert want[-1] == t1  # the last run reaches past the end: clipped
    for i, j in ((0, ends[-1]), (3, 20), (17, 17), (21, ends[-1])):
        np.testing.assert_array_equal(grid_times(i, j, first, count, np.ones_like(count), ends, t0, t1, period),
                                      want[i:j])


def numpy_staircase_cut(r_h, f_h, r_t, f_t, length, cap):
    """``_fir_lookahead.staircase_cut`` by whole-array NumPy (its form before the compiled loop):
    cut candidates sorted per line, allowed feeds per interval, the ``(B, n, n)`` piece costs and
    the first least ``a <= c`` of the flattened totals."""
    B = length.size
    x = np.sort(np.clip(np.concatenate([np.zeros((B, 1)), length[:, None], r_h, length[:, None] - r_t], axis=1),
                        0.0, length[:, None]), axis=1)
    n = x.shape[1]
    left, right = x[:, :-1], x[:, 1:]
    f_cov_h = np.min(np.where(r_h[:, None, :] >= right[:, :, None], f_h[:, None, :], np.inf), axis=2, initial=np.inf)
    f_cov_t = np.min(np.where((length[:, None] - r_t)[:, None, :] <= left[:, :, None], f_t[:, None, :], np.inf), axis=2,
                     initial=np.inf)
    allowed = np.where(right > left, np.maximum(np.minimum(np.minimum(f_cov_h, f_cov_t), cap[:, None]), 1e-300), np.inf)
    low = np.full((B, n, n), np.inf)
    for i in range(n - 1):
        low[:, i, i + 1:] = np.minimum.accumulate(allowed[:, i:], axis=1)
    span = x[:, None, :] - x[:, :, None]
    with np.errstate(invalid="ignore", divide="ignore"):
        cost = np.where(span > 0, span / low, 0.0)
    total = cost[:, 0, :, None] + cost + cost[:, None, :, n - 1]
    total = np.where(np.triu(np.ones((n, n), dtype=bool))[None], total, np.inf)
    a, c = np.divmod(np.argmin(total.reshape(B, -1), axis=1), n)
    rows = np.arange(B)
    xa, xc = x[rows, a], x[rows, c]
    feeds = np.stack([np.where(xa > 0, low[rows, 0, a], cap), np.where(xc > xa, low[rows, a, c], cap),
                      np.where(xc < length, low[rows, c, n - 1], cap)], axis=1)
    return xa / length, (length - xc) / length, np.minimum(feeds, cap[:, None])


def test_staircase_kernel_is_the_numpy_form_bit_for_bit():
    """Random staircases: reaches inside, beyond and at the line's ends, repeated reaches and
    feeds (ties between cuts), padding (reach 0, feed inf), feeds above the cap."""
    from research.interpolators._fir_lookahead import staircase_cut
    rng = np.random.default_rng(17)
    for H, T in ((1, 1), (3, 2), (4, 4), (2, 5)):
        B = 300
        length = rng.choice([0.1, 1.0, 5.0], B) * rng.uniform(0.5, 1.5, B)
        r_h = length[:, None] * rng.choice([0.0, 0.2, 0.5, 1.0, 1.3], (B, H)) * rng.choice([1.0, rng.uniform()], (B, H))
        r_t = length[:, None] * rng.choice([0.0, 0.3, 0.5, 1.0, 2.0], (B, T))
        f_h = np.where(r_h > 0, rng.choice([20.0, 50.0, 80.0, 150.0], (B, H)), np.inf)
        f_t = np.where(r_t > 0, rng.choice([20.0, 50.0, 90.0, 150.0], (B, T)), np.inf)
        cap = rng.choice([60.0, 100.0, 120.0], B)
        got = staircase_cut(r_h, f_h, r_t, f_t, length, cap)
        want = numpy_staircase_cut(r_h, f_h, r_t, f_t, length, cap)
        for g, w in zip(got, want):
            np.testing.assert_array_equal(g, w)


def _lookahead_candidates(seed, arcs, delays):
    """The look-ahead's candidates of a seeded random program, with what ``plan_fir`` times them by."""
    from research.interpolators._fir_lookahead import look_ahead
    from research.interpolators._fir_settle import _pulse_table
    from research.interpolators.fir import _as_toolpath
    from research.paths.library import random_program

    rng = np.random.default_rng(seed)
    tp = _as_toolpath(random_program(rng, arcs=arcs))
    eps, feed = float(np.exp(rng.uniform(np.log(0.005), np.log(0.5)))), float(rng.uniform(20.0, 300.0))
    M = tp.n_blocks
    t_in, t_out = tp.tangents()
    table = _pulse_table(tp)
    d = np.asarray(delays)
    cands = [c() for c, _ in look_ahead(tp, table, np.full(M, feed), np.ones(M), d, np.full(M - 1, eps), t_in, t_out,
                                          False)]
    return tp, table, feed, eps, d, t_in, t_out, cands


@pytest.mark.parametrize("turn", [False, True])
@pytest.mark.parametrize("delays", [(0.06, 0.03), (0.08,)])
@pytest.mark.parametrize("arcs", [False, True])
def test_predicted_cycle_matches_the_piece_arrays(delays, arcs, turn):
    """``predicted_cycle`` (one pass) against the cycle time summed from the arrays of
    ``PulseTable.pieces`` and ``_fir_profile.timing`` (eq 5 pulses, eq 13/14 overlaps), on the
    look-ahead's candidates of random programs with random overlap shrinks, for either corner
    speed (``plan_fir``'s ``corner_speed``)."""
    from research.interpolators import _fir_profile
    from research.interpolators._fir_candidate_kernels import predicted_cycle

    rng = np.random.default_rng(3)
    for seed in range(6):
        tp, table, feed, eps, d, t_in, t_out, cands = _lookahead_candidates(seed, arcs, delays)
        M, Mp = tp.n_blocks, table.m_pad
        lengths = np.concatenate([tp.lengths, np.ones(Mp - M + 1)])
        feeds = np.concatenate([np.full(M, feed), np.ones(Mp - M + 1)])
        ends = np.stack([np.pad(table.first_motion, (0, Mp - M)), np.pad(table.last_motion, (0, Mp - M))])
        tangents = np.stack([np.pad(t_in, ((0, Mp - M), (0, 0))), np.pad(t_out, ((0, Mp - M), (0, 0)))])
        tol_v = np.full(M - 1, eps)
        arc_of = np.full(table.block.size, -1)
        arc_of[table.arc_pieces] = np.arange(table.arc_pieces.size)
        ds = np.sort(d)[::-1]
        h_full = float(kernel_second_integral(np.array(0.5 * d.sum()), ds))
        for factor, head, tail, full, others, arc_rel in cands:
            shrink = np.where(rng.random(M - 1) < 0.3, rng.random(M - 1), 1.0)
            frac, pf = table.pieces(head, tail, factor, arc_rel)
            tv, ov = _fir_profile.timing(lengths, feeds, table.block, pf, ends, tangents, full, shrink, others, tol_v, d,
                                         turn)
            want = float(np.sum(frac * tv) + np.sum(d.sum() - ov) + d.sum())
            got = predicted_cycle(tp.lengths, np.full(M, feed), table.block, table.role, table.fraction, arc_of,
                                  arc_rel, factor, head, tail, table.first_motion, table.last_motion, t_in, t_out, full,
                                  shrink, others, tol_v, ds, h_full, turn)
            assert abs(got - want) <= 1e-12 * want, (seed, got, want)


def test_break_even_feed_inverts_the_slow_down_cost():
    """``_fir_lookahead._break_even_feed``: the slow-down cost ``min(f T_d, cap) (1 / f - 1 / F_v)``
    (its docstring's model, evaluated here) at the feed returned is the dwell cost asked for, on
    both sides of the stretch cap; the cost falls with the feed (so the feed is unique), and a cost
    of ``T_d`` or more gives 0."""
    from research.interpolators._fir_lookahead import _break_even_feed

    rng = np.random.default_rng(5)
    Td, n = 0.09, 2000
    cap, Fv = rng.uniform(0.001, 20.0, n), rng.uniform(5.0, 300.0, n)
    cost = rng.uniform(1e-6, Td * (1 - 1e-9), n)
    f = _break_even_feed(cap, Td, Fv, cost)

    def slow(f):
        return np.minimum(f * Td, cap) * (1.0 / f - 1.0 / Fv)

    assert np.all((f > 0) & (f < Fv))
    np.testing.assert_allclose(slow(f), cost, rtol=1e-9, atol=1e-15)
    assert np.any(f * Td <= cap) and np.any(f * Td > cap)  # both branches met
    assert np.all(slow(f * (1 - 1e-6)) > slow(f)) and np.all(slow(f * (1 + 1e-6)) < slow(f))
    assert np.all(_break_even_feed(cap, Td, Fv, np.full(n, Td)) == 0.0)


def test_dwell_is_cheaper_where_the_largest_feed_is_below_break_even():
    """``_fir_lookahead._dwell_cheaper``: the window error at the break-even feed against the
    tolerance, from the term-by-term sum (``slow_displacement``), False where a rule cannot dwell
    (NaN cost); and where the error grows with the feed (checked on a grid), the same answer as
    the window feed of ``largest_feed`` against the break-even feed, but where that feed lies
    within the search's stopping band of it."""
    from research.interpolators._fir_lookahead import _break_even_feed, _dwell_cheaper

    rng = np.random.default_rng(11)
    delays = np.array([0.06, 0.03])
    Td = float(delays.sum())
    T = 600
    s = np.cumsum(rng.uniform(0.05, 3.0, T))
    du = rng.normal(0.0, 0.05, (T, 2))
    chain = ChainError(s, du, delays)
    Fv = rng.uniform(20.0, 300.0, T)
    cap = rng.uniform(0.01, 5.0, T)
    tol = np.exp(rng.uniform(np.log(1e-4), np.log(0.05), T))
    costs = np.stack([np.where(rng.random(T) < 0.2, np.nan, rng.uniform(0.0, Td, T)), rng.uniform(0.0, Td, T)])
    got = _dwell_cheaper(chain, s, Fv, cap, Td, tol, costs)
    assert not np.any(got[np.isnan(costs)])
    agree = checked = 0
    for r in range(2):
        j = np.flatnonzero(~np.isnan(costs[r]))
        f_star = _break_even_feed(cap[j], Td, Fv[j], costs[r, j])
        e = np.linalg.norm(slow_displacement(s, du, delays, s[j], f_star), axis=1)
        np.testing.assert_array_equal(got[r, j], e > tol[j])
        f_w = chain.largest_feed(s[j], Fv[j], tol[j])
        grid = np.linspace(0.0, 1.0, 41)[1:]
        for i, jj in enumerate(j):
            errs = np.linalg.norm(slow_displacement(s, du, delays, np.full(grid.size, s[jj]), grid * Fv[jj]), axis=1)
            if np.all(np.diff(errs) >= 0) and abs(f_w[i] / f_star[i] - 1) > 1e-2:
                checked += 1
                agree += got[r, jj] == (f_w[i] < f_star[i])
    assert checked >= 200 and agree == checked


def numpy_line_pieces(h_blk, h_reach, h_feed, t_blk, t_reach, t_feed, L, body, F, arc):
    """``_fir_lookahead.line_pieces`` by whole-array NumPy (its form before the compiled pass)."""
    from research.interpolators._fir_lookahead import staircase_cut

    M = L.size
    n_h, n_t = np.bincount(h_blk, minlength=M), np.bincount(t_blk, minlength=M)
    r_h, f_h, r_t, f_t = np.zeros(M), np.full(M, np.inf), np.zeros(M), np.full(M, np.inf)
    np.maximum.at(r_h, h_blk, h_reach)
    np.minimum.at(f_h, h_blk, h_feed)
    np.maximum.at(r_t, t_blk, t_reach)
    np.minimum.at(f_t, t_blk, t_feed)
    b = np.minimum(body, F)
    # one window at each end (or none): the staircase has at most three steps
    a_cut = np.minimum(r_h, L - r_t)  # the head piece ends where the tail's reach begins, if earlier
    b_cut = np.maximum(L - r_t, r_h)
    head_f = np.minimum(np.where(a_cut > 0, f_h, b), b)
    mid_f = np.minimum(b, np.minimum(np.where(r_h + r_t > L, f_h, np.inf), np.where(r_h + r_t > L, f_t, np.inf)))
    tail_f = np.minimum(np.where(b_cut < L, f_t, b), b)
    head, tail = a_cut / L, (L - b_cut) / L
    feeds = np.stack([head_f, mid_f, tail_f], axis=1)
    multi = np.flatnonzero(~arc & ((n_h > 1) | (n_t > 1)))
    if multi.size:
        slot = np.full(M, -1)
        slot[multi] = np.arange(multi.size)
        head[multi], tail[multi], feeds[multi] = staircase_cut(
            _pad_rows(slot, h_blk, h_reach, 0.0), _pad_rows(slot, h_blk, h_feed, np.inf),
            _pad_rows(slot, t_blk, t_reach, 0.0), _pad_rows(slot, t_blk, t_feed, np.inf), L[multi], b[multi])
    feeds[arc] = F[arc, None]
    head[arc], tail[arc] = 0.0, 0.0
    # an empty end piece takes the feed of the nearest piece that is not: eq 13/14 reads a block's
    # entry and exit feeds from its first and last pieces
    mid = 1.0 - head - tail > 0
    h, m, t = feeds.T
    feeds = np.stack([np.where(head > 0, h, np.where(mid, m, t)), m, np.where(tail > 0, t, np.where(mid, m, h))], axis=1)
    return head, tail, feeds


def _pad_rows(slot, blk, values, fill):
    """``(B, K)`` rows of ``values`` grouped by ``slot[blk]`` (entries whose slot is -1 dropped),
    padded with ``fill``."""
    s = slot[blk]
    keep = s >= 0
    s, v = s[keep], values[keep]
    order = np.argsort(s, kind="stable")
    s, v = s[order], v[order]
    B = int(slot.max()) + 1
    count = np.bincount(s, minlength=B)
    rank = np.arange(s.size) - np.repeat(np.cumsum(count) - count, count)
    out = np.full((B, max(int(count.max(initial=0)), 1)), fill)
    out[s, rank] = v
    return out


def test_line_pieces_match_the_numpy_form():
    """``line_pieces`` (one compiled pass) against its whole-array NumPy form, bit for bit, on random
    windows: lines reached by none, one or several windows from either end (the staircase cuts),
    reaches beyond the line, arcs (untouched)."""
    from research.interpolators._fir_lookahead import line_pieces

    rng = np.random.default_rng(21)
    for _ in range(30):
        M = int(rng.integers(1, 40))
        L = rng.uniform(0.01, 5.0, M)
        F = rng.uniform(50.0, 300.0, M)
        arc = rng.random(M) < 0.2
        body = np.where(rng.random(M) < 0.3, rng.uniform(10.0, 300.0, M), F)
        nh, nt = int(rng.integers(0, 3 * M)), int(rng.integers(0, 3 * M))
        h = (rng.integers(0, M, nh), rng.uniform(0.0, 6.0, nh), rng.uniform(5.0, 300.0, nh))
        t = (rng.integers(0, M, nt), rng.uniform(0.0, 6.0, nt), rng.uniform(5.0, 300.0, nt))
        got = line_pieces(*h, *t, L, body, F, arc)
        want = numpy_line_pieces(*h, *t, L, body, F, arc)
        for g, w in zip(got, want):
            np.testing.assert_array_equal(g, w)
