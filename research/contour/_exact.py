"""Exact contour error and tracking error.

Contour error (Prévost 2012 §2.2, Fig 2): the shortest distance ``e_p`` from each actual point
``P_i`` to the reference path, found with a spatial index plus local projection
(:func:`research.contour._geometry.project`). Tracking error: the time-linked axis differences
``eps_i = R_i - P_i`` and their norm ``|P_i R_i|`` (Prévost §2.2).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from research.contour._geometry import as_reference, points_of, project
from research.drives import DriveResponse
from research.errors import ParameterError
from research.paths.polyline import Polyline
from research.trajectory import Trajectory


@dataclass(frozen=True)
class ContourError:
    """Exact contour error of N points against a reference path.

    Attributes:
        distance: ``(N,)`` shortest distance to the path [mm].
        vector: ``(N, d)`` ``P_i - foot_i`` [mm]: from the closest path point to the actual point.
        foot: ``(N, d)`` closest path points [mm].
        signed: ``(N,)`` for planar paths: the distance with the sign of ``t x (P - foot)``
            (positive to the left of the direction of travel); ``None`` for 1-D and 3-D paths.
    """

    distance: np.ndarray
    vector: np.ndarray
    foot: np.ndarray
    signed: np.ndarray | None

    @property
    def max(self) -> float:
        """Largest distance [mm]."""
        return float(np.max(self.distance))


def contour_error(path, actual) -> ContourError:
    """Exact contour error of ``actual`` against ``path``.

    Args:
        path: reference path: :class:`~research.paths.Polyline`, :class:`~research.paths.bspline.BSplinePath`,
            a :class:`~research.trajectory.Trajectory` (the curve it traces, from its exact profile)
            or ``(M, d)`` points of a densely sampled curve [mm].
        actual: ``(N, d)`` positions [mm], a Trajectory (its ``q``) or a DriveResponse (its ``position``).
    Returns:
        :class:`ContourError`.
    Raises:
        ParameterError: non-finite positions or a dimension mismatch.
    """
    p = points_of(actual)
    proj = project(path, p)
    vector = p - proj.foot
    signed = None
    if p.shape[1] == 2:
        side = proj.tangent[:, 0] * vector[:, 1] - proj.tangent[:, 1] * vector[:, 0]
        signed = np.where(side < 0, -proj.distance, proj.distance)
    return ContourError(proj.distance, vector, proj.foot, signed)


def brute_force_contour_error(path: Polyline, points, chunk: int = 256) -> np.ndarray:
    """Reference O(N M) contour error: every point against every segment (chunked to bound memory).

    For tests and benchmarks only; :func:`contour_error` gives the same distances in O((N + M) log M).

    Args:
        path: a :class:`Polyline` with M segments.
        points: ``(N, d)`` [mm].
    Returns:
        ``(N,)`` distances [mm].
    """
    ref = as_reference(path)
    if not isinstance(ref, Polyline):
        raise ParameterError(f"brute_force_contour_error needs a Polyline, got {type(path).__name__}")
    q = points_of(points, "points")
    a, ab = ref.points[:-1], np.diff(ref.points, axis=0)
    ab2 = np.sum(ab * ab, axis=1)
    out = np.empty(q.shape[0])
    for s in range(0, q.shape[0], chunk):
        qq = q[s : s + chunk, None, :]
        u = np.clip(np.sum((qq - a) * ab, axis=2) / ab2, 0.0, 1.0)
        out[s : s + chunk] = np.sqrt(np.min(np.sum((qq - a - u[..., None] * ab) ** 2, axis=2), axis=1))
    return out


@dataclass(frozen=True)
class TrackingError:
    """Axis tracking error ``eps = R - P`` (Prévost §2.2).

    Attributes:
        t: ``(N,)`` sample times [s].
        axis: ``(N, A)`` per-axis error [mm] (rad for rotary axes).
        norm: ``(N,)`` ``|P_i R_i|`` [mm].
    """

    t: np.ndarray
    axis: np.ndarray
    norm: np.ndarray


def _timed(x, name):
    if isinstance(x, DriveResponse) and name == "reference":
        raise ParameterError("reference must be the setpoint Trajectory or a (t, positions) pair, not a DriveResponse")
    if isinstance(x, (Trajectory, DriveResponse)):
        return np.asarray(x.t, dtype=np.float64), points_of(x, name), float(x.sample_period)
    if isinstance(x, tuple) and len(x) == 2:
        t = np.asarray(x[0], dtype=np.float64).ravel()
        return t, points_of(x[1], name), float(np.median(np.diff(t))) if t.size > 1 else 1.0
    raise ParameterError(f"{name} must be a Trajectory, a DriveResponse or a (t, positions) pair, got {type(x).__name__}")


def check_same_grid(reference, actual) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(t, R, P)`` after checking that reference and actual share one time grid.

    Raises:
        ParameterError: different sample counts, different axis counts or different sample times
            (the message gives both lengths or the first sample whose times differ).
    """
    t_r, R, Ts = _timed(reference, "reference")
    t_a, P, _ = _timed(actual, "actual")
    if R.shape[0] != P.shape[0] or t_r.size != t_a.size:
        raise ParameterError(
            f"reference and actual have different lengths: {R.shape[0]} reference samples, {P.shape[0]} actual "
            "samples; compare them on one time grid (resample one of them first)"
        )
    if t_r.size != R.shape[0] or t_a.size != P.shape[0]:
        raise ParameterError("reference/actual: the time vector and the positions have different lengths")
    if R.shape[1] != P.shape[1]:
        raise ParameterError(f"reference has {R.shape[1]} axes but actual has {P.shape[1]}")
    off = np.abs(t_r - t_a) > 1e-9 + 1e-6 * Ts
    if off.any():
        i = int(np.argmax(off))
        raise ParameterError(
            f"reference and actual are on different time grids: sample {i} is at t = {t_r[i]!r} s in the reference "
            f"and t = {t_a[i]!r} s in the actual motion"
        )
    return t_r, R, P


def tracking_error(reference, actual) -> TrackingError:
    """Axis tracking error ``R_i - P_i`` and its norm (Prévost §2.2).

    Args:
        reference: the setpoint :class:`Trajectory` or a ``(t, positions)`` pair [s], [mm].
        actual: :class:`DriveResponse`, :class:`Trajectory` or ``(t, positions)`` on the same grid.
    Returns:
        :class:`TrackingError`.
    Raises:
        ParameterError: different lengths or time grids (:func:`check_same_grid`).
    """
    t, R, P = check_same_grid(reference, actual)
    e = R - P
    return TrackingError(t, e, np.linalg.norm(e, axis=1))


def reference_dimension(path) -> int:
    """Number of coordinates of a reference path."""
    return as_reference(path).dim
