"""The general closed-loop axis model of Sencer (2009) thesis eq 6.1-6.3 and the pole map eq 6.13.

Eq 6.3 (with the Coulomb friction of eq 6.2)::

    (s^2 + a1 s + a2 + a3/s) x = (b0 s^2 + b1 s + b2 + a3/s) x_r - d_c sign(x'),

i.e. ``G_track(s) = (b0 s^3 + b1 s^2 + b2 s + a3) / (s^3 + a1 s^2 + a2 s + a3)`` and
``G_dist(s) = s / (s^3 + a1 s^2 + a2 s + a3)`` (Fig 6.2). Seven parameters: three poles (a1..a3), three
zeros (b0..b2, with unity DC gain built in) and the average Coulomb friction d_c.
"""

from __future__ import annotations

import equinox as eqx
import jax.numpy as jnp
import numpy as np
from jax import Array

from research.drives._realization import Realization
from research.drives._validation import check_finite, check_nonnegative, is_concrete
from research.errors import ParameterError


def denominator_from_poles(natural_frequency, damping, real_pole):
    """Thesis eq 6.13: ``s^3 + a1 s^2 + a2 s + a3 = (s + p)(s^2 + 2 zeta wn s + wn^2)``.

    Args:
        natural_frequency: ``wn`` of the complex pair [rad/s].
        damping: ``zeta`` [-] of the pair (``zeta > 1`` gives two real poles, as the thesis' PSO allows).
        real_pole: ``p`` [rad/s], the overdamped pole sits at ``s = -p``.
    Returns:
        ``(a1, a2, a3)`` in [1/s], [1/s^2], [1/s^3].
    """
    wn, z, p = natural_frequency, damping, real_pole
    return p + 2 * z * wn, wn**2 + 2 * z * wn * p, p * wn**2


class ClosedLoopModel(eqx.Module):
    """Closed-loop axis dynamics, thesis eq 6.1/6.3 (Fig 6.2).

    Attributes:
        a1, a2, a3: denominator coefficients [1/s], [1/s^2], [1/s^3] (eq 6.3).
        b0, b1, b2: numerator coefficients [-], [1/s], [1/s^2] (eq 6.3); the constant term is a3.
        dc: average Coulomb friction amplitude in the units of eq 6.3, [mm/s^2] (rad/s^2 for rotary axes).

    The tracking transfer function is x/x_r, the disturbance transfer function is x/w for the friction
    input ``w = d_c sign(x')`` (both eq 6.1). Stability is not enforced here (identified models may be
    unstable); :func:`research.drives.simulate` and :meth:`check_stable` reject unstable ones.
    """

    a1: Array
    a2: Array
    a3: Array
    b0: Array
    b1: Array
    b2: Array
    dc: Array

    def __init__(self, a1, a2, a3, b0, b1, b2, dc=0.0):
        self.a1, self.a2, self.a3 = (jnp.asarray(v, dtype=jnp.float64) for v in (a1, a2, a3))
        self.b0, self.b1, self.b2 = (jnp.asarray(v, dtype=jnp.float64) for v in (b0, b1, b2))
        self.dc = jnp.asarray(dc, dtype=jnp.float64)

    def __check_init__(self):
        fields = dict(a1=self.a1, a2=self.a2, a3=self.a3, b0=self.b0, b1=self.b1, b2=self.b2, dc=self.dc)
        if not is_concrete(*fields.values()):
            return
        check_finite("ClosedLoopModel", **fields)
        check_nonnegative("ClosedLoopModel", dc=self.dc)
        if float(self.a3) == 0.0:
            raise ParameterError("ClosedLoopModel.a3 must be nonzero (it sets the unity DC gain of eq 6.3), got 0")

    @staticmethod
    def from_poles(natural_frequency, damping, real_pole, b0, b1, b2, dc=0.0) -> "ClosedLoopModel":
        """Model whose poles are given by (wn [rad/s], zeta, p [rad/s]) through eq 6.13."""
        a1, a2, a3 = denominator_from_poles(natural_frequency, damping, real_pole)
        return ClosedLoopModel(a1, a2, a3, b0, b1, b2, dc)

    # -- transfer functions -------------------------------------------------------------------
    def closed_loop_model(self) -> "ClosedLoopModel":
        """Itself (every drive model offers this map to eq 6.3)."""
        return self

    @property
    def denominator(self) -> Array:
        """``[1, a1, a2, a3]``, descending powers of s."""
        return jnp.stack([jnp.ones_like(self.a1), self.a1, self.a2, self.a3])

    @property
    def tracking_numerator(self) -> Array:
        """``[b0, b1, b2, a3]``, descending powers of s (eq 6.1)."""
        return jnp.stack([self.b0, self.b1, self.b2, self.a3])

    @property
    def disturbance_numerator(self) -> Array:
        """``[0, 0, 1, 0]``: ``G_dist = s / (s^3 + a1 s^2 + a2 s + a3)`` per unit friction input (eq 6.3)."""
        z = jnp.zeros_like(self.a1)
        return jnp.stack([z, z, jnp.ones_like(self.a1), z])

    def poles(self) -> np.ndarray:
        """Closed-loop poles [rad/s] (roots of ``s^3 + a1 s^2 + a2 s + a3``)."""
        return np.roots(np.asarray(self.denominator, dtype=np.float64))

    def zeros(self) -> np.ndarray:
        """Zeros of ``G_track`` [rad/s]; two when ``b0 = 0``."""
        return np.roots(np.trim_zeros(np.asarray(self.tracking_numerator, dtype=np.float64), "f"))

    def pole_parameters(self) -> tuple[float, float, float]:
        """Inverse of eq 6.13: ``(wn [rad/s], zeta, p [rad/s])``.

        With a complex pair, ``wn`` and ``zeta`` describe the pair and ``p`` the real pole. With three
        real poles the slowest one is ``p`` and the other two give ``zeta >= 1``.
        """
        r = self.poles()
        cplx = r[np.abs(r.imag) > 1e-9 * np.abs(r)]
        if cplx.size:
            pair = cplx[0]
            real = r[np.abs(r.imag) <= 1e-9 * np.abs(r)].real[0]
            wn = abs(pair)
            return float(wn), float(-pair.real / wn), float(-real)
        r = np.sort(r.real)[::-1]  # slowest (closest to 0) first
        p, r1, r2 = r
        wn = np.sqrt(r1 * r2)
        return float(wn), float(-(r1 + r2) / (2 * wn)), float(-p)

    def steady_state_ramp_error(self, velocity) -> Array:
        """Tracking error ``x_r - x`` [mm] after transients for ``x_r = V t``: ``V (a2 - b2) / a3``.

        From the final value theorem on ``(1 - G_track(s)) V / s^2``; friction has no effect at DC
        because ``G_dist(0) = 0``.
        """
        return velocity * (self.a2 - self.b2) / self.a3

    def realization(self) -> Realization:
        """State ``z = [int (x_r - x) dt, x, x']`` [mm s, mm, mm/s]; ``x''`` from eq 6.3 (cf. eq 6.7)."""
        one, zero = jnp.ones_like(self.a1), jnp.zeros_like(self.a1)
        A = jnp.array([[zero, -one, zero], [zero, zero, one], [self.a3, -self.a2, -self.a1]])
        B = jnp.array([[one, zero, zero], [zero, zero, zero], [self.b2, self.b1, self.b0]])
        Bw = jnp.array([[zero, zero], [zero, zero], [-one, zero]])
        C = jnp.array([[zero, one, zero], [zero, zero, one], [zero, zero, zero]])
        return Realization(
            A, B, Bw, C, jnp.zeros((3, 3)), jnp.zeros((3, 2)), self.dc, zero, position_index=1, velocity_index=2, has_control=False
        )
