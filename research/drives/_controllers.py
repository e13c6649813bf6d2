"""P-PI cascade and PID position control of a rigid-body axis, thesis Fig 6.1b/c, with the maps to the
general closed-loop model (eq 6.4 and eq 6.5).

The controllers are modelled in continuous time, as the thesis' transfer functions are; the simulator
discretizes the whole closed loop exactly (see :mod:`research.drives._simulate`). Friction
feed-forward adds ``friction_ff * d_c sign(x_r') / (Ka Kt)`` to the control voltage, so the residual
Coulomb torque is ``d_c (sign(x') - friction_ff sign(x_r'))``.
"""

from __future__ import annotations

import equinox as eqx
import jax.numpy as jnp
from jax import Array

from research.drives._closed_loop import ClosedLoopModel
from research.drives._realization import Realization
from research.drives._rigid_body import RigidBodyAxis
from research.drives._validation import check_finite, check_nonnegative, check_unit_interval, is_concrete
from research.errors import ParameterError


def _as_f64(*values):
    return tuple(jnp.asarray(v, dtype=jnp.float64) for v in values)


class PPICascade(eqx.Module):
    """P position loop around a PI velocity loop with velocity, viscous, inertia and friction feed-forward
    (thesis Fig 6.1b).

    ``omega_c = Kv (x_r - x) + Vff x_r'/rg``,
    ``u = Kp (omega_c - omega) + Ki int(omega_c - omega) dt + Jff m x_r'' + Bff c x_r' + friction_ff d_c sign(x_r')/(Ka Kt)``
    with the motor speed ``omega = x'/rg``.

    Attributes:
        plant: the rigid-body axis (Fig 6.1a).
        Kv: position-loop gain [(rad/s)/mm].
        Kp: velocity-loop proportional gain [V/(rad/s)].
        Ki: velocity-loop integral gain [V/rad].
        Vff, Bff, Jff: velocity, viscous-damping and inertia feed-forward gains in [0, 1] (§6.2).
        friction_ff: Coulomb friction feed-forward gain in [0, 1].
    """

    plant: RigidBodyAxis
    Kv: Array
    Kp: Array
    Ki: Array
    Vff: Array
    Bff: Array
    Jff: Array
    friction_ff: Array

    def __init__(self, plant, Kv, Kp, Ki, Vff=0.0, Bff=0.0, Jff=0.0, friction_ff=0.0):
        self.plant = plant
        self.Kv, self.Kp, self.Ki, self.Vff, self.Bff, self.Jff, self.friction_ff = _as_f64(
            Kv, Kp, Ki, Vff, Bff, Jff, friction_ff
        )

    def __check_init__(self):
        if not isinstance(self.plant, RigidBodyAxis):
            raise ParameterError(f"PPICascade.plant must be a RigidBodyAxis, got {type(self.plant).__name__}")
        gains = dict(Kv=self.Kv, Kp=self.Kp, Ki=self.Ki)
        ff = dict(Vff=self.Vff, Bff=self.Bff, Jff=self.Jff, friction_ff=self.friction_ff)
        if not is_concrete(*gains.values(), *ff.values()):
            return
        check_finite("PPICascade", **gains, **ff)
        check_nonnegative("PPICascade", **gains)
        check_unit_interval("PPICascade", **ff)

    def closed_loop_model(self) -> ClosedLoopModel:
        """Thesis eq 6.4: a1 = (B + Ka Kt Kp)/J, a2 = Ka Kt (Ki + Kp Kv rg)/J, a3 = Ka Kt Ki Kv rg/J,
        b0 = Jff, b1 = (Bff B + Ka Kt Kp Vff)/J, b2 = Ka Kt (Kp Kv rg + Ki Vff)/J, dc = rg d_c/J.

        The friction amplitude is the residual ``(1 - friction_ff) rg d_c / J`` [mm/s^2] (exact for
        ``x'`` and ``x_r'`` of the same sign).
        """
        P = self.plant
        K = P.Ka * P.Kt
        return ClosedLoopModel(
            a1=(P.B + K * self.Kp) / P.J,
            a2=K * (self.Ki + self.Kp * self.Kv * P.rg) / P.J,
            a3=K * self.Ki * self.Kv * P.rg / P.J,
            b0=self.Jff,
            b1=(self.Bff * P.B + K * self.Kp * self.Vff) / P.J,
            b2=K * (self.Kp * self.Kv * P.rg + self.Ki * self.Vff) / P.J,
            dc=(1 - self.friction_ff) * P.friction_acceleration,
        )

    def steady_state_ramp_error(self, velocity) -> Array:
        """``x_r - x`` [mm] at constant reference velocity ``V`` [mm/s]: ``V (1 - Vff)/(Kv rg)``.

        The PI velocity loop integrates away viscous and Coulomb torque, so only the position-loop
        error that the velocity command needs remains.
        """
        return velocity * (1 - self.Vff) / (self.Kv * self.plant.rg)

    def realization(self) -> Realization:
        """State ``z = [x, x', eta]`` [mm, mm/s, rad], ``eta = int(omega_c - omega) dt``; friction in [N m]."""
        P = self.plant
        K, g = P.Ka * P.Kt, P.rg
        zero, one = jnp.zeros_like(P.J), jnp.ones_like(P.J)
        Cu = jnp.stack([-self.Kp * self.Kv, -self.Kp / g, self.Ki])
        Du = jnp.stack([self.Kp * self.Kv, self.Kp * self.Vff / g + self.Bff * P.B / (K * g), self.Jff * P.J / (K * g)])
        Dwu = jnp.stack([zero, 1 / K])
        gain = g * K / P.J
        A = jnp.stack([
            jnp.stack([zero, one, zero]),
            gain * Cu + jnp.stack([zero, -P.B / P.J, zero]),
            jnp.stack([-self.Kv, -one / g, zero]),
        ])
        B = jnp.stack([jnp.zeros(3), gain * Du, jnp.stack([self.Kv, self.Vff / g, zero])])
        Bw = jnp.stack([jnp.zeros(2), jnp.stack([-g / P.J, g / P.J]), jnp.zeros(2)])
        C = jnp.stack([jnp.stack([one, zero, zero]), jnp.stack([zero, one, zero]), Cu])
        D = jnp.stack([jnp.zeros(3), jnp.zeros(3), Du])
        Dw = jnp.stack([jnp.zeros(2), jnp.zeros(2), Dwu])
        return Realization(A, B, Bw, C, D, Dw, P.coulomb, self.friction_ff * P.coulomb, position_index=0, velocity_index=1, has_control=True)


class PIDController(eqx.Module):
    """PID position control with viscous, inertia and friction feed-forward (thesis Fig 6.1c).

    ``u = Kp (wp x_r - x) + Ki int(x_r - x) dt + Kd (wd x_r' - x') + Jff m x_r'' + Bff c x_r' + friction_ff d_c sign(x_r')/(Ka Kt)``.

    The set-point weights ``wp``, ``wd`` (both 1 in Fig 6.1c, giving eq 6.5) are the standard two-degree-
    of-freedom PID extension; they are needed to reproduce the thesis' Table 6.2 virtual drive, whose
    ``b2 != a2`` cannot come from eq 6.5.

    Attributes:
        plant: the rigid-body axis.
        Kp [V/mm], Ki [V/(mm s)], Kd [V s/mm]: PID gains.
        Bff, Jff, friction_ff: feed-forward gains in [0, 1].
        wp, wd: proportional and derivative set-point weights in [0, 1].
    """

    plant: RigidBodyAxis
    Kp: Array
    Ki: Array
    Kd: Array
    Bff: Array
    Jff: Array
    friction_ff: Array
    wp: Array
    wd: Array

    def __init__(self, plant, Kp, Ki, Kd, Bff=0.0, Jff=0.0, friction_ff=0.0, wp=1.0, wd=1.0):
        self.plant = plant
        self.Kp, self.Ki, self.Kd, self.Bff, self.Jff, self.friction_ff, self.wp, self.wd = _as_f64(
            Kp, Ki, Kd, Bff, Jff, friction_ff, wp, wd
        )

    def __check_init__(self):
        if not isinstance(self.plant, RigidBodyAxis):
            raise ParameterError(f"PIDController.plant must be a RigidBodyAxis, got {type(self.plant).__name__}")
        gains = dict(Kp=self.Kp, Ki=self.Ki, Kd=self.Kd)
        unit = dict(Bff=self.Bff, Jff=self.Jff, friction_ff=self.friction_ff, wp=self.wp, wd=self.wd)
        if not is_concrete(*gains.values(), *unit.values()):
            return
        check_finite("PIDController", **gains, **unit)
        check_nonnegative("PIDController", **gains)
        check_unit_interval("PIDController", **unit)

    def closed_loop_model(self) -> ClosedLoopModel:
        """Thesis eq 6.5 (with set-point weights): a1 = (B + Ka Kt Kd rg)/J, a2 = Ka Kt Kp rg/J,
        a3 = Ka Kt Ki rg/J, b0 = Jff, b1 = (Bff B + wd Ka Kt Kd rg)/J, b2 = wp Ka Kt Kp rg/J,
        dc = (1 - friction_ff) rg d_c/J."""
        P = self.plant
        K = P.Ka * P.Kt * P.rg
        return ClosedLoopModel(
            a1=(P.B + K * self.Kd) / P.J,
            a2=K * self.Kp / P.J,
            a3=K * self.Ki / P.J,
            b0=self.Jff,
            b1=(self.Bff * P.B + self.wd * K * self.Kd) / P.J,
            b2=self.wp * K * self.Kp / P.J,
            dc=(1 - self.friction_ff) * P.friction_acceleration,
        )

    def realization(self) -> Realization:
        """State ``z = [int(x_r - x) dt, x, x']`` [mm s, mm, mm/s]; friction in [N m]."""
        P = self.plant
        K, g = P.Ka * P.Kt, P.rg
        zero, one = jnp.zeros_like(P.J), jnp.ones_like(P.J)
        Cu = jnp.stack([self.Ki, -self.Kp, -self.Kd])
        Du = jnp.stack([self.wp * self.Kp, self.wd * self.Kd + self.Bff * P.B / (K * g), self.Jff * P.J / (K * g)])
        gain = g * K / P.J
        A = jnp.stack([
            jnp.stack([zero, -one, zero]),
            jnp.stack([zero, zero, one]),
            gain * Cu + jnp.stack([zero, zero, -P.B / P.J]),
        ])
        B = jnp.stack([jnp.stack([one, zero, zero]), jnp.zeros(3), gain * Du])
        Bw = jnp.stack([jnp.zeros(2), jnp.zeros(2), jnp.stack([-g / P.J, g / P.J])])
        C = jnp.stack([jnp.stack([zero, one, zero]), jnp.stack([zero, zero, one]), Cu])
        D = jnp.stack([jnp.zeros(3), jnp.zeros(3), Du])
        Dw = jnp.stack([jnp.zeros(2), jnp.zeros(2), jnp.stack([zero, 1 / K])])
        return Realization(A, B, Bw, C, D, Dw, P.coulomb, self.friction_ff * P.coulomb, position_index=1, velocity_index=2, has_control=True)
