"""Contour error estimators of Sencer (2009) thesis §4.3-4.4: the basic, shifted and compensated
Frenet-frame estimates of the tool-tip contour error (eq 4.16-4.27) and the tool-orientation contour
error (eq 4.28-4.35), with the exact errors they approximate.

Sign convention (eq 4.14): tracking error ``e = P_ref - P`` (reference minus actual).

- Frenet frame at the reference point (eq 4.16-4.17): ``t = P'_ref / |P'_ref|``, ``n`` the unit part of
  ``P''_ref`` normal to ``t`` (so that t, n are "mutually orthogonal"), ``b = t x n``.
- Basic (eq 4.20): ``eps ~ e_n n + e_b b``; its size ``sqrt(e_n^2 + e_b^2) = |e - (e.t) t|``.
- Shifted (eq 4.21-4.22): delay ``t_d = e_t / |P'_ref(t)|``; frame taken at ``t - t_d``.
- Compensated (eq 4.23-4.27): ``h = P_ref(t) - P_ref(t - t_d)``; ``e~ = F~^T e + W F~^T h`` with
  ``W = diag(0, -1, -1)``, i.e. the normal/binormal parts of ``e - h`` in the shifted frame.
- Orientation (eq 4.35): ``eps_R = e_R - v (v^T e_R)`` for rotary errors ``e_R = [e_a, e_c]`` and the
  unit rotary reference velocity ``v``; ``eps_o = J_o eps_R`` (eq 4.34) in the workpiece frame.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import jax
import jax.numpy as jnp
import numpy as np

from research.contour._geometry import points_of
from research.errors import ParameterError
from research.paths.kinematics5 import TableTiltingAC, orientation_jacobian, tool_orientation
from research.paths.polyline import Polyline
from research.trajectory import Trajectory

#: a reference tool tip: times [s] -> (P, P', P''), each (N, 3) [mm, mm/s, mm/s^2]
TipReference = Callable[[np.ndarray], tuple[np.ndarray, np.ndarray, np.ndarray]]


def tip_reference(trajectory: Trajectory, machine: TableTiltingAC | None = None) -> TipReference:
    """The reference tool tip and its first two time derivatives at any time.

    Args:
        trajectory: reference axis motion; Cartesian ``(N, 2..3)`` when ``machine`` is None, else the
            five axes ``[x, y, z, a, c]`` [mm, rad].
        machine: 5-axis kinematics; the tip is then ``P(q(t))`` (eq 4.5) and its derivatives
            ``J q'`` and ``J q'' + (d/dt J) q'`` (eq 4.10), by JAX forward-mode differentiation.
    Returns:
        ``t -> (P, P', P'')``, each ``(len(t), 3)`` (planar paths padded with z = 0).
    """
    if machine is None:
        def cartesian(t):
            out = [np.asarray(trajectory.evaluate(np.atleast_1d(t), nu)) for nu in range(3)]
            return tuple(np.pad(x, ((0, 0), (0, 3 - x.shape[1]))) for x in out)
        return cartesian
    if trajectory.n_axes != 5:
        raise ParameterError(f"a 5-axis tip reference needs axes [x, y, z, a, c], got {trajectory.axes}")

    def tip(q):
        return machine.forward(q)[0]

    @jax.jit
    def derivatives(q, v, a):
        def first(qq, vv):
            return jax.jvp(tip, (qq,), (vv,))
        (P, dP), (_, ddP_v) = jax.jvp(lambda qq: first(qq, v), (q,), (v,))
        _, dP_a = jax.jvp(tip, (q,), (a,))
        return P, dP, ddP_v + dP_a

    def five_axis(t):
        t = np.atleast_1d(t)
        q, v, a = (jnp.asarray(trajectory.evaluate(t, nu)) for nu in range(3))
        return tuple(np.asarray(x) for x in jax.vmap(derivatives)(q, v, a))

    return five_axis


def _unit(x, eps=1e-300):
    return x / np.maximum(np.linalg.norm(x, axis=-1, keepdims=True), eps)


def frenet_frame(velocity, acceleration) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Unit tangent, normal and binormal (eq 4.16-4.17) from ``P'`` and ``P''`` ``(N, 3)``.

    Where ``P''`` has no part normal to ``t`` (straight motion) ``n`` is any unit vector normal to
    ``t``; the estimators' sizes do not depend on that choice."""
    t = _unit(velocity)
    n = acceleration - np.sum(acceleration * t, axis=1, keepdims=True) * t
    weak = np.linalg.norm(n, axis=1) <= 1e-12 * np.maximum(np.linalg.norm(acceleration, axis=1), 1.0)
    if weak.any():
        helper = np.where(np.abs(t[:, :1]) < 0.9, np.array([[1.0, 0, 0]]), np.array([[0, 1.0, 0]]))
        alt = helper - np.sum(helper * t, axis=1, keepdims=True) * t
        n = np.where(weak[:, None], alt, n)
    n = _unit(n)
    return t, n, np.cross(t, n)


@dataclass(frozen=True)
class FrenetEstimates:
    """The thesis' tool-tip contour error estimates at N samples.

    Attributes:
        basic, shifted, compensated: ``(N,)`` estimated contour error sizes [mm] (eq 4.20, 4.22, 4.27).
        delay: ``(N,)`` ``t_d`` of eq 4.21 [s] (positive: the actual tip lags the reference).
        tracking: ``(N, 3)`` tool-tip tracking error ``e = P_ref - P`` [mm].
    """

    basic: np.ndarray
    shifted: np.ndarray
    compensated: np.ndarray
    delay: np.ndarray
    tracking: np.ndarray


def frenet_contour_estimates(reference: TipReference, t, actual_tip, min_speed_ratio: float = 0.01) -> FrenetEstimates:
    """Basic, shifted and compensated Frenet-frame contour error estimates (thesis eq 4.20-4.27).

    Args:
        reference: ``t -> (P_ref, P'_ref, P''_ref)`` (see :func:`tip_reference`).
        t: ``(N,)`` sample times [s].
        actual_tip: ``(N, 3)`` actual tool-tip positions [mm] at those times (planar: ``(N, 2)``).
        min_speed_ratio: below this fraction of the peak reference speed (start and end of the motion)
            eq 4.21 divides by ~0; the delay is then taken as 0, so shifted = compensated = basic.
    Returns:
        :class:`FrenetEstimates`.
    Raises:
        ParameterError: lengths differ.
    """
    t = np.asarray(t, dtype=np.float64).ravel()
    P = points_of(actual_tip, "actual_tip")
    if P.shape[0] != t.size:
        raise ParameterError(f"actual_tip has {P.shape[0]} samples but t has {t.size}; they must be on one time grid")
    P = np.pad(P, ((0, 0), (0, 3 - P.shape[1])))
    R, dR, ddR = reference(t)
    e = R - P  # eq 4.14
    tan, _, _ = frenet_frame(dR, ddR)
    e_t = np.sum(e * tan, axis=1)

    def normal_size(vec, tangent):
        return np.linalg.norm(vec - np.sum(vec * tangent, axis=1, keepdims=True) * tangent, axis=1)

    basic = normal_size(e, tan)  # eq 4.20
    speed = np.linalg.norm(dR, axis=1)
    moving = speed > min_speed_ratio * speed.max()
    delay = np.where(moving, e_t / np.where(moving, speed, 1.0), 0.0)  # eq 4.21
    Rd, dRd, ddRd = reference(t - delay)
    tan_d, _, _ = frenet_frame(dRd, ddRd)  # eq 4.22
    shifted = normal_size(e, tan_d)
    h = R - Rd  # eq 4.23
    compensated = normal_size(e - h, tan_d)  # eq 4.24-4.27
    return FrenetEstimates(basic, shifted, compensated, delay, e)


def exact_tip_contour_error(reference: TipReference, t_start: float, t_end: float, actual_tip,
                            spacing: float = 0.02) -> np.ndarray:
    """True tool-tip contour error: the shortest distance from each actual tip to the reference tip
    curve ``{P_ref(tau), t_start <= tau <= t_end}`` (the thesis' iterative search, §4.5).

    A dense polyline of the curve (about ``spacing`` [mm] between vertices) with its KD-tree finds the
    basin; Newton on ``P'_ref(tau) . (P_ref(tau) - P) = 0`` finishes on the curve itself.

    Returns:
        ``(N,)`` distances [mm].
    """
    P = np.pad(points_of(actual_tip, "actual_tip"), ((0, 0), (0, 0)))
    P = np.pad(P, ((0, 0), (0, 3 - P.shape[1])))
    coarse = np.linspace(t_start, t_end, 2001)
    Rc = reference(coarse)[0]
    length = float(np.sum(np.linalg.norm(np.diff(Rc, axis=0), axis=1)))
    n = max(2001, int(np.ceil(length / spacing)) + 1)
    tau = np.linspace(t_start, t_end, n)
    pts = reference(tau)[0]
    keep = np.concatenate([[True], np.linalg.norm(np.diff(pts, axis=0), axis=1) > 1e-9])
    tau, pts = tau[keep], pts[keep]
    _, seg, u = Polyline(pts).project(P)
    lo, hi = tau[np.maximum(seg - 1, 0)], tau[np.minimum(seg + 2, tau.size - 1)]
    s = tau[seg] + u * (tau[seg + 1] - tau[seg])
    for _ in range(8):
        R, dR, ddR = reference(s)
        e = R - P
        g = np.sum(dR * e, axis=1)
        dg = np.sum(dR * dR, axis=1) + np.sum(ddR * e, axis=1)
        step = np.where(dg > 0, g / np.where(dg > 0, dg, 1.0), 0.0)
        s = np.clip(s - step, lo, hi)
    return np.linalg.norm(reference(s)[0] - P, axis=1)


@dataclass(frozen=True)
class OrientationContourError:
    """Tool orientation contour error estimate (thesis eq 4.28-4.35).

    Attributes:
        rotary: ``(N, 2)`` ``eps_R = [eps_a, eps_c]`` in joint coordinates [rad] (eq 4.35).
        workpiece: ``(N, 3)`` ``eps_o = J_o eps_R`` in the workpiece frame [rad] (eq 4.34).
        tracking: ``(N, 2)`` rotary tracking errors ``e_R = [e_a, e_c]`` [rad].
    """

    rotary: np.ndarray
    workpiece: np.ndarray
    tracking: np.ndarray


def orientation_contour_error(reference_q, reference_qdot, actual_q) -> OrientationContourError:
    """Eq 4.35: the rotary tracking errors minus their part along the rotary reference velocity.

    Args:
        reference_q: ``(N, 5)`` reference axes ``[x, y, z, a, c]`` (only a, c are used) [rad].
        reference_qdot: ``(N, 5)`` reference axis velocities [rad/s].
        actual_q: ``(N, 5)`` actual axes [rad].
    Returns:
        :class:`OrientationContourError`.
    """
    q, dq, qa = (np.asarray(x, dtype=np.float64) for x in (reference_q, reference_qdot, actual_q))
    if not (q.shape == dq.shape == qa.shape and q.ndim == 2 and q.shape[1] == 5):
        raise ParameterError(
            f"reference_q, reference_qdot and actual_q must all be (N, 5) [x, y, z, a, c]; got {q.shape}, {dq.shape}, {qa.shape}"
        )
    eR = q[:, 3:] - qa[:, 3:]
    v = _unit(dq[:, 3:])
    eps = eR - v * np.sum(v * eR, axis=1, keepdims=True)  # eq 4.35
    Jo = np.asarray(orientation_jacobian(q[:, 3], q[:, 4]))
    return OrientationContourError(eps, np.einsum("nij,nj->ni", Jo, eps), eR)


def exact_orientation_contour_error(reference_q_dense, actual_q) -> np.ndarray:
    """True orientation contour error: the angle [rad] from each actual tool axis to the closest
    orientation of the reference orientation path (thesis §4.5), given densely sampled reference
    rotary positions ``(M, 5)`` (or ``(M, 2)`` [a, c]). The path on the unit sphere is approximated by
    its chords; with chord length ``h`` the angle is exact to ``O(h^2)``.

    Returns:
        ``(N,)`` angles [rad].
    """
    ref = np.asarray(reference_q_dense, dtype=np.float64)
    act = np.asarray(actual_q, dtype=np.float64)
    O_ref = np.asarray(tool_orientation(ref[:, -2], ref[:, -1]))
    O_act = np.asarray(tool_orientation(act[:, -2], act[:, -1]))
    keep = np.concatenate([[True], np.linalg.norm(np.diff(O_ref, axis=0), axis=1) > 1e-12])
    _, seg, u = Polyline(O_ref[keep]).project(O_act)
    pts = O_ref[keep]
    foot = _unit(pts[seg] + u[:, None] * (pts[seg + 1] - pts[seg]))
    return np.arccos(np.clip(np.sum(foot * O_act, axis=1), -1.0, 1.0))
