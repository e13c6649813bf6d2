"""Cornering tolerance held *after the servo* (beyond Sencer 2015).

Eq 13/14 bound the distance from each corner vertex to the FIR *reference*. The drive lags the
reference, so the actual path cuts the corner further (on the Fig 6 diamond through the Table 6.1
drive: 537 um for eps = 500 um). The option here plans the FIR at a reduced tolerance ``eps'``
chosen so that the *simulated actual* corner error is at most ``eps``:

    eps'_{k+1} = eps'_k - (e_k - eps),      e_k = max_j |V_j - actual path(eps'_k)|,

starting at ``eps'_0 = eps``: the drive's excess ``e_k - eps'_k`` is subtracted from the target.
The excess depends only weakly on ``eps'`` (the lag is set by the feed and the drive), so this
fixed point settles in a few simulations; it stops once ``e_k <= eps`` (to ``atol``) and raises
:class:`~research.errors.ConvergenceError` otherwise. The timing of the FIR stays the paper's (eq
11-14), so the spectral zeros of eq 10 stay on the modes, unlike a mirror correction of the
reference (:func:`~research.contour.mirror_passes`), which changes its spectrum.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.interpolate import CubicSpline

from research.errors import ConvergenceError, ParameterError
from research.trajectory import Trajectory


def vertex_distances(q: np.ndarray, t: np.ndarray, vertices: np.ndarray, step: float = 1e-5) -> np.ndarray:
    """Distance [mm] from each vertex ``(K, d)`` to the curve through samples ``q`` ``(N, d)`` at
    times ``t`` ``(N,)`` [s] (cubic spline, evaluated every ``step`` s): eq 13/14's corner error
    when ``q`` is the reference, the corner error after the servo when ``q`` is the actual motion.

    Example:
        >>> t = np.linspace(0.0, 1.0, 11)
        >>> q = np.column_stack([t, np.zeros_like(t)])
        >>> vertex_distances(q, t, np.array([[0.5, 0.25]])).round(6).tolist()
        [0.25]
    """
    vertices = np.atleast_2d(np.asarray(vertices, dtype=np.float64))
    cs = CubicSpline(np.asarray(t, dtype=np.float64), np.asarray(q, dtype=np.float64))
    P = cs(np.arange(float(t[0]), float(t[-1]), step))
    return np.array([float(np.min(np.linalg.norm(P - V, axis=1))) for V in vertices])


def held_at_rest(traj: Trajectory, horizon: float) -> Trajectory:
    """The same motion, held at rest at its end point until ``horizon`` [s] (so a drive settles)."""
    n = int(np.ceil(horizon / traj.sample_period)) + 1
    k = traj.n_samples
    if n <= k:
        return traj
    t = np.arange(n) * traj.sample_period
    rest = np.zeros((n - k, traj.n_axes))
    q = np.vstack([np.asarray(traj.q), np.repeat(np.asarray(traj.q[-1:]), n - k, axis=0)])
    v, a, j = (np.vstack([np.asarray(x), rest]) for x in (traj.v, traj.a, traj.j))
    return Trajectory(t, q, v, a, j, traj.duration, traj.exact, traj.axes, traj.sample_period)


@dataclass(frozen=True)
class ServoTolerance:
    """Result of :func:`servo_tolerance`.

    Attributes:
        tolerance: the reduced tolerance ``eps'`` the FIR was planned at [mm].
        reference: the FIR reference planned at it.
        corner_error: ``(K,)`` corner errors of the simulated actual path [mm] (all <= eps).
        history: ``(eps'_k, e_k)`` of every simulation [mm].
    """

    tolerance: float
    reference: Trajectory
    corner_error: np.ndarray
    history: tuple[tuple[float, float], ...]


def servo_tolerance(plan, simulate_actual, vertices: np.ndarray, tolerance: float, *, settle: float = 1.0,
                    atol: float = 1e-4, max_simulations: int = 12) -> ServoTolerance:
    """Plan at the tolerance that makes the corner error after the servo at most ``tolerance``.

    Args:
        plan: ``eps' [mm] -> Trajectory`` (e.g. ``lambda e: fir_interpolate(path, F, delays, e)``).
        simulate_actual: ``Trajectory -> (N, d)`` actual positions [mm] on the trajectory's grid
            (e.g. ``lambda tr: np.asarray(simulate(drive, tr).position)``).
        vertices: ``(K, d)`` corner vertices of the programmed path [mm].
        tolerance: eps [mm] to hold after the servo, > 0.
        settle: rest [s] simulated after the motion, so the actual path reaches its end.
        atol: slack [mm] below ``tolerance`` at which the search stops (the excess is subtracted
            exactly, so the result usually lands within it).
        max_simulations: bound on the drive simulations.

    Returns:
        :class:`ServoTolerance`.

    Raises:
        ParameterError: a tolerance <= 0.
        ConvergenceError: no tolerance > 0 found within ``max_simulations`` (the drive alone
            cuts the corners by more than ``tolerance``).
    """
    if not (np.isfinite(tolerance) and tolerance > 0):
        raise ParameterError(f"servo_tolerance: tolerance must be finite and > 0 mm, got {tolerance!r}")
    eps_k, history = float(tolerance), []
    for _ in range(max_simulations):
        ref = plan(eps_k)
        held = held_at_rest(ref, float(ref.duration) + settle)
        err = vertex_distances(simulate_actual(held), np.asarray(held.t), vertices)
        e = float(np.max(err, initial=0.0))
        history.append((eps_k, e))
        if e <= tolerance * (1 + 1e-9):
            return ServoTolerance(eps_k, ref, err, tuple(history))
        # subtract the drive's excess; stay strictly below the last attempt if it barely moved
        step = e - tolerance
        eps_k = eps_k - max(step, atol)
        if eps_k <= 0:
            break
    raise ConvergenceError(f"servo_tolerance: corner error after the servo {history[-1][1] * 1e3:.1f} um still above "
                           f"{tolerance * 1e3:.1f} um after {len(history)} simulations (history {history})",
                           residual=history[-1][1] - tolerance, steps=len(history))
