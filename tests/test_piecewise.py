"""PiecewisePolynomial: exact moving average, antiderivative, evaluation and uniform sampling."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from research.piecewise import PiecewisePolynomial


def box_pulse():
    return PiecewisePolynomial.from_steps(jnp.array([0.0, 0.5]), jnp.array([[2.0]]))


def test_moving_average_of_pulse_is_trapezoid():
    """Sencer 2015 eq 4: a pulse v of length T_v through one filter T_1 is a trapezoid."""
    v = box_pulse().moving_average(0.2)
    t = np.array([0.0, 0.1, 0.2, 0.35, 0.5, 0.6, 0.7, 0.8])
    expected = [0.0, 1.0, 2.0, 2.0, 2.0, 1.0, 0.0, 0.0]
    np.testing.assert_allclose(np.asarray(v(t))[:, 0], expected, atol=1e-14)
    np.testing.assert_allclose(np.asarray(v(np.array([0.1]), nu=1)), [[10.0]])  # a_max = v / T_1


def test_moving_average_matches_numerical_average():
    """Three filters with incommensurate delays against brute-force quadrature."""
    x = PiecewisePolynomial.from_steps(jnp.array([0.0, 0.3, 0.31, 1.0]), jnp.array([[1.0, -1.0], [0.0, 0.0], [-2.0, 0.5]]))
    y = x
    delays = (0.137, 0.0711, 0.0231)
    for T in delays:
        y = y.moving_average(T)
    # brute force: iterate running means on a fine grid
    dt = 1e-6
    t = np.arange(0, 1.5, dt)
    z = np.where((t <= 1.0)[:, None], np.asarray(x(t)), 0.0)  # moving_average treats x as 0 outside
    for T in delays:
        c = np.vstack([np.zeros((1, 2)), np.cumsum(z, axis=0) * dt])
        lag = np.interp(t - T, np.concatenate([t, [t[-1] + dt]]), np.arange(len(t) + 1), left=0)
        lo = np.floor(lag).astype(int)
        frac = lag - lo
        c_lag = c[lo] * (1 - frac)[:, None] + c[np.minimum(lo + 1, len(t))] * frac[:, None]
        z = (c[1:] - c_lag) / T
    probe = np.array([0.05, 0.2, 0.33, 0.6, 1.1, 1.2])
    np.testing.assert_allclose(np.asarray(y(probe)), z[(probe / dt).astype(int)], atol=2e-4)  # brute force is first order in dt


def test_antiderivative_and_end_values():
    p = box_pulse().antiderivative(3.0)
    assert float(p(jnp.array([0.25]))[0, 0]) == pytest.approx(3.5)
    assert float(p.end_values()[0]) == pytest.approx(4.0)
    assert float(p(jnp.array([10.0]))[0, 0]) == pytest.approx(4.0)  # held after the end
    assert float(p(jnp.array([10.0]), nu=1)[0, 0]) == 0.0  # at rest after the end


def test_sample_matches_evaluate():
    y = box_pulse().moving_average(0.0731).moving_average(0.0333).antiderivative(0.0)
    n = 700
    samples = np.asarray(y.sample(1e-3, n, orders=4))
    t = np.arange(n) * 1e-3
    for nu in range(3):
        np.testing.assert_allclose(samples[nu], np.asarray(y(t, nu)), atol=1e-9)


def test_grad_through_breaks():
    """d/dT of the filtered position at a fixed time, against central differences."""

    def f(T):
        return box_pulse().moving_average(T).antiderivative()(jnp.array([0.55]))[0, 0]

    h = 1e-7
    assert float(jax.grad(f)(0.2)) == pytest.approx(float((f(0.2 + h) - f(0.2 - h)) / (2 * h)), rel=1e-6)


@pytest.mark.parametrize("n_samples", [100, 60_000])
def test_sample_takes_the_new_phase_at_a_break_rounded_past_the_grid(n_samples):
    """A jerk step whose break lands 1e-13 s after sample 30 (a break 'on the grid' up to rounding)
    is sampled as on it: sample 30 has the new value, as for a break exactly on the grid. A break
    1e-6 Ts after the sample is a real one and is left alone."""
    Ts = 1e-3
    for shift, expected in ((1e-13, -1.0), (0.0, -1.0), (1e-9, 1.0)):
        pp = PiecewisePolynomial.from_steps(jnp.array([0.0, 30 * Ts + shift, n_samples * Ts]), jnp.array([[1.0], [-1.0]]))
        (jerk,) = pp.sample(Ts, n_samples, orders=1)
        assert jerk[29, 0] == 1.0 and jerk[31, 0] == -1.0
        assert jerk[30, 0] == expected, shift


def _numpy_reference(breaks, coeffs, t, nu, snap):
    """Evaluation by NumPy array operations, written out independently of the compiled kernel:
    clip to ``[b_0, b_K]``, ``searchsorted(side="right")`` for the piece, Horner's rule on
    ``c_m m! / (m - nu)!`` in the local time; derivatives zero outside ``[b_0, b_K]``."""
    import math

    K, D = coeffs.shape[0], coeffs.shape[1]
    if nu >= D:
        return np.zeros((t.size, coeffs.shape[2]))
    clipped = np.clip(t, breaks[0], breaks[-1])
    piece = np.clip(np.searchsorted(breaks, clipped + snap, side="right") - 1, 0, K - 1)
    tau = (clipped - breaks[piece])[:, None]
    c = coeffs[piece]
    value = c[:, D - 1, :] * math.perm(D - 1, nu)
    for m in range(D - 2, nu - 1, -1):
        value = value * tau + c[:, m, :] * math.perm(m, nu)
    if nu:
        value = np.where(((t >= breaks[0]) & (t <= breaks[-1]))[:, None], value, 0.0)
    return value


@pytest.mark.parametrize("seed", range(6))
def test_numpy_evaluator_matches_array_evaluation_bit_for_bit(seed):
    """``NumpyPiecewise`` (one compiled pass, ``research._piecewise_eval``) against the NumPy array
    form above on random profiles with zero-length pieces, at times inside, on and outside the
    breaks (and NaN), for every derivative order up to one above the degree and with a snap: the
    same operations in the same order, so the same bits."""
    from research.piecewise import NumpyPiecewise

    rng = np.random.default_rng(seed)
    K, D, A = int(rng.integers(1, 40)), int(rng.integers(1, 6)), int(rng.integers(1, 4))
    steps = rng.exponential(1.0, K) * (rng.random(K) > 0.2)  # some pieces of zero length
    breaks = np.concatenate([[rng.normal()], rng.normal() + np.cumsum(steps)])
    breaks = np.maximum.accumulate(breaks)
    coeffs = rng.normal(size=(K, D, A)) * 10.0 ** rng.integers(-3, 4, size=(K, D, A))
    t = np.concatenate([rng.uniform(breaks[0] - 1.0, breaks[-1] + 1.0, 500), breaks, breaks + 1e-13,
                        breaks - 1e-13, [np.nan]])
    ev = NumpyPiecewise(breaks, coeffs)
    for nu in range(D + 1):
        for snap in (0.0, 1e-12):
            got = ev(t, nu, snap)
            want = _numpy_reference(breaks, coeffs, t, nu, snap)
            assert got.shape == (t.size, A)
            np.testing.assert_array_equal(got, want)
    assert ev(t.reshape(-1, 1), 0).shape == (t.size, 1, A)
