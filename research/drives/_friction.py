"""Coulomb friction, thesis eq 6.2: ``d = d_c sign(x')``.

Two versions of the sign: the exact one (eq 6.2: +1 for positive velocity, -1 for negative, 0 at rest)
used for simulation, and ``tanh(v / width)`` for gradients, whose derivative is finite everywhere.
"""

from __future__ import annotations

import jax.numpy as jnp
from jax import Array


def coulomb_sign(velocity: Array) -> Array:
    """Exact sign of eq 6.2: 1 for ``velocity > 0``, -1 for ``< 0``, 0 at rest.

    Args:
        velocity: axis velocity [mm/s or rad/s], any shape.
    Returns:
        array of the same shape with values in {-1, 0, 1}.
    """
    return jnp.sign(velocity)


def smooth_sign(velocity: Array, width: float | Array) -> Array:
    """Smooth approximation ``tanh(velocity / width)`` of :func:`coulomb_sign`.

    Args:
        velocity: axis velocity [mm/s or rad/s].
        width: velocity [same unit] over which the sign changes from -0.76 to +0.76; the error against
            the exact sign is below ``2 exp(-2 |v| / width)``.
    Returns:
        array of the velocity's shape in (-1, 1), differentiable in ``velocity`` and ``width``.
    """
    return jnp.tanh(velocity / width)
