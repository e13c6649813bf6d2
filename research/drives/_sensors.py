"""Encoder quantization and measurement noise, for synthetic drive logs.

The thesis' 5-axis machine has 2.9 um linear and 8.7 urad rotary encoder resolution (§4.5).
"""

from __future__ import annotations

import equinox as eqx
import jax
import jax.numpy as jnp
from jax import Array

from research.drives._validation import check_finite, check_nonnegative, is_concrete
from research.errors import ParameterError


class Encoder(eqx.Module):
    """Position sensor: additive Gaussian noise, then quantization to the encoder grid.

    Attributes:
        resolution: one count [mm] (or [rad]); 0 disables quantization.
        noise_std: standard deviation of the noise added before quantization [mm] (or [rad]).
    """

    resolution: Array
    noise_std: Array

    def __init__(self, resolution, noise_std=0.0):
        self.resolution = jnp.asarray(resolution, dtype=jnp.float64)
        self.noise_std = jnp.asarray(noise_std, dtype=jnp.float64)

    def __check_init__(self):
        if not is_concrete(self.resolution, self.noise_std):
            return
        check_finite("Encoder", resolution=self.resolution, noise_std=self.noise_std)
        check_nonnegative("Encoder", resolution=self.resolution, noise_std=self.noise_std)


#: Thesis §4.5: 2.9 um linear encoders (X, Y, Z), 8.7 urad rotary encoders (A, C).
THESIS_LINEAR_ENCODER = Encoder(resolution=2.9e-3)
THESIS_ROTARY_ENCODER = Encoder(resolution=8.7e-6)


def measure(encoder: Encoder, position, seed: int) -> Array:
    """Encoder reading of ``position``: ``resolution * round((position + noise) / resolution)``.

    Args:
        encoder: one :class:`Encoder` for all axes.
        position: true positions [mm or rad], any shape, e.g. ``(N, A)``.
        seed: integer seed of the noise (``jax.random.PRNGKey(seed)``); the same seed gives the same log.
    Returns:
        measured positions, same shape; multiples of the resolution when it is > 0.
    """
    if not isinstance(seed, int) or isinstance(seed, bool):
        raise ParameterError(f"measure: seed must be an int, got {seed!r}")
    x = jnp.asarray(position, dtype=jnp.float64)
    noise = encoder.noise_std * jax.random.normal(jax.random.PRNGKey(seed), x.shape, dtype=jnp.float64)
    y = x + noise
    q = jnp.where(encoder.resolution > 0, encoder.resolution, 1.0)
    return jnp.where(encoder.resolution > 0, q * jnp.round(y / q), y)
