"""Rigid-body feed-drive axis, thesis Fig 6.1a and eq 4.11.

    J theta'' + B theta' = Ka Kt u - d sign(theta'),       x = rg theta,

so in axis units ``m x'' + c x' = u - d sign(x') / (Ka Kt)`` with the equivalent inertia
``m = J / (Ka Kt rg)`` [V s^2/mm] and damping ``c = B / (Ka Kt rg)`` [V s/mm] (eq 4.11).
For rotary axes positions are in rad and ``rg = 1``.
"""

from __future__ import annotations

import equinox as eqx
import jax.numpy as jnp
from jax import Array

from research.drives._validation import check_finite, check_nonnegative, check_positive, is_concrete


class RigidBodyAxis(eqx.Module):
    """Rigid-body axis with Coulomb friction (Fig 6.1a, eq 4.11, eq 6.2).

    Attributes:
        J: equivalent inertia [kg m^2].
        B: equivalent viscous damping [N m s/rad].
        Ka: current amplifier gain [A/V].
        Kt: motor torque constant [N m/A].
        rg: transmission gain [mm/rad] (ball-screw lead / 2 pi; 1 for direct-drive rotary axes).
        coulomb: average Coulomb friction torque ``d_c`` [N m] (eq 6.2).
    """

    J: Array
    B: Array
    Ka: Array
    Kt: Array
    rg: Array
    coulomb: Array

    def __init__(self, J, B, Ka=1.0, Kt=1.0, rg=1.0, coulomb=0.0):
        self.J, self.B, self.Ka, self.Kt, self.rg, self.coulomb = (
            jnp.asarray(v, dtype=jnp.float64) for v in (J, B, Ka, Kt, rg, coulomb)
        )

    def __check_init__(self):
        f = dict(J=self.J, B=self.B, Ka=self.Ka, Kt=self.Kt, rg=self.rg, coulomb=self.coulomb)
        if not is_concrete(*f.values()):
            return
        check_finite("RigidBodyAxis", **f)
        check_positive("RigidBodyAxis", J=self.J, Ka=self.Ka, Kt=self.Kt, rg=self.rg)
        check_nonnegative("RigidBodyAxis", B=self.B, coulomb=self.coulomb)

    @staticmethod
    def from_equivalent(m, c, coulomb_voltage=0.0) -> "RigidBodyAxis":
        """Axis from the identified equivalent parameters of eq 4.11 / Table 4.1.

        Args:
            m: ``J/(Ka Kt rg)`` [V s^2/mm] (or [V s^2/rad]).
            c: ``B/(Ka Kt rg)`` [V s/mm] (or [V s/rad]).
            coulomb_voltage: Coulomb friction expressed as control voltage, ``d_c/(Ka Kt)`` [V].
        Returns:
            the axis with ``Ka = Kt = 1`` and ``rg = 1``, so ``J = m``, ``B = c``, ``coulomb = coulomb_voltage``
            numerically; only these ratios are identifiable from position/voltage data.
        """
        return RigidBodyAxis(J=m, B=c, Ka=1.0, Kt=1.0, rg=1.0, coulomb=coulomb_voltage)

    @property
    def m(self) -> Array:
        """Equivalent inertia ``J/(Ka Kt rg)`` [V s^2/mm], eq 4.11."""
        return self.J / (self.Ka * self.Kt * self.rg)

    @property
    def c(self) -> Array:
        """Equivalent viscous damping ``B/(Ka Kt rg)`` [V s/mm], eq 4.11."""
        return self.B / (self.Ka * self.Kt * self.rg)

    @property
    def friction_acceleration(self) -> Array:
        """Coulomb friction as axis deceleration ``rg d_c / J`` [mm/s^2]: the ``d_c`` of eq 6.3 (eq 6.4/6.5)."""
        return self.rg * self.coulomb / self.J

    def acceleration(self, velocity, voltage, friction_sign) -> Array:
        """Axis acceleration [mm/s^2] of eq 4.11 for a given velocity [mm/s], voltage [V] and sign(x')."""
        return (voltage - self.c * velocity - self.coulomb * friction_sign / (self.Ka * self.Kt)) / self.m
