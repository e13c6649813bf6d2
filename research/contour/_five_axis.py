"""The thesis' 5-axis contour-error study (Sencer 2009 §4.5, Fig 4.6): the eq 4.36 path interpolated
at 50 mm/s, run through the Table 6.3 axis models, with the exact tool-tip contour error and the
three Frenet-frame estimates."""

from __future__ import annotations

from dataclasses import dataclass

import jax
import jax.numpy as jnp
import numpy as np

from research.contour._cec import simulate_setpoint
from research.contour._frenet import (
    FrenetEstimates,
    OrientationContourError,
    exact_orientation_contour_error,
    exact_tip_contour_error,
    frenet_contour_estimates,
    orientation_contour_error,
    tip_reference,
)
from research.drives import DriveResponse, table_6_3_closed_loop
from research.errors import ParameterError
from research.interpolators import fir_interpolate
from research.paths.kinematics5 import TableTiltingAC
from research.paths.polyline import Polyline
from research.trajectory import Trajectory

#: eq 4.36: |dP/dl| = sqrt(15^2 + 5^2 + 15^2) [mm/rad] is constant, so l = s / sqrt(475)
_TIP_SPEED = float(np.sqrt(475.0))
AXES5 = ("x", "y", "z", "a", "c")


def _eq436_axes(machine: TableTiltingAC):
    def q_of_l(l):
        tip = jnp.stack([15 * jnp.cos(l) + 5 * jnp.sin(l), 15 * jnp.sin(l) - 5 * jnp.cos(l), 15 * l])
        return machine.inverse_with_angles(tip, jnp.arccos(jnp.sin(l) / 5), jnp.arctan(jnp.cos(l) / 5))
    d1 = jax.jacfwd(q_of_l)
    d2 = jax.jacfwd(d1)
    d3 = jax.jacfwd(d2)
    return jax.jit(jax.vmap(lambda l: (q_of_l(l), d1(l), d2(l), d3(l))))


def eq436_trajectory(machine: TableTiltingAC | None = None, *, feed: float = 50.0, acceleration: float = 1500.0,
                     sample_period: float = 1e-3) -> Trajectory:
    """Axis trajectory ``[x, y, z, a, c]`` for the thesis eq 4.36 path (Fig 4.5).

    The tip arc length ``s(t)`` is a jerk-limited FIR profile (Sencer 2015) with cruise ``feed`` (50 mm/s,
    thesis §4.5) and peak tangential acceleration ``acceleration`` (1500 mm/s^2: ``T1 = F / A``,
    ``T2 = T1 / 2``); ``l = s / sqrt(475)``; ``q(l)`` by eq 3.21/4.6 and its time derivatives by the
    chain rule (``q' = q_l l'``, ``q'' = q_ll l'^2 + q_l l''``, ``q''' = q_lll l'^3 + 3 q_ll l' l'' + q_l l'''``).

    Args:
        machine: kinematics (default: all offsets zero).
        feed: cruise tip feed [mm/s]; acceleration: [mm/s^2]; sample_period: ``Ts`` [s].
    """
    machine = TableTiltingAC() if machine is None else machine
    if not (feed > 0 and acceleration > 0):
        raise ParameterError(f"feed and acceleration must be > 0, got {feed!r} mm/s, {acceleration!r} mm/s^2")
    length = 4 * np.pi * _TIP_SPEED
    T1 = feed / acceleration
    s_traj = fir_interpolate(Polyline([[0.0], [length]]), feed, [T1, T1 / 2], 0.0, sample_period)
    s, ds, dds, ddds = (np.asarray(x)[:, 0] / _TIP_SPEED for x in (s_traj.q, s_traj.v, s_traj.a, s_traj.j))
    q, g1, g2, g3 = (np.asarray(x) for x in _eq436_axes(machine)(jnp.asarray(s)))
    v = g1 * ds[:, None]
    a = g2 * ds[:, None] ** 2 + g1 * dds[:, None]
    j = g3 * ds[:, None] ** 3 + 3 * g2 * (ds * dds)[:, None] + g1 * ddds[:, None]
    return Trajectory(s_traj.t, q, v, a, j, s_traj.duration, None, AXES5, sample_period)


@dataclass(frozen=True)
class FiveAxisContourStudy:
    """Thesis Fig 4.6 data.

    Attributes:
        t: ``(N,)`` [s]; exact: ``(N,)`` true tip contour error [mm];
        estimates: the Frenet estimates; orientation: eq 4.35 estimate; orientation_exact: ``(N,)`` [rad].
        reference: the axis trajectory; response: the simulated axes.
    """

    t: np.ndarray
    exact: np.ndarray
    estimates: FrenetEstimates
    orientation: OrientationContourError
    orientation_exact: np.ndarray
    reference: Trajectory
    response: DriveResponse

    def discrepancy(self, name: str) -> np.ndarray:
        """``|estimate - exact|`` [mm] for ``name`` in basic / shifted / compensated."""
        if name not in ("basic", "shifted", "compensated"):
            raise ParameterError(f"estimate name must be basic, shifted or compensated, got {name!r}")
        return np.abs(getattr(self.estimates, name) - self.exact)


def five_axis_contour_study(machine: TableTiltingAC | None = None, drives=None, *, sample_period: float = 1e-3,
                            friction: str = "exact") -> FiveAxisContourStudy:
    """Run thesis §4.5: eq 4.36 trajectory, Table 6.3 closed-loop axis models (one per axis, with their
    Coulomb friction ``dc``), exact tip contour error vs the basic / shifted / compensated estimates,
    and the orientation contour error (eq 4.35) vs its exact value."""
    machine = TableTiltingAC() if machine is None else machine
    ref = eq436_trajectory(machine, sample_period=sample_period)
    drives = tuple(table_6_3_closed_loop(a) for a in AXES5) if drives is None else drives
    resp = simulate_setpoint(ref, drives, friction)
    reference = tip_reference(ref, machine)
    P = np.asarray(machine.forward(jnp.asarray(resp.position))[0])
    t = np.asarray(ref.t)
    est = frenet_contour_estimates(reference, t, P)
    exact = exact_tip_contour_error(reference, float(t[0]), float(t[-1]), P)
    ori = orientation_contour_error(ref.q, ref.v, resp.position)
    fine = ref.evaluate(np.linspace(t[0], t[-1], 20 * t.size))
    ori_exact = exact_orientation_contour_error(fine, np.asarray(resp.position))
    return FiveAxisContourStudy(t, exact, est, ori, ori_exact, ref, resp)
