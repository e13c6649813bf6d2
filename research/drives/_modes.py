"""Lightly damped structural modes excited by the axis acceleration (residual vibration).

A flexible structure on the moving axis (e.g. the steel beams on the X-Y table of Sencer et al. 2015
§4, first bending modes 11.4 Hz in X and 6.8 Hz in Y) is a base-excited oscillator: its deflection
``delta`` relative to the axis obeys

    delta'' + 2 zeta wn delta' + wn^2 delta = -x'',

with ``x''`` the actual axis acceleration. The structure is light against the axis, so it does not
load the drive. The tip moves with ``x + delta``.
"""

from __future__ import annotations

import equinox as eqx
import jax.numpy as jnp
import numpy as np
from jax import Array

from research.drives._validation import check_finite, check_positive, is_concrete
from research.errors import ParameterError


class FlexibleMode(eqx.Module):
    """One lightly damped structural mode excited by axis acceleration.

    Attributes:
        natural_frequency: ``wn`` [rad/s].
        damping: ``zeta`` [-], in (0, 1).
    """

    natural_frequency: Array
    damping: Array

    def __init__(self, natural_frequency, damping):
        self.natural_frequency = jnp.asarray(natural_frequency, dtype=jnp.float64)
        self.damping = jnp.asarray(damping, dtype=jnp.float64)

    def __check_init__(self):
        if not is_concrete(self.natural_frequency, self.damping):
            return
        check_finite("FlexibleMode", natural_frequency=self.natural_frequency, damping=self.damping)
        check_positive("FlexibleMode", natural_frequency=self.natural_frequency, damping=self.damping)
        if not float(self.damping) < 1:
            raise ParameterError(f"FlexibleMode.damping must be < 1 for a lightly damped mode, got {float(self.damping)}")

    @staticmethod
    def from_hz(frequency_hz, damping) -> "FlexibleMode":
        """Mode with natural frequency given in Hz (converted to rad/s)."""
        return FlexibleMode(2 * np.pi * jnp.asarray(frequency_hz, dtype=jnp.float64), damping)

    def frequency_response(self, frequency_hz) -> Array:
        """Deflection per axis acceleration ``delta/x'' = -1/(s^2 + 2 zeta wn s + wn^2)`` [mm/(mm/s^2)] at s = j 2 pi f."""
        s = 2j * jnp.pi * jnp.asarray(frequency_hz, dtype=jnp.float64)
        w, z = self.natural_frequency, self.damping
        return -1.0 / (s**2 + 2 * z * w * s + w**2)

    def poles(self) -> np.ndarray:
        """The mode's two poles [rad/s]."""
        w, z = float(self.natural_frequency), float(self.damping)
        return np.roots([1.0, 2 * z * w, w * w])

    def state_matrices(self):
        """``(A_m, e)``: ``[delta, delta']' = A_m [delta, delta'] + e x''`` with ``e = [0, -1]``."""
        w, z = self.natural_frequency, self.damping
        zero, one = jnp.zeros_like(w), jnp.ones_like(w)
        A = jnp.stack([jnp.stack([zero, one]), jnp.stack([-w * w, -2 * z * w])])
        return A, jnp.stack([zero, -one])
