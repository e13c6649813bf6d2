"""Residual vibration of a lightly damped, base-excited structural mode once the motion has stopped
(the beams of Sencer 2015 §4): ``d'' + 2 zeta wn d' + wn^2 d = -x''``. After the excitation ends at
``t_e`` the mode rings freely with complex amplitude ``B = int x''(tau) exp(lam (t_e - tau)) d tau``,
``lam = -zeta wn + j wn sqrt(1 - zeta^2)``, and envelope ``|B| / w_d`` [mm].

- :func:`residual_vibration_sampled`: any sampled acceleration (trapezoid rule);
- :func:`fir_pulse_residual`: the closed form for an FIR-filtered train of velocity pulses,
  ``B = sum_m dv_m exp(lam (t_last - t_m)) prod_i (exp(lam T_i) - 1) / (lam T_i)`` (eq 8 at ``w = wn``
  when ``zeta -> 0``, zero at ``T_i = k / f``, eq 10), differentiable and ``jax.vmap``-able.
"""

from __future__ import annotations

import jax.numpy as jnp
import numpy as np
from jax import Array


def residual_vibration_sampled(t, acceleration, frequency_hz: float, damping: float) -> float:
    """Envelope [mm] of a mode's free vibration after a sampled acceleration [mm/s^2] ends.

    Args:
        t: ``(N,)`` sample times [s]; the excitation ends at ``t[-1]``.
        acceleration: ``(N,)`` the axis acceleration exciting the mode [mm/s^2].
        frequency_hz: natural frequency [Hz]; damping: ratio [-] (0 < zeta < 1).
    Returns:
        ``|B| / w_d`` [mm], ``B`` by the trapezoid rule (error ``O((wn Ts)^2)``).
    """
    t, a = np.asarray(t, dtype=np.float64), np.asarray(acceleration, dtype=np.float64)
    wn = 2 * np.pi * frequency_hz
    wd = wn * np.sqrt(1 - damping**2)
    lam = -damping * wn + 1j * wd
    return float(abs(np.trapezoid(a * np.exp(lam * (t[-1] - t)), t)) / wd)


def fir_pulse_residual(velocity_steps: Array, starts: Array, ends: Array, last, delays: Array, frequency_hz: Array,
                       damping: Array) -> Array:
    """Residual vibration envelopes [mm] after a train of velocity pulses filtered by an FIR chain.

    Args:
        velocity_steps: ``(K, M)`` velocity of pulse ``m`` along the axis exciting mode ``k`` [mm/s].
        starts, ends: ``(M,)`` pulse edges [s]; last: the last pulse's end [s] (motion ends at ``last + T_d``).
        delays: ``(n,)`` FIR delays ``T_i`` [s].
        frequency_hz, damping: ``(K,)`` the modes [Hz, -].
    Returns:
        ``(K,)`` envelopes ``|B| / w_d`` [mm] (empty when ``K = 0``).
    """
    if frequency_hz.shape[0] == 0:
        return jnp.zeros(0)
    wn = 2 * jnp.pi * frequency_hz
    wd = wn * jnp.sqrt(1.0 - damping**2)
    lam = (-damping * wn + 1j * wd)[:, None]  # (K, 1)
    filt = jnp.prod(jnp.expm1(lam * delays[None, :]) / (lam * delays[None, :]), axis=1)  # (K,)
    edges = jnp.exp(lam * (last - starts)[None, :]) - jnp.exp(lam * (last - ends)[None, :])  # (K, M)
    return jnp.abs(jnp.sum(velocity_steps * edges, axis=1) * filt) / wd
