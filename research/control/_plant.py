"""The five rigid-body feed drives of the thesis' 5-axis machine (eq 4.11 / 5.1, Table 4.1 = Table 5.1)
with Coulomb friction as the disturbance ``d = d_c sign(q')`` (eq 6.2), as one immutable module.

    m_i q_i'' + c_i q_i' = u_i - d_c,i sign(q_i'),     i = x, y, z, a, c

Units: ``m`` [V s^2/mm] ([V s^2/rad] for A, C), ``c`` [V s/mm] ([V s/rad]), ``coulomb`` [V] (friction
expressed at the amplifier input, as eq 4.11's ``d_i``). The thesis prints no Coulomb friction for
this machine; :func:`research.control.identify_coulomb` derives it from the thesis' Fig 5.7 peak
axis errors (stated there).
"""

from __future__ import annotations

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jax import Array

from research.control._gains import AXES, plant_step_matrices
from research.drives import TABLE_4_1
from research.errors import ParameterError


class FiveAxisPlant(eqx.Module):
    """Rigid-body X, Y, Z, A, C drives (eq 4.11).

    Attributes:
        m: ``(5,)`` equivalent inertia ``J / (Ka Kt rg)``; c: ``(5,)`` equivalent damping ``B / (Ka Kt rg)``;
        coulomb: ``(5,)`` Coulomb friction voltage ``d_c`` [V] (>= 0).
    """

    m: Array
    c: Array
    coulomb: Array

    def __init__(self, m, c, coulomb=0.0):
        self.m, self.c = jnp.asarray(m, dtype=jnp.float64), jnp.asarray(c, dtype=jnp.float64)
        coulomb = jnp.asarray(coulomb, dtype=jnp.float64)
        if coulomb.ndim and coulomb.shape != self.m.shape:
            raise ParameterError(f"FiveAxisPlant.coulomb must be a scalar or have 5 entries (x, y, z, a, c), "
                                 f"got shape {coulomb.shape}")
        self.coulomb = jnp.broadcast_to(coulomb, self.m.shape)

    def __check_init__(self):
        if any(isinstance(x, jax.core.Tracer) for x in (self.m, self.c, self.coulomb)):
            return
        for name in ("m", "c", "coulomb"):
            v = np.asarray(getattr(self, name))
            if v.shape != (5,):
                raise ParameterError(f"FiveAxisPlant.{name} must have 5 entries (x, y, z, a, c), got shape {v.shape}")
            if not np.all(np.isfinite(v)):
                raise ParameterError(f"FiveAxisPlant.{name} must be finite, got {v}")
        if np.any(np.asarray(self.m) <= 0):
            raise ParameterError(f"FiveAxisPlant.m must be > 0 for every axis, got {np.asarray(self.m)}")
        for name in ("c", "coulomb"):
            v = np.asarray(getattr(self, name))
            if np.any(v < 0):
                i = int(np.argmax(v < 0))
                raise ParameterError(f"FiveAxisPlant.{name}[{AXES[i]!r}] must be >= 0, got {v[i]}")

    def with_coulomb(self, coulomb) -> "FiveAxisPlant":
        """The same drives with Coulomb friction ``coulomb`` [V] (scalar or ``(5,)``)."""
        return FiveAxisPlant(self.m, self.c, coulomb)

    def discretize(self, T: float):
        """Exact ZOH matrices ``(Ad (5, 2, 2), Bd (5, 2))`` of every axis for the period ``T`` [s]."""
        return plant_step_matrices(self.m, self.c, T)


def thesis_plant(coulomb=0.0) -> FiveAxisPlant:
    """Thesis Table 5.1 (= Table 4.1) drives: m = 0.00162 0.00174 0.00296 0.00682 0.00054, c = 0.00681
    0.00863 0.01518 0.01964 0.00368 (Table 4.1 prints Z's c in V s/rad; Table 5.1 in V s/mm, used here).

    Args:
        coulomb: Coulomb friction voltage [V], scalar or one per axis.
    """
    m = [TABLE_4_1[a][0] for a in AXES]
    c = [TABLE_4_1[a][1] for a in AXES]
    return FiveAxisPlant(m, c, coulomb)
