"""Frequency responses of the tracking and disturbance transfer functions (thesis eq 6.1, Fig 6.7) and a
pole/zero/damping report (thesis Table 6.3 layout)."""

from __future__ import annotations

import dataclasses

import equinox as eqx
import jax.numpy as jnp
import numpy as np
from jax import Array

from research.drives._controllers import PIDController, PPICascade


class FrequencyResponse(eqx.Module):
    """Complex frequency responses at ``s = j 2 pi f``.

    Attributes:
        frequency: ``f`` [Hz], ``(F,)``.
        tracking: ``G_track = x / x_r`` [mm/mm], ``(F,)``.
        disturbance: ``G_dist = x / w`` per unit friction input: [mm/(mm/s^2)] for eq 6.3 models,
            [mm/(N m)] for P-PI/PID models (eq 6.1 includes the factor ``rg/J``).
    """

    frequency: Array
    tracking: Array
    disturbance: Array

    def magnitude_db(self) -> tuple[Array, Array]:
        """``20 log10 |G|`` of the tracking and disturbance responses [dB]."""
        return 20 * jnp.log10(jnp.abs(self.tracking)), 20 * jnp.log10(jnp.abs(self.disturbance))

    def phase_deg(self) -> tuple[Array, Array]:
        """Unwrapped phases of the tracking and disturbance responses [deg]."""
        return (
            jnp.degrees(jnp.unwrap(jnp.angle(self.tracking))),
            jnp.degrees(jnp.unwrap(jnp.angle(self.disturbance))),
        )


def _disturbance_gain(model):
    """Factor from the model's friction unit to the eq 6.3 unit [mm/s^2]: ``rg/J`` for physical models."""
    if isinstance(model, (PPICascade, PIDController)):
        return model.plant.rg / model.plant.J
    return 1.0


def frequency_response(model, frequency_hz) -> FrequencyResponse:
    """Tracking and disturbance frequency responses of a drive model (eq 6.1).

    Args:
        model: :class:`ClosedLoopModel`, :class:`PPICascade` or :class:`PIDController`.
        frequency_hz: frequencies [Hz].
    Returns:
        :class:`FrequencyResponse`; differentiable in the model parameters.
    """
    cl = model.closed_loop_model()
    f = jnp.asarray(frequency_hz, dtype=jnp.float64)
    s = 2j * jnp.pi * f
    den = jnp.polyval(cl.denominator, s)
    track = jnp.polyval(cl.tracking_numerator, s) / den
    dist = _disturbance_gain(model) * jnp.polyval(cl.disturbance_numerator, s) / den
    return FrequencyResponse(f, track, dist)


def _frequency_damping(roots):
    roots = np.asarray(roots, dtype=np.complex128)
    w = np.abs(roots)
    zeta = np.where(w > 0, -roots.real / np.where(w > 0, w, 1.0), 1.0)
    return w / (2 * np.pi), zeta


@dataclasses.dataclass(frozen=True)
class PoleZeroReport:
    """Poles, zeros and their frequencies and damping (thesis Table 6.3 layout).

    Attributes:
        poles, zeros: roots [rad/s] of the closed-loop denominator and of the tracking numerator.
        pole_frequency_hz, pole_damping: ``|p|/(2 pi)`` [Hz] and ``-Re(p)/|p|`` per pole.
        zero_frequency_hz, zero_damping: the same for the zeros (a right-half-plane real zero has -1).
        natural_frequency_hz, damping, real_pole_hz: ``(wn, zeta, p)`` of eq 6.13 [Hz, -, Hz].
        stable: all poles in the open left half plane.
    """

    poles: np.ndarray
    zeros: np.ndarray
    pole_frequency_hz: np.ndarray
    pole_damping: np.ndarray
    zero_frequency_hz: np.ndarray
    zero_damping: np.ndarray
    natural_frequency_hz: float
    damping: float
    real_pole_hz: float
    stable: bool

    def __str__(self) -> str:
        rows = [f"wn = {self.natural_frequency_hz:.4g} Hz, zeta = {self.damping:.3g}, p = {self.real_pole_hz:.4g} Hz"
                f" ({'stable' if self.stable else 'UNSTABLE'})"]
        for kind, r, f, z in (("p", self.poles, self.pole_frequency_hz, self.pole_damping),
                              ("z", self.zeros, self.zero_frequency_hz, self.zero_damping)):
            for i, (ri, fi, zi) in enumerate(zip(r, f, z), 1):
                rows.append(f"{kind}{i}: {ri.real:12.5g} {ri.imag:+12.5g}j rad/s  {fi:9.4g} Hz  damping {zi:7.3g}")
        return "\n".join(rows)


def pole_zero_report(model) -> PoleZeroReport:
    """Pole/zero/damping report of the closed-loop tracking transfer function of ``model``."""
    cl = model.closed_loop_model()
    poles, zeros = cl.poles(), cl.zeros()
    order_p, order_z = np.argsort(-np.abs(poles), kind="stable"), np.argsort(-np.abs(zeros), kind="stable")
    poles, zeros = poles[order_p], zeros[order_z]
    pf, pz = _frequency_damping(poles)
    zf, zz = _frequency_damping(zeros)
    wn, zeta, p = cl.pole_parameters()
    return PoleZeroReport(poles, zeros, pf, pz, zf, zz, wn / (2 * np.pi), zeta, p / (2 * np.pi), bool(np.all(poles.real < 0)))
