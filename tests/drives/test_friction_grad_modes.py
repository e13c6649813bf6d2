"""Coulomb friction at reversal, gradients, structural modes and encoder models."""

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest
from scipy import signal

from research.drives import (
    ClosedLoopModel,
    Encoder,
    FlexibleMode,
    coulomb_sign,
    denominator_from_poles,
    measure,
    simulate,
    smooth_sign,
    table_6_1_closed_loop,
    table_6_1_ppi,
)
from tests.drives._helpers import make_trajectory, sine_trajectory

Ts = 1e-3


def test_sign_functions():
    v = jnp.array([-2.0, -1e-9, 0.0, 1e-9, 3.0])
    np.testing.assert_array_equal(coulomb_sign(v), [-1, -1, 0, 1, 1])
    s = smooth_sign(v, 0.01)
    assert float(s[2]) == 0.0 and float(s[0]) == pytest.approx(-1.0, abs=1e-12)
    assert float(jax.grad(lambda x: smooth_sign(x, 0.5))(0.0)) == pytest.approx(2.0)


def test_friction_before_reversal_is_a_step_through_the_disturbance_tf():
    """Moving at +V from sample 0, friction is the constant +dc, so the position deficit against the
    friction-free run is dc times the ZOH step response of G_dist = s/(s^3 + a1 s^2 + a2 s + a3)."""
    m = table_6_1_closed_loop()
    m0 = ClosedLoopModel(m.a1, m.a2, m.a3, m.b0, m.b1, m.b2, 0.0)
    n, V = 600, 20.0
    t = np.arange(n) * Ts
    tr = make_trajectory(V * t, Ts, v=np.full(n, V))
    diff = np.asarray(simulate(m, tr).position - simulate(m0, tr).position)[:, 0]
    den = [1.0, float(m.a1), float(m.a2), float(m.a3)]
    Ad, Bd, Cd, Dd, _ = signal.cont2discrete(signal.tf2ss([1.0, 0.0], den), Ts, method="zoh")
    _, step, _ = signal.dlsim((Ad, Bd, Cd, Dd, Ts), np.ones(n))
    np.testing.assert_allclose(diff, -float(m.dc) * step[:, 0], rtol=1e-6, atol=1e-12)


def test_friction_flips_with_actual_velocity_at_reversal():
    """Sinusoidal motion: the friction disturbance is dc sign(x') of the *actual* velocity at every
    sample, flips exactly once per reversal, and lags the reference reversal (the drive lags)."""
    m = table_6_1_closed_loop()
    tr = sine_trajectory(2.0, 1.0, 2000, Ts)  # reversals at t = 0.25, 0.75, 1.25, 1.75 s
    res = simulate(m, tr)
    fr, vel = np.asarray(res.friction[:, 0]), np.asarray(res.velocity[:, 0])
    np.testing.assert_array_equal(fr, float(m.dc) * np.sign(vel))
    flips = np.flatnonzero(np.diff(np.sign(fr[1:])) != 0) + 1
    assert len(flips) == 4
    t_rev = np.array([0.25, 0.75, 1.25, 1.75])
    lag = flips * Ts - t_rev
    assert np.all(lag >= 0) and np.all(lag < 0.02)
    # superposition: the position deficit is the ZOH disturbance response to the friction sequence
    m0 = ClosedLoopModel(m.a1, m.a2, m.a3, m.b0, m.b1, m.b2, 0.0)
    d = np.asarray(simulate(m0, tr).position - res.position)[:, 0]
    den = [1.0, float(m.a1), float(m.a2), float(m.a3)]
    Ad, Bd, Cd, Dd, _ = signal.cont2discrete(signal.tf2ss([1.0, 0.0], den), Ts, method="zoh")
    _, resp, _ = signal.dlsim((Ad, Bd, Cd, Dd, Ts), fr)
    np.testing.assert_allclose(d, resp[:, 0], rtol=1e-6, atol=1e-12)
    # friction opposes the new motion: just after each flip the axis is pushed against its velocity
    for f in flips:
        assert np.all(np.sign(d[f + 2:f + 20]) == np.sign(vel[f + 2:f + 20]))


def test_friction_feedforward_cancels_friction_away_from_reversals():
    ppi = table_6_1_ppi()
    ppi_ff = eqx.tree_at(lambda p: p.friction_ff, ppi, jnp.asarray(1.0))
    tr = sine_trajectory(2.0, 1.0, 2000, Ts)
    res = simulate(ppi_ff, tr)
    nonzero = np.flatnonzero(np.asarray(res.friction[:, 0]) != 0)
    # residual friction only in the few samples where actual and reference velocity differ in sign
    assert 0 < nonzero.size < 40
    assert float(ppi_ff.closed_loop_model().dc) == 0.0


def test_smooth_friction_converges_to_exact():
    m = table_6_1_closed_loop()
    tr = sine_trajectory(2.0, 1.0, 1000, Ts)
    exact = np.asarray(simulate(m, tr).position)
    errs = [np.max(np.abs(np.asarray(simulate(m, tr, friction="smooth", friction_width=w).position) - exact))
            for w in (1.0, 0.01)]
    assert errs[1] < errs[0] and errs[1] < 1e-6


def _loss(params, tr):
    a1, b1, dc = params
    base = table_6_1_closed_loop()
    m = ClosedLoopModel(a1, base.a2, base.a3, base.b0, b1, base.b2, dc)
    res = simulate(m, tr, friction="smooth", friction_width=0.5)
    return jnp.sum(res.tracking_error**2) * Ts


def test_grad_of_tracking_loss_matches_finite_differences():
    tr = sine_trajectory(2.0, 1.0, 600, Ts)
    p0 = jnp.array([238.4335, 117.5424, 200.0])
    g = np.asarray(jax.grad(_loss)(p0, tr))
    for k in range(3):
        h = 1e-6 * float(p0[k])
        e = jnp.zeros(3).at[k].set(h)
        fd = (float(_loss(p0 + e, tr)) - float(_loss(p0 - e, tr))) / (2 * h)
        assert g[k] == pytest.approx(fd, rel=1e-5), k
    assert np.all(g != 0)


def test_grad_through_physical_ppi_gains():
    tr = sine_trajectory(2.0, 1.0, 400, Ts)
    ppi = table_6_1_ppi()

    def loss(kp):
        m = eqx.tree_at(lambda p: p.Kp, ppi, kp)
        return jnp.sum(simulate(m, tr, friction="smooth").tracking_error ** 2)

    kp = ppi.Kp
    g = float(jax.grad(loss)(kp))
    h = 1e-6 * float(kp)
    fd = (float(loss(kp + h)) - float(loss(kp - h))) / (2 * h)
    assert g == pytest.approx(fd, rel=1e-5)


def test_flexible_mode_residual_vibration_frequency_and_decay():
    """After a fast move stops, the beam rings at wn sqrt(1 - zeta^2) and decays as exp(-zeta wn t)."""
    mode = FlexibleMode.from_hz(11.4, 0.02)  # Sencer 2015 §4 X beam, assumed 2 % damping
    n = 3000
    t = np.arange(n) * Ts
    T = 0.1  # quintic rest-to-rest move of 10 mm in 0.1 s, then rest
    s = np.clip(t / T, 0, 1)
    q = 10 * (10 * s**3 - 15 * s**4 + 6 * s**5)
    v = 10 * (30 * s**2 - 60 * s**3 + 30 * s**4) / T
    a = 10 * (60 * s - 180 * s**2 + 120 * s**3) / T**2
    j = 10 * (60 - 360 * s + 360 * s**2) / T**3 * (t <= T)
    res = simulate(table_6_1_closed_loop(), make_trajectory(q, Ts, v, a, j), modes=mode)
    d = np.asarray(res.deflection[:, 0])
    tail = d[1000:]
    assert np.max(np.abs(tail)) > 1e-3  # the move leaves residual vibration
    zc = np.flatnonzero(np.diff(np.sign(tail)) > 0)
    period = np.mean(np.diff(zc)) * Ts
    wd = 2 * np.pi * 11.4 * np.sqrt(1 - 0.02**2)
    assert 2 * np.pi / period == pytest.approx(wd, rel=2e-3)
    peaks = [np.max(np.abs(tail[i * 500:(i + 1) * 500])) for i in range(3)]
    ratio = peaks[1] / peaks[0]
    assert ratio == pytest.approx(np.exp(-0.02 * 2 * np.pi * 11.4 * 0.5), rel=0.05)
    # no mode -> no deflection output
    assert simulate(table_6_1_closed_loop(), make_trajectory(q, Ts, v, a, j)).deflection is None


def test_flexible_mode_steady_state_matches_its_frequency_response():
    """With perfect tracking (b = a, G_track = 1) the axis acceleration is the reference's, so the
    beam's steady deflection amplitude is |delta/x''(j w)| A w^2 (Sencer 2015 Y beam, 6.8 Hz)."""
    mode = FlexibleMode.from_hz(6.8, 0.03)
    a1, a2, a3 = denominator_from_poles(2 * np.pi * 60, 0.7, 2 * np.pi * 40)
    perfect = ClosedLoopModel(a1, a2, a3, 1.0, a1, a2, 0.0)
    f, amp = 5.0, 0.1
    res = simulate(perfect, sine_trajectory(amp, f, 8000, Ts), modes=mode)
    np.testing.assert_allclose(res.position, res.reference, atol=1e-7)  # cubic hold of a sine: O((w Ts)^4)
    expected = abs(complex(mode.frequency_response(f))) * amp * (2 * np.pi * f) ** 2
    d = np.asarray(res.deflection[6000:, 0])
    assert np.max(np.abs(d)) == pytest.approx(expected, rel=2e-3)


def test_encoder_quantization_and_seeded_noise():
    x = jnp.linspace(-1.0, 1.0, 1001)[:, None]
    enc = Encoder(resolution=2.9e-3)
    y = np.asarray(measure(enc, x, seed=0))
    assert np.max(np.abs(y - np.asarray(x))) <= 2.9e-3 / 2 + 1e-15
    np.testing.assert_allclose(y / 2.9e-3, np.round(y / 2.9e-3), atol=1e-9)
    noisy = Encoder(resolution=0.0, noise_std=1e-3)
    a, b, c = (np.asarray(measure(noisy, jnp.zeros((20000, 1)), seed=s)) for s in (1, 1, 2))
    np.testing.assert_array_equal(a, b)
    assert not np.array_equal(a, c)
    assert np.std(a) == pytest.approx(1e-3, rel=0.03)
