"""Closed-loop simulation of the five rigid-body drives under a sliding-mode controller: the SISO axis
controller (thesis [35], eq 5.23-5.27 with W = 0) or the complete 5-axis contour controller of Fig 5.4
(tool-tip controller §5.2 for X, Y, Z; orientation contour controller §5.3 for A, C).

One ``jax.lax.scan`` over the control periods (jit / vmap / grad-able). Period ``k``: read the measured
``q_k, q'_k`` (exact, no encoder quantization: an assumption), compute ``u_k``, hold it (ZOH) over
``[kT, (k+1)T]`` together with the friction ``d_c sign(q'_k)`` (exact sign, or ``tanh(q'/width)`` for
gradients), and step the exact ZOH discretization of eq 4.11.

**Tool-tip contour controller** (eq 5.1-5.17; our reading, where the printed equations are garbled or
leave a choice open). Errors ``e = P_ref - P(q)``, ``e' = P'_ref - J q'`` (eq 4.14, P by eq 4.5, J by
eq 4.8); Frenet errors ``e_F = F^T e``, ``e_F' = F^T e' + F'^T e`` (eq 5.3 with the *basic* frame at the
reference point, h = 0: Fig 4.6 shows basic and compensated agree to 0.1 um on this path, and the
delay-compensated frame's h', h'' are not defined in the thesis); ``E_F = int e_F``;
surface ``S = e_F' + C_P e_F + C_I E_F`` (eq 5.5-5.7, ``C_P = 2 zeta wn``, ``C_I = wn^2``). The law
commands the tip acceleration

    P''_des = P''_ref + F [2 F'^T e' + F''^T e + C_P e_F' + C_I e_F + m_F^-1 (Ks S + delta_hat)]

and realizes it with the Cartesian axes: ``q''_xyz = J_xyz^-1 (P''_des - J' q' - J_ac alpha_ac)``,
``u_xyz = M q''_xyz + C q'_xyz`` (eq 5.15 row by row, with the rotary rows replaced by the orientation
controller as in Fig 5.4; ``alpha_ac`` is the rotary acceleration that controller commands). The
disturbance observer integrates the surface per direction, ``delta_hat(k) = delta_hat(k-1) + T Gamma S``
(eq 5.8 with kappa = 1). ``m_F`` is the direction inertia that turns Table 5.3's Ks, Gamma [V/..]
into accelerations: the thesis leaves it open; we take the inverse direction-averaged tip mobility
``m_F = 3 / (1/m_x + 1/m_y + 1/m_z)`` (for the rotation-only Cartesian Jacobian of eq 4.6 the tip
mobility along a unit direction u is ``u^T R M^-1 R^T u``, whose average over directions is
``tr(M^-1)/3``).

*Lyapunov argument* (eq 5.10-5.17 in these coordinates). With the law above the surface obeys
``m_F S' = -Ks S + (delta - delta_hat)``, where ``delta = m_F F^T J M^-1 d`` is the drive disturbance
seen in the Frenet directions (assumed constant over short intervals, as the thesis does for d).
``V = 1/2 S^T m_F S + 1/2 (delta - delta_hat)^T Gamma^-1 (delta - delta_hat)`` is positive definite,
and with ``delta_hat' = Gamma S``, ``V' = -S^T Ks S <= 0``. V is bounded below and non-increasing, so
S, delta_hat are bounded; S' is bounded, hence V'' bounded and V' uniformly continuous; Barbalat's
lemma gives ``S -> 0``, and on ``S = 0`` the Frenet errors obey ``e_F'' + C_P e_F' + C_I e_F = 0``
(Hurwitz for wn, zeta > 0), so ``e_F -> 0`` and, F being orthogonal, ``e -> 0``. The same argument
with ``m_F -> diag(m_a, m_c)`` is eq 5.25-5.28 for the orientation controller. Bounds on the observer
(eq 5.9, kappa = 0 at the limits) only add a non-positive term; the thesis gives no limits, so none
are applied.

**Orientation contour controller** (eq 5.18-5.27): ``e_R = [e_a, e_c]``, ``eps_R = e_R - v (v^T e_R)``
(eq 5.20, v the unit rotary reference direction), ``e~ = e_R + W int eps_R`` (eq 5.22),
``S = Delta e~ + e~'`` (eq 5.23), ``u = M Delta e~' + M q''_ref + M W eps_R' + C q' + Ks S + d_hat``
(eq 5.27; ``e~' = e_R' + W eps_R``, ``eps_R'`` by the product rule with ``v'``), ``d_hat`` by eq 5.24.
W = 0 is the SISO law of the rotary axes.

Saturation and divergence: with ``u_max`` the voltages are clipped (the amplifier limit; counted per
sample in the result). If any axis error exceeds ``divergence_limit`` (mm or rad) or a control value is
not finite, the loop is flagged ``diverged`` at that sample and its state is frozen from there, so no
NaN or overflow leaves the simulation; callers check :attr:`ClosedLoopResult.diverged`.
"""

from __future__ import annotations

from typing import Union

import equinox as eqx
import jax
import jax.numpy as jnp
from jax import Array
from jax.experimental.jet import jet

from research.control._gains import AxisSMC, ContourGains
from research.control._plant import FiveAxisPlant
from research.control._reference import ContourReference
from research.errors import ParameterError
from research.paths.kinematics5 import TableTiltingAC

Controller = Union[AxisSMC, ContourGains]
#: control periods per scan iteration (measured in benchmarks/bench_control.py)
UNROLL = 1


class ClosedLoopResult(eqx.Module):
    """Simulated closed loop.

    Attributes:
        q, qd: ``(N, 5)`` actual axis positions [mm, rad] and velocities at the control samples.
        u: ``(N, 5)`` control voltages [V] (after saturation). d_hat: ``(N, 5)`` observer states
        (SISO: per axis [V]; contour: ``[delta_t, delta_n, delta_b, d_a, d_c]`` [V]).
        saturated: ``(N,)`` number of axes at the voltage limit per sample.
        diverged: scalar bool; diverged_at: first diverged sample (``N`` if none).
    """

    q: Array
    qd: Array
    u: Array
    d_hat: Array
    saturated: Array
    diverged: Array
    diverged_at: Array


def direction_inertia(plant: FiveAxisPlant) -> Array:
    """``m_F`` of the tool-tip directions (module docstring): ``3 / sum(1/m_xyz)``, broadcast to ``(3,)``."""
    return jnp.full((3,), 3.0 / jnp.sum(1.0 / plant.m[:3]))


def _siso_law(g: AxisSMC, plant, r, q, qd, dh, T):
    e, de = r["q"] - q, r["qd"] - qd
    S = g.lam * e + de
    dh = dh + T * g.Gamma * S  # eq 5.24
    u = plant.m * (g.lam * de + r["qdd"]) + plant.c * qd + g.Ks * S + dh  # eq 5.27, W = 0
    return u, dh, {}


def _orientation_law(g: AxisSMC, W, m, c, r, q, qd, dh, Ieps, T):
    """Eq 5.20-5.27 for A, C: returns ``(u, d_hat, int eps, commanded acceleration)``."""
    e, de = r["q"][3:] - q, r["qd"][3:] - qd
    v, vd = r["v"], r["vd"]
    eps = e - v * jnp.dot(v, e)  # eq 5.20
    deps = de - vd * jnp.dot(v, e) - v * (jnp.dot(vd, e) + jnp.dot(v, de))
    Ieps = Ieps + T * eps
    et = e + W * Ieps  # eq 5.22
    det = de + W * eps
    S = g.lam * et + det  # eq 5.23
    dh = dh + T * g.Gamma * S  # eq 5.24
    acc = g.lam * det + r["qdd"][3:] + W * deps
    u = m * acc + c * qd + g.Ks * S + dh  # eq 5.27
    return u, dh, Ieps, acc + g.Ks * S / m


def _J_xyz(q):
    """``dP/d[x, y, z] = R(a, c)^T diag(-1, -1, 1)`` of eq 4.5 (independent of the offsets)."""
    sa, ca, sc, cc = jnp.sin(q[3]), jnp.cos(q[3]), jnp.sin(q[4]), jnp.cos(q[4])
    R = jnp.array([[cc, sc, 0.0], [-ca * sc, ca * cc, sa], [sa * sc, -sa * cc, ca]])
    return R.T * jnp.array([-1.0, -1.0, 1.0])[None, :]


def _contour_law(g: ContourGains, plant, machine, r, q, qd, dh, IF, Ieps, T):
    m, c = plant.m, plant.c
    u_r, dh_r, Ieps, alpha_r = _orientation_law(g.rotary, g.W, m[3:], c[3:], r, q[3:], qd[3:], dh[3:], Ieps, T)

    def tip(qq):
        return machine.forward(qq)[0]

    # one Taylor pass (jax.experimental.jet): P, P' = J q', and the part of P'' not made by the
    # Cartesian accelerations, J' q' + J_ac alpha_ac (eq 4.10)
    P, (Pd, P2_rest) = jet(tip, (q,), ((qd, jnp.concatenate([jnp.zeros(3), alpha_r])),))
    F, Fd, Fdd = r["F"], r["Fd"], r["Fdd"]
    e, de = r["P"] - P, r["Pd"] - Pd
    eF = F.T @ e
    deF = F.T @ de + Fd.T @ e
    IF = IF + T * eF
    tg = g.tip
    CP, CI = 2 * tg.zeta * tg.wn, tg.wn**2
    S = deF + CP * eF + CI * IF  # eq 5.5
    mF = direction_inertia(plant)
    dF = dh[:3] + T * tg.Gamma * S  # eq 5.8
    rho = 2 * Fd.T @ de + Fdd.T @ e + CP * deF + CI * eF + (tg.Ks * S + dF) / mF
    Pdd_des = r["Pdd"] + F @ rho
    # J_xyz = R(a, c)^T diag(-1, -1, 1) is orthogonal (eq 4.6), so its inverse is its transpose
    qdd_c = _J_xyz(q).T @ (Pdd_des - P2_rest)
    u_c = m[:3] * qdd_c + c[:3] * qd[:3]  # eq 5.15, Cartesian rows
    return jnp.concatenate([u_c, u_r]), jnp.concatenate([dF, dh_r]), IF, Ieps


def simulate_closed_loop(plant: FiveAxisPlant, reference: ContourReference, controller: Controller,
                         machine: TableTiltingAC | None = None, *, u_max: float | None = None,
                         friction_width: float = 0.0, divergence_limit: float = 10.0) -> ClosedLoopResult:
    """Run the closed loop over the reference (the loop starts on the reference, at rest).

    Args:
        plant: the five drives (eq 4.11) with their Coulomb friction.
        reference: :class:`ContourReference` (its ``sample_period`` is the control period T).
        controller: :class:`AxisSMC` (5 axes, SISO) or :class:`ContourGains` (Fig 5.4 scheme).
        machine: A/C kinematics (needed by the contour controller; default all offsets zero).
        u_max: amplifier voltage limit [V] (None: no saturation).
        friction_width: 0 for the exact sign of eq 6.2, else the ``tanh`` width [mm/s] (for gradients).
        divergence_limit: axis error [mm or rad] beyond which the run is flagged diverged.
    Returns:
        :class:`ClosedLoopResult`.
    Raises:
        ParameterError: a SISO gain set without 5 axes, or a non-positive limit.
    """
    machine = TableTiltingAC() if machine is None else machine
    if isinstance(controller, AxisSMC) and controller.lam.shape != (5,):
        raise ParameterError(f"SISO controller needs 5 axes (x, y, z, a, c), got {controller.lam.shape[0]} gain entries")
    if not isinstance(controller, (AxisSMC, ContourGains)):
        raise ParameterError(f"controller must be AxisSMC or ContourGains, got {type(controller).__name__}")
    if reference.q.shape[1:] != (5,):
        raise ParameterError(f"reference must have 5 axes, got q of shape {reference.q.shape}")
    if u_max is not None and not u_max > 0:
        raise ParameterError(f"u_max must be > 0 V, got {u_max!r}")
    if not divergence_limit > 0:
        raise ParameterError(f"divergence_limit must be > 0, got {divergence_limit!r}")
    return _run(plant, reference, controller, machine, jnp.inf if u_max is None else float(u_max),
                float(friction_width), float(divergence_limit))


@eqx.filter_jit
def _run(plant, reference, controller, machine, u_max, friction_width, divergence_limit):
    T = reference.sample_period
    Ad, Bd = plant.discretize(T)
    rows = dict(q=reference.q, qd=reference.qd, qdd=reference.qdd, P=reference.P, Pd=reference.Pd,
                Pdd=reference.Pdd, F=reference.F, Fd=reference.Fd, Fdd=reference.Fdd, v=reference.v, vd=reference.vd)
    contour = isinstance(controller, ContourGains)

    def sign(v):
        return jnp.tanh(v / friction_width) if friction_width > 0 else jnp.sign(v)

    def step(carry, r):
        q, qd, dh, IF, Ieps, div, kdiv, k = carry
        if contour:
            u, dh_n, IF_n, Ieps_n = _contour_law(controller, plant, machine, r, q, qd, dh, IF, Ieps, T)
        else:
            u, dh_n, _ = _siso_law(controller, plant, r, q, qd, dh, T)
            IF_n, Ieps_n = IF, Ieps
        u = jnp.clip(u, -u_max, u_max)
        sat = jnp.sum(jnp.abs(u) >= u_max)
        w = u - plant.coulomb * sign(qd)
        x = jnp.einsum("aij,aj->ai", Ad, jnp.stack([q, qd], -1)) + Bd * w[:, None]
        bad = ~jnp.all(jnp.isfinite(u)) | ~jnp.all(jnp.isfinite(x)) | jnp.any(jnp.abs(r["q"] - q) > divergence_limit)
        now = div | bad
        kdiv = jnp.where(now & ~div, k, kdiv)
        keep = lambda new, old: jnp.where(now, old, new)  # noqa: E731  frozen once diverged
        u_out = jnp.where(now, 0.0, u)
        carry = (keep(x[:, 0], q), keep(x[:, 1], qd), keep(dh_n, dh), keep(IF_n, IF), keep(Ieps_n, Ieps), now, kdiv, k + 1)
        return carry, (q, qd, u_out, dh, sat)

    N = reference.t.shape[0]
    z5 = jnp.zeros(5)
    carry0 = (reference.q[0], reference.qd[0], z5, jnp.zeros(3), jnp.zeros(2), jnp.array(False), jnp.int32(N), jnp.int32(0))
    carry, (q, qd, u, dh, sat) = jax.lax.scan(step, carry0, rows, unroll=UNROLL)
    return ClosedLoopResult(q, qd, u, dh, sat, carry[5], carry[6])
