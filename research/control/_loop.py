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

*Cost per sample* (benchmarks/bench_control.py, target <= 3x the SISO loop). Everything that depends only
on the reference is computed before the loop: the Frenet frame and its derivatives come with the
reference (:mod:`research.control._reference`) and are stacked once into ``[F | F' | F'']``, so one
reduction per period gives all six frame products. Per period only what depends on the measured state
is computed: the tip kinematics ``P, P', P''_rest`` in scalar closed form (two plane rotations, see
:func:`_tip_motion`). On XLA:CPU each ``dot`` of these sizes is a separate library call per period and
a Taylor-mode (``jet``) evaluation of the kinematics costs more than the rest of the law together; the
closed form took the contour / SISO cost ratio from 5-7x to about 2x (CPU time, same run).

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
import numpy as np
from jax import Array

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
    # v.e, v.e', v'.e in one reduction (fewer kernels per period on CPU)
    D = jnp.sum(jnp.stack([v, vd])[:, None, :] * jnp.stack([e, de])[None, :, :], axis=-1)
    ve, vde, vde_ = D[0, 0], D[0, 1], D[1, 0]
    eps = e - v * ve  # eq 5.20
    deps = de - vd * ve - v * (vde_ + vde)
    Ieps = Ieps + T * eps
    et = e + W * Ieps  # eq 5.22
    det = de + W * eps
    S = g.lam * et + det  # eq 5.23
    dh = dh + T * g.Gamma * S  # eq 5.24
    acc = g.lam * det + r["qdd"][3:] + W * deps
    u = m * acc + c * qd + g.Ks * S + dh  # eq 5.27
    return u, dh, Ieps, acc + g.Ks * S / m


def _rot(cs, sn, u0, u1):
    """Plane rotation ``[[cos, -sin], [sin, cos]] [u0, u1]`` (scalars)."""
    return cs * u0 - sn * u1, sn * u0 + cs * u1


def _tip_motion(machine: TableTiltingAC, q, qd, alpha):
    """Tool tip ``P`` (eq 4.5), ``P' = J q'`` and the part of ``P''`` not made by the Cartesian
    accelerations, ``J' q' + J_ac alpha`` (eq 4.10), for the rotary accelerations ``alpha = [a'', c'']``.

    ``P = R(a, c)^T k`` with ``k = diag(-1, -1, 1) ([x, y, z] - offset(a))`` (eq 4.5, 4.6) is a plane
    rotation by ``a`` of ``(k1, k2)`` into ``(w1, w2)``, then a plane rotation by ``c`` of ``(k0, w1)`` into
    ``(P0, P1)``, and ``P2 = w2``. For ``u = Rot(t) v``: ``u' = Rot v' + t' Jr u`` and
    ``u'' = Rot v'' + 2 t' Jr Rot v' + t'' Jr u - t'^2 u`` (``Jr [u0, u1] = [-u1, u0]``); dropping the
    Cartesian accelerations from ``v''`` gives ``P''_rest``. Scalar closed form: the jet (Taylor-mode)
    form of the same derivatives, and a stacked 3 x 3 form, cost 1-4 us per control period on CPU
    (benchmarks/bench_control.py). Equal to ``machine.forward`` and its jet to rounding (tested).
    """
    L = machine.L_ac
    sa, ca, sc, cc = jnp.sin(q[3]), jnp.cos(q[3]), jnp.sin(q[4]), jnp.cos(q[4])
    ad, cd, aa, ca_ = qd[3], qd[4], alpha[0], alpha[1]
    k0, k1, k2 = -q[0], -(q[1] + L * sa), q[2] - (L * ca + machine.L_ya - machine.L_t)
    k0d, k1d, k2d = -qd[0], -(qd[1] + L * ca * ad), qd[2] + L * sa * ad
    k1r, k2r = L * (sa * ad**2 - ca * aa), L * (ca * ad**2 + sa * aa)  # offset's part of k''
    # rotation by a
    w1, w2 = _rot(ca, sa, k1, k2)
    r1, r2 = _rot(ca, sa, k1d, k2d)
    w1d, w2d = r1 - ad * w2, r2 + ad * w1
    s1, s2 = _rot(ca, sa, k1r, k2r)
    w1r = s1 - 2 * ad * r2 - aa * w2 - ad**2 * w1
    w2r = s2 + 2 * ad * r1 + aa * w1 - ad**2 * w2
    # rotation by c of (k0, w1); k0'' is a Cartesian acceleration (dropped)
    P0, P1 = _rot(cc, sc, k0, w1)
    t0, t1 = _rot(cc, sc, k0d, w1d)
    P0d, P1d = t0 - cd * P1, t1 + cd * P0
    u0, u1 = _rot(cc, sc, 0.0 * k0, w1r)
    P0r = u0 - 2 * cd * t1 - ca_ * P1 - cd**2 * P0
    P1r = u1 + 2 * cd * t0 + ca_ * P0 - cd**2 * P1
    return jnp.stack([P0, P1, w2]), jnp.stack([P0d, P1d, w2d]), jnp.stack([P0r, P1r, w2r])


def _J_xyz_T(q, v):
    """``J_xyz^T v`` with ``J_xyz = dP/d[x, y, z] = R(a, c)^T diag(-1, -1, 1)`` (eq 4.5; independent of
    the offsets): ``diag(-1, -1, 1) R v``, ``R v = Rot(-a) about X of Rot(-c) about Z of v`` (eq 4.6)."""
    sa, ca, sc, cc = jnp.sin(q[3]), jnp.cos(q[3]), jnp.sin(q[4]), jnp.cos(q[4])
    u0, u1 = _rot(cc, -sc, v[0], v[1])
    w1, w2 = _rot(ca, -sa, u1, v[2])
    return jnp.stack([-u0, -w1, w2])


def _contour_law(g: ContourGains, plant, machine, r, q, qd, dh, IF, Ieps, T):
    m, c = plant.m, plant.c
    u_r, dh_r, Ieps, alpha_r = _orientation_law(g.rotary, g.W, m[3:], c[3:], r, q[3:], qd[3:], dh[3:], Ieps, T)

    # P, P' = J q', and the part of P'' not made by the Cartesian accelerations, J' q' + J_ac alpha_ac (eq 4.10)
    P, Pd, P2_rest = _tip_motion(machine, q, qd, alpha_r)
    Fall = r["Fall"]  # [F | F' | F''], (3, 9), stacked along the reference once (see _run)
    e, de = r["P"] - P, r["Pd"] - Pd
    # the six frame products F^T e, F^T e', F'^T e, F'^T e', F''^T e, F''^T e' in one reduction
    G = jnp.sum(Fall[:, :, None] * jnp.stack([e, de], -1)[:, None, :], axis=0)
    eF = G[0:3, 0]
    deF = G[0:3, 1] + G[3:6, 0]
    IF = IF + T * eF
    tg = g.tip
    CP, CI = 2 * tg.zeta * tg.wn, tg.wn**2
    S = deF + CP * eF + CI * IF  # eq 5.5
    mF = direction_inertia(plant)
    dF = dh[:3] + T * tg.Gamma * S  # eq 5.8
    rho = 2 * G[3:6, 1] + G[6:9, 0] + CP * deF + CI * eF + (tg.Ks * S + dF) / mF
    Pdd_des = r["Pdd"] + jnp.sum(Fall[:, :3] * rho[None, :], axis=1)
    # J_xyz = R(a, c)^T diag(-1, -1, 1) is orthogonal (eq 4.6), so its inverse is its transpose
    qdd_c = _J_xyz_T(q, Pdd_des - P2_rest)
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
        u_max: amplifier voltage limit [V], scalar or one per axis (None: no saturation).
        friction_width: 0 for the exact sign of eq 6.2, else the ``tanh`` width [mm/s] (for gradients).
        divergence_limit: axis error [mm or rad] beyond which the run is flagged diverged.
    Returns:
        :class:`ClosedLoopResult`.
    Raises:
        ParameterError: a SISO gain set without 5 axes, a non-positive limit, the contour controller on
            a joint-only reference, or reference rows of different lengths or with non-finite values.
    """
    machine = TableTiltingAC() if machine is None else machine
    if isinstance(controller, AxisSMC) and controller.lam.shape != (5,):
        raise ParameterError(f"SISO controller needs 5 axes (x, y, z, a, c), got {controller.lam.shape[0]} gain entries")
    if not isinstance(controller, (AxisSMC, ContourGains)):
        raise ParameterError(f"controller must be AxisSMC or ContourGains, got {type(controller).__name__}")
    if reference.q.shape[1:] != (5,):
        raise ParameterError(f"reference must have 5 axes, got q of shape {reference.q.shape}")
    _check_reference(reference)
    if isinstance(controller, ContourGains) and not reference.has_frame:
        raise ParameterError("the contour controller needs a reference with the tip path's Frenet frame "
                             "(parametric_reference / eq436_reference); this one is joint-only (joint_reference)")
    if u_max is not None:
        u_max = np.broadcast_to(np.asarray(u_max, dtype=np.float64), (5,)) if np.ndim(u_max) == 0 else np.asarray(u_max, dtype=np.float64)
        if u_max.shape != (5,):
            raise ParameterError(f"u_max must be a scalar or one limit per axis (x, y, z, a, c), got shape {u_max.shape}")
        if not np.all(np.isfinite(u_max) & (u_max > 0)):
            raise ParameterError(f"u_max must be > 0 V and finite for every axis, got {u_max}")
    if not divergence_limit > 0:
        raise ParameterError(f"divergence_limit must be > 0, got {divergence_limit!r}")
    return _run(plant, reference, controller, machine, jnp.full(5, jnp.inf) if u_max is None else jnp.asarray(u_max),
                float(friction_width), float(divergence_limit))


_REFERENCE_FIELDS = ("t", "q", "qd", "qdd", "P", "Pd", "Pdd", "F", "Fd", "Fdd", "v", "vd")


def _check_reference(reference: ContourReference) -> None:
    """Every row of the reference has the same length and (when the arrays are concrete, i.e. outside a
    trace) finite values; raises :class:`ParameterError` naming the field and the first bad sample."""
    N = reference.t.shape[0]
    for name in _REFERENCE_FIELDS:
        x = getattr(reference, name)
        if x.shape[:1] != (N,):
            raise ParameterError(f"ContourReference.{name} has {x.shape[0] if x.ndim else 0} rows, t has {N}")
        if isinstance(x, jax.core.Tracer):
            continue
        bad = ~np.isfinite(np.asarray(x).reshape(N, -1)).all(axis=1)
        if bad.any():
            k = int(np.argmax(bad))
            raise ParameterError(f"ContourReference.{name} is not finite at sample {k} (t = {float(reference.t[k]):.6g} s)"
                                 f"{'' if bad.sum() == 1 else f' and {int(bad.sum()) - 1} more samples'}")


@eqx.filter_jit
def _run(plant, reference, controller, machine, u_max, friction_width, divergence_limit):
    T = reference.sample_period
    Ad, Bd = plant.discretize(T)
    contour = isinstance(controller, ContourGains)
    # each loop reads only the reference rows its law uses; the contour law's frame and its derivatives
    # are stacked once here, outside the loop, so that one reduction per period gives all six products
    rows = dict(q=reference.q, qd=reference.qd, qdd=reference.qdd)
    if contour:
        rows.update(P=reference.P, Pd=reference.Pd, Pdd=reference.Pdd, v=reference.v, vd=reference.vd,
                    Fall=jnp.concatenate([reference.F, reference.Fd, reference.Fdd], axis=-1))

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
        # exact ZOH step per axis, elementwise (a batched 2 x 2 dot is a library call per period on CPU)
        qn = Ad[:, 0, 0] * q + Ad[:, 0, 1] * qd + Bd[:, 0] * w
        qdn = Ad[:, 1, 0] * q + Ad[:, 1, 1] * qd + Bd[:, 1] * w
        bad = ~jnp.all(jnp.isfinite(u)) | ~jnp.all(jnp.isfinite(qn)) | ~jnp.all(jnp.isfinite(qdn)) | jnp.any(jnp.abs(r["q"] - q) > divergence_limit)
        now = div | bad
        kdiv = jnp.where(now & ~div, k, kdiv)
        keep = lambda new, old: jnp.where(now, old, new)  # noqa: E731  frozen once diverged
        u_out = jnp.where(now, 0.0, u)
        carry = (keep(qn, q), keep(qdn, qd), keep(dh_n, dh), keep(IF_n, IF), keep(Ieps_n, Ieps), now, kdiv, k + 1)
        return carry, (q, qd, u_out, dh, sat)

    N = reference.t.shape[0]
    z5 = jnp.zeros(5)
    carry0 = (reference.q[0], reference.qd[0], z5, jnp.zeros(3), jnp.zeros(2), jnp.array(False), jnp.int32(N), jnp.int32(0))
    carry, (q, qd, u, dh, sat) = jax.lax.scan(step, carry0, rows, unroll=UNROLL)
    return ClosedLoopResult(q, qd, u, dh, sat, carry[5], carry[6])
