"""The reference a contour controller needs at every control period: joint commands ``q_ref, q'_ref,
q''_ref``, the tool-tip pose ``P_ref, P'_ref, P''_ref`` in the workpiece frame, the Frenet frame
``F = [t n b]`` of the tip path with ``F'`` and ``F''`` (eq 5.3-5.4), and the unit rotary reference
direction ``v`` of eq 5.20 with ``v'``.

Everything is computed from the path's parametric form ``P(l), a(l), c(l)`` and the scalar motion law
``l(t)`` (JAX forward-mode derivatives in ``l``, then the chain rule in time), so the frame is the
*geometric* Frenet frame of the tip curve: it is defined at rest (start and end of the motion, where
``P'_ref = 0`` and eq 4.16 divides by zero) and needs no fourth time derivative of the motion.

Frenet frame undefined: where the tip curve's curvature ``kappa = |P_l x P_ll| / |P_l|^3`` is below
``kappa_min`` (a straight stretch) the normal is undefined; :func:`parametric_reference` raises
:class:`~research.errors.FrenetFrameError` naming the parameter and time stretch. No fallback frame is
invented: on a straight stretch the split of the normal plane into normal and binormal is arbitrary,
and a caller with such a path must choose one. Where the rotary axes do not move (``|dq_R/dl| = 0``)
the orientation path is a point, every rotary error is a contour error, and ``v = 0`` makes eq 5.20
give ``eps_R = e_R``.
"""

from __future__ import annotations

import functools
from typing import Callable

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jax import Array

from research.errors import FrenetFrameError, ParameterError
from research.interpolators import fir_interpolate
from research.paths.kinematics5 import TableTiltingAC
from research.paths.polyline import Polyline
from research.trajectory import Trajectory

AXES5 = ("x", "y", "z", "a", "c")


class ContourReference(eqx.Module):
    """Sampled reference of a closed-loop 5-axis run (``N`` control periods).

    Attributes:
        t: ``(N,)`` [s]. q, qd, qdd: ``(N, 5)`` joint reference [mm, rad] and time derivatives.
        P, Pd, Pdd: ``(N, 3)`` reference tool tip [mm] and derivatives. F, Fd, Fdd: ``(N, 3, 3)`` Frenet
        frame (columns t, n, b) and its time derivatives [1, 1/s, 1/s^2]. v, vd: ``(N, 2)`` unit rotary
        reference direction of eq 5.20 and its derivative [1/s]. sample_period: ``T`` [s].
        has_frame: False for a joint-only reference (:func:`joint_reference`), whose tip and frame rows are
        zero and which only the SISO controller may run.
    """

    t: Array
    q: Array
    qd: Array
    qdd: Array
    P: Array
    Pd: Array
    Pdd: Array
    F: Array
    Fd: Array
    Fdd: Array
    v: Array
    vd: Array
    sample_period: float = eqx.field(static=True, default=1e-3)
    has_frame: bool = eqx.field(static=True, default=True)

    @property
    def n_samples(self) -> int:
        return int(self.t.shape[0])


def _frame_of(dP, ddP):
    t = dP / jnp.linalg.norm(dP)
    n = ddP - jnp.dot(ddP, t) * t
    n = n / jnp.linalg.norm(n)
    return jnp.stack([t, n, jnp.cross(t, n)], axis=-1)


@functools.partial(jax.jit, static_argnums=(0, 1, 2))
def _geometry(tip, a, c, machine, l):
    """``P, P_l, P_ll``, joints ``q`` and ``q_l .. q_lll``, rotary ``r_l, r_ll`` at every ``l`` (jit-cached
    per path functions)."""
    d = jax.jacfwd

    def joints(s):
        return machine.inverse_with_angles(tip(s), a(s), c(s))

    def rot(s):
        return jnp.stack([a(s), c(s)])

    return jax.vmap(lambda s: (tip(s), d(tip)(s), d(d(tip))(s), joints(s), d(joints)(s), d(d(joints))(s),
                               d(d(d(joints)))(s), d(rot)(s), d(d(rot))(s)))(l)


@functools.partial(jax.jit, static_argnums=(0,))
def _frames(tip, l):
    """Frenet frame ``F(l)`` and ``F_l, F_ll``."""
    d = jax.jacfwd

    def frame(s):
        return _frame_of(d(tip)(s), d(d(tip))(s))

    return jax.vmap(lambda s: (frame(s), d(frame)(s), d(d(frame))(s)))(l)


def parametric_reference(tip: Callable, a: Callable, c: Callable, l, ld, ldd, lddd, t, machine: TableTiltingAC,
                         sample_period: float, *, kappa_min: float = 1e-6) -> tuple[ContourReference, Trajectory]:
    """Reference of a path given as ``P(l)`` [mm], ``a(l)``, ``c(l)`` [rad] and a motion law ``l(t)``.

    Args:
        tip, a, c: JAX-traceable functions of a scalar ``l``.
        l, ld, ldd, lddd: ``(N,)`` samples of ``l(t)`` and its first three time derivatives.
        t: ``(N,)`` sample times [s]; machine: the A/C kinematics (eq 4.6); sample_period: ``T`` [s].
        kappa_min: smallest curvature [1/mm] at which the Frenet frame counts as defined.
    Returns:
        ``(reference, trajectory)``: the :class:`ContourReference` and the joint :class:`Trajectory`
        (for the exact contour errors of :mod:`research.contour`).
    Raises:
        FrenetFrameError: zero tip speed in ``l`` or curvature below ``kappa_min`` somewhere.
        ParameterError: arrays of different lengths.
    """
    l, ld, ldd, lddd, t = (np.asarray(x, dtype=np.float64).ravel() for x in (l, ld, ldd, lddd, t))
    if not (l.size == ld.size == ldd.size == lddd.size == t.size):
        raise ParameterError(f"l, l', l'', l''' and t must have one length; got {l.size}, {ld.size}, {ldd.size}, "
                             f"{lddd.size}, {t.size}")

    P, P1, P2, q, q1, q2, q3, r1, r2 = (np.asarray(x) for x in _geometry(tip, a, c, machine, jnp.asarray(l)))
    speed = np.linalg.norm(P1, axis=1)
    kappa = np.linalg.norm(np.cross(P1, P2), axis=1) / np.maximum(speed, 1e-300) ** 3
    bad = (speed <= 1e-12 * max(float(speed.max()), 1.0)) | (kappa < kappa_min)
    if bad.any():
        idx = np.flatnonzero(bad)
        i0, i1 = int(idx[0]), int(idx[-1])
        raise FrenetFrameError(
            f"Frenet frame undefined on {idx.size} of {l.size} samples, first at l = {l[i0]:.6g} (t = {t[i0]:.6g} s), "
            f"last at l = {l[i1]:.6g} (t = {t[i1]:.6g} s): curvature {kappa[i0]:.3g} 1/mm (need >= {kappa_min:g}) "
            f"or zero tip speed dP/dl; the tool-tip contour controller needs a curved tip path (module docstring)")

    F, F1, F2 = (np.asarray(x) for x in _frames(tip, jnp.asarray(l)))
    norm_r = np.linalg.norm(r1, axis=1)
    moving = norm_r > 1e-12 * max(float(norm_r.max()), 1e-300)
    v_l = np.where(moving[:, None], r1 / np.where(moving, norm_r, 1.0)[:, None], 0.0)
    # d/dl (r1/|r1|) = (I - v v^T) r2 / |r1|
    dv_l = np.where(moving[:, None], (r2 - v_l * np.sum(v_l * r2, axis=1, keepdims=True))
                    / np.where(moving, norm_r, 1.0)[:, None], 0.0)

    c1, c2 = ld[:, None], ld[:, None] ** 2
    Pd, Pdd = P1 * c1, P2 * c2 + P1 * ldd[:, None]
    qd = q1 * c1
    qdd = q2 * c2 + q1 * ldd[:, None]
    qddd = q3 * (ld**3)[:, None] + 3 * q2 * (ld * ldd)[:, None] + q1 * lddd[:, None]
    Fd = F1 * ld[:, None, None]
    Fdd = F2 * (ld**2)[:, None, None] + F1 * ldd[:, None, None]
    ref = ContourReference(jnp.asarray(t), *(jnp.asarray(x) for x in (q, qd, qdd, P, Pd, Pdd, F, Fd, Fdd, v_l, dv_l * c1)),
                           sample_period=float(sample_period))
    traj = Trajectory(t, q, qd, qdd, qddd, np.float64(t[-1]), None, AXES5, float(sample_period))
    return ref, traj


#: eq 4.36: |dP/dl| = sqrt(15^2 + 5^2 + 15^2) mm/rad is constant, so l = s / sqrt(475)
EQ436_TIP_SPEED = float(np.sqrt(475.0))


def _eq436_tip(l):
    return jnp.stack([15 * jnp.cos(l) + 5 * jnp.sin(l), 15 * jnp.sin(l) - 5 * jnp.cos(l), 15 * l])


def _eq436_a(l):
    return jnp.arccos(jnp.sin(l) / 5)


def _eq436_c(l):
    return jnp.arctan(jnp.cos(l) / 5)


def eq436_reference(machine: TableTiltingAC | None = None, *, feed: float = 50.0, acceleration: float = 1500.0,
                    sample_period: float = 1e-3) -> tuple[ContourReference, Trajectory]:
    """Reference on the thesis' Fig 5.5 path (eq 4.36, ``l`` in [0, 4 pi], tip length 273.87 mm).

    Motion law: the tip arc length ``s(t)`` is the same jerk-limited FIR profile as
    :func:`research.contour.eq436_trajectory` (cruise ``feed``, thesis §5.4 "maximum cruise speed of
    50 mm/sec and cubic acceleration/decelerations of 1500 mm/sec^2"; read as ``T1 = F / A``,
    ``T2 = T1 / 2``), and ``l = s / sqrt(475)``.

    Args:
        machine: kinematics (default: all offsets zero, as in :mod:`research.contour`).
        feed: cruise tip feed [mm/s]; acceleration: [mm/s^2]; sample_period: control period ``T`` [s].
    Returns:
        ``(ContourReference, Trajectory)``.
    """
    machine = TableTiltingAC() if machine is None else machine
    if not (np.isfinite(feed) and np.isfinite(acceleration) and feed > 0 and acceleration > 0):
        raise ParameterError(f"feed and acceleration must be finite and > 0, got {feed!r} mm/s, {acceleration!r} mm/s^2")
    length = 4 * np.pi * EQ436_TIP_SPEED
    T1 = feed / acceleration
    s = fir_interpolate(Polyline([[0.0], [length]]), feed, [T1, T1 / 2], 0.0, sample_period)
    l, ld, ldd, lddd = (np.asarray(x)[:, 0] / EQ436_TIP_SPEED for x in (s.q, s.v, s.a, s.j))
    return parametric_reference(_eq436_tip, _eq436_a, _eq436_c, l, ld, ldd, lddd, np.asarray(s.t), machine, sample_period)


def joint_reference(trajectory: Trajectory, sample_period: float) -> ContourReference:
    """A joint-only reference for the SISO controller: ``trajectory`` (axes x, y, z, a, c) evaluated at
    every control period ``sample_period`` [s] by :meth:`Trajectory.evaluate` (exact profile, or the
    cubic Hermite interpolant of its samples), with zero tip / frame rows and ``has_frame = False``.

    Raises:
        ParameterError: a trajectory without the five axes, or a non-positive period.
    """
    if tuple(trajectory.axes) != AXES5:
        raise ParameterError(f"joint_reference needs axes {AXES5}, got {tuple(trajectory.axes)}")
    if not (np.isfinite(sample_period) and sample_period > 0):
        raise ParameterError(f"sample_period must be > 0 s, got {sample_period!r}")
    t0, t1 = float(np.asarray(trajectory.t)[0]), float(np.asarray(trajectory.t)[-1])
    t = t0 + np.arange(int(np.floor((t1 - t0) / sample_period + 1e-9)) + 1) * sample_period
    ev = trajectory.evaluator()
    q, qd, qdd = (np.asarray(ev(t, nu), dtype=np.float64) for nu in range(3))
    N = t.size
    z3, z33, z2 = jnp.zeros((N, 3)), jnp.zeros((N, 3, 3)), jnp.zeros((N, 2))
    return ContourReference(jnp.asarray(t), jnp.asarray(q), jnp.asarray(qd), jnp.asarray(qdd), z3, z3, z3, z33, z33, z33,
                            z2, z2, sample_period=float(sample_period), has_frame=False)
