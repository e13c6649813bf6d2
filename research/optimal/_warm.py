"""Warm start: map any :class:`Trajectory` along the path (S-curve, FIR, ...) onto the phase grid.

Phase boundaries: phase ``k`` of the OCP ends near vertex ``P_{k+1}``; for the warm start it ends
at the time the trajectory comes closest to that vertex. The search for vertex ``k`` is limited to
the samples whose travelled distance ``integral |v| dt``, rescaled to the path's length (a motion
that cuts corners travels less, and on many short segments the shortfall adds up to more than half
a segment), lies within half a segment of the vertex's arc length, so a path that comes back near
an earlier vertex cannot confuse it. A solution of the OCP itself carries its phase boundaries
(:func:`grid_from_result`). Inside each phase
the ``N`` equal intervals get the trajectory's state at their nodes (from the exact profile when
the trajectory has one) and the mean jerk ``(a_{i+1} - a_i) / h`` that joins them.
"""

from __future__ import annotations

import numpy as np

from research.errors import ParameterError
from research.optimal._ocp import PhaseGrid
from research.paths.polyline import Polyline
from research.trajectory import Trajectory

_GOLDEN = 0.5 * (np.sqrt(5.0) - 1.0)


def phase_boundaries(traj: Trajectory, path: Polyline) -> np.ndarray:
    """Times [s] at which ``traj`` passes the vertices of ``path``, shape ``(M + 1,)``.

    Args:
        traj: a motion along ``path`` that starts on its first vertex and ends on its last.
        path: the polyline [mm].

    Returns:
        ``0``, the closest-approach time of each interior vertex (refined by golden-section search
        on the exact profile when there is one), and the trajectory's duration.

    Raises:
        ParameterError: the trajectory has other axes, does not start and end on the path's end
            points, or does not pass the vertices in order.
    """
    if traj.n_axes != path.dim:
        raise ParameterError(f"warm_start has {traj.n_axes} axes but the path has {path.dim}")
    f = traj.evaluate
    duration = float(traj.duration)
    if traj.exact is not None:  # dense enough to resolve every segment
        t = np.linspace(0.0, duration, 64 * path.n_segments + 1)
        q = f(t, 0)
    else:
        t, q = np.asarray(traj.t), np.asarray(traj.q)
    for name, i, k in (("start", 0, 0), ("end", -1, -1)):
        if np.linalg.norm(q[i] - path.points[k]) > 1e-6 * max(path.length, 1.0):
            raise ParameterError(f"warm_start does not follow the path: it {name}s at {q[i].tolist()}, "
                                 f"not on the path's {name} point {path.points[k].tolist()}")
    travelled = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(q, axis=0), axis=1))])
    if travelled[-1] > 0:
        travelled *= path.length / travelled[-1]
    S, L = path.arc_length, path.lengths
    idx, first = [], 0
    for k in range(1, path.n_segments):
        near = np.flatnonzero((travelled >= S[k] - 0.5 * L[k - 1]) & (travelled <= S[k] + 0.5 * L[k]))
        near = near[near >= first]
        if near.size == 0:
            raise ParameterError(f"warm_start does not follow the path: it never comes near vertex {k} {path.points[k].tolist()}")
        first = int(near[np.argmin(np.linalg.norm(q[near] - path.points[k], axis=1))])
        idx.append(first)
    idx = np.asarray(idx, dtype=np.int64)
    times = t[idx] if idx.size else np.zeros(0)
    if traj.exact is not None and idx.size:
        lo, hi = t[np.maximum(idx - 1, 0)], t[np.minimum(idx + 1, t.size - 1)]
        target = path.points[1:-1]

        def dist(s):
            return np.linalg.norm(f(s, 0) - target, axis=1)

        for _ in range(50):
            a, b = hi - _GOLDEN * (hi - lo), lo + _GOLDEN * (hi - lo)
            left = dist(a) < dist(b)
            lo, hi = np.where(left, lo, a), np.where(left, b, hi)
        times = 0.5 * (lo + hi)
    times = np.concatenate([[0.0], times, [duration]])
    if np.any(np.diff(times) <= 0):
        k = int(np.argmin(np.diff(times) > 0))
        raise ParameterError(f"warm_start passes vertex {k + 1} no later than vertex {k}; it does not follow the path in order")
    return times


def grid_from_trajectory(traj: Trajectory, path: Polyline, intervals: int) -> PhaseGrid:
    """The warm-start trajectory on the phase grid of ``path`` with ``intervals`` per phase."""
    return grid_at(traj, phase_boundaries(traj, path), path, intervals)


def grid_from_result(durations: np.ndarray, traj: Trajectory, path: Polyline, intervals: int) -> PhaseGrid:
    """A solution of the OCP (its phase ``durations`` [s] and trajectory) on a grid of ``intervals``
    per phase: the same phase boundaries, the exact profile at the new nodes."""
    return grid_at(traj, np.concatenate([[0.0], np.cumsum(durations)]), path, intervals)


def grid_at(traj: Trajectory, times: np.ndarray, path: Polyline, intervals: int) -> PhaseGrid:
    """``traj`` on the phase grid whose phase boundaries are ``times`` ``(M + 1,)`` [s]."""
    durations = np.diff(times)
    frac = np.arange(intervals) / intervals
    nodes = np.concatenate([(times[:-1, None] + durations[:, None] * frac[None, :]).ravel(), times[-1:]])
    f = traj.evaluate
    states = np.stack([f(nodes, nu) for nu in range(3)], axis=1)
    states[-1, 0] = path.points[-1]
    states[-1, 1:] = 0.0  # the motion ends at rest on the last vertex
    h = np.repeat(durations / intervals, intervals)
    jerks = np.diff(states[:, 2, :], axis=0) / h[:, None]
    return PhaseGrid(durations, states, jerks)
