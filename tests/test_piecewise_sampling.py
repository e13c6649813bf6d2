"""One-pass grid sampling (research/_grid_sample.py) against the per-order evaluation it replaces.

The reference is :class:`research.piecewise.NumpyPiecewise`, evaluated once per derivative order
with its own piece search (``searchsorted`` on ``t + snap``) and the snap of DESIGN.md (grid
sampling takes right-hand limits with a 1e-9 Ts snap) -- an independent locate-and-Horner path, the
one ``PiecewisePolynomial.sample`` used for up to 5e4 samples before the kernel. Agreement asked:
max |difference| <= 1e-12 relative to each order's largest magnitude (issue 19 item 5).
"""

import jax.numpy as jnp
import numpy as np
import pytest

from research.errors import ParameterError
from research.interpolators.fir import plan_fir
from research.paths import named_path
from research.piecewise import GRID_SNAP, NumpyPiecewise, PiecewisePolynomial
from research.trajectory import Trajectory

REL = 1e-12


def per_order(breaks, coeffs, Ts, n, orders):
    ev = NumpyPiecewise(np.asarray(breaks, float), np.asarray(coeffs, float))
    t = breaks[0] + np.arange(n) * Ts
    return [ev(t, nu, snap=GRID_SNAP * Ts) for nu in range(orders)]


def assert_same(new, ref):
    for nu, (x, r) in enumerate(zip(new, ref)):
        scale = max(1.0, float(np.max(np.abs(r))))
        err = float(np.max(np.abs(np.asarray(x) - r)))
        assert err <= REL * scale, f"order {nu}: max |diff| {err:.3e} > {REL:g} x {scale:.3e}"


def random_profile(rng, K, degree, A, Ts):
    """Random breaks (some zero-length pieces, some on the grid up to +-rounding) and coefficients."""
    h = rng.uniform(0.0, 7.3 * Ts, K)
    h[rng.random(K) < 0.1] = 0.0
    breaks = rng.uniform(-1.0, 1.0) + np.concatenate([[0.0], np.cumsum(h)])
    on_grid = rng.random(K + 1) < 0.2
    on_grid[0] = False
    k = np.round((breaks - breaks[0]) / Ts)
    jitter = rng.choice([0.0, 1e-16, -1e-16, 3e-13 * Ts], K + 1)
    breaks = np.where(on_grid, breaks[0] + k * Ts + jitter, breaks)
    breaks = np.maximum.accumulate(breaks)
    coeffs = rng.normal(size=(K, degree + 1, A)) * 10.0 ** rng.uniform(-2, 3, (1, degree + 1, 1))
    return breaks, coeffs


@pytest.mark.parametrize("seed", range(6))
def test_random_piecewise_matches_per_order(seed):
    rng = np.random.default_rng(seed)
    Ts = rng.choice([1e-3, 2.5e-4, 1 / 3000])
    K, degree, A = int(rng.integers(1, 400)), int(rng.integers(0, 6)), int(rng.integers(1, 4))
    breaks, coeffs = random_profile(rng, K, degree, A, Ts)
    # the grid runs past the end: samples after breaks[-1] hold the value, derivatives are zero
    n = int((breaks[-1] - breaks[0]) / Ts) + int(rng.integers(1, 20))
    orders = int(rng.integers(1, 6))
    pp = PiecewisePolynomial(jnp.asarray(breaks), jnp.asarray(coeffs))
    new = pp.sample(Ts, n, orders=orders)
    assert len(new) == orders and all(x.shape == (n, A) for x in new)
    assert_same(new, per_order(breaks, coeffs, Ts, n, orders))
    if orders > 1:
        assert np.all(new[1][breaks[0] + np.arange(n) * Ts > breaks[-1]] == 0.0)


def test_planned_fir_trajectory_matches_per_order():
    """A planned FIR profile (corner90, Sencer 2015 delays 148/89 ms) sampled at 1 ms, and the
    Trajectory built from it (same samples, no per-sample re-check)."""
    plan = plan_fir(named_path("corner90"), 200.0, [0.148, 0.089], 0.05)
    Ts = 1e-3
    tr = plan.trajectory(Ts)
    breaks, coeffs = np.asarray(plan.position.breaks), np.asarray(plan.position.coeffs)
    n = tr.n_samples
    assert_same((tr.q, tr.v, tr.a, tr.j), per_order(breaks, coeffs, Ts, n, 4))
    np.testing.assert_allclose(tr.q[-1], named_path("corner90").points[-1], atol=1e-9)


def test_from_piecewise_rejects_non_finite_profile():
    breaks = jnp.array([0.0, 0.01, 0.02])
    coeffs = np.zeros((2, 2, 2))
    coeffs[1, 1, 0] = np.nan
    with pytest.raises(ParameterError, match="coeffs not finite at index \\(1, 1, 0\\)"):
        Trajectory.from_piecewise(PiecewisePolynomial(breaks, jnp.asarray(coeffs)), 1e-3, ("x", "y"))
    with pytest.raises(ParameterError, match="2 channels"):
        Trajectory.from_piecewise(PiecewisePolynomial(breaks, jnp.zeros((2, 2, 2))), 1e-3, ("x", "y", "z"))


def test_sampling_memory_is_its_output_and_the_break_indices():
    """The sampler holds no per-piece table: sampling a 20,000-piece cubic profile on 20,000 samples
    for four orders peaks (traced) at the ``(4, N, 3)`` output plus four doubles a piece (the
    first-sample indices and the temporaries that compute them from the breaks), + 64 kB -- where a
    ``(K, orders, d + 1, A)`` table of derivative coefficients was 4x the profile (7.7 MB here,
    against a 1.9 MB output: 11.7 MB traced)."""
    import tracemalloc

    from research._grid_sample import sample_grid

    rng = np.random.default_rng(5)
    K, N, Ts = 20000, 20000, 1e-3
    breaks = np.concatenate([[0.0], np.cumsum(rng.uniform(0.1, 1.9, K) * Ts)])
    coeffs = rng.normal(size=(K, 4, 3))
    sample_grid(breaks[:3], coeffs[:2], Ts, 4, 4)  # compiled
    tracemalloc.start()
    try:
        out = sample_grid(breaks, coeffs, Ts, N, 4)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert peak <= out.nbytes + 4 * 8 * (K + 1) + 64e3, (peak, out.nbytes)
    assert_same(tuple(out), per_order(breaks, coeffs, Ts, N, 4))
