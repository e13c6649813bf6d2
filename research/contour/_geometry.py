"""Reference geometry for contour errors: exact closest points on a polyline, a B-spline, a sampled
curve or the curve traced by a :class:`~research.trajectory.Trajectory`, and dense polylines of them.

Every projection uses a spatial index (KD-tree) to find the basin and an exact local projection to
finish, so it costs O((N + M) log M) for N points against an M-piece path, never O(N M).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from research.drives import DriveResponse
from research.errors import ParameterError, PathError
from research.paths.bspline import BSplinePath
from research.paths.polyline import Polyline
from research.trajectory import Trajectory

#: spacing [mm] of the dense polyline that stands for a Trajectory's curve; its chord error is
#: spacing^2 kappa / 8, i.e. 1.25e-6 mm at a 20 mm radius.
TRAJECTORY_SPACING = 0.01


@dataclass(frozen=True)
class Projection:
    """Closest points of a reference path.

    Attributes:
        distance: ``(N,)`` distance [mm] from each point to the path.
        foot: ``(N, d)`` closest point on the path [mm].
        tangent: ``(N, d)`` unit tangent of the path at the foot (direction of travel).
    """

    distance: np.ndarray
    foot: np.ndarray
    tangent: np.ndarray


def points_of(actual, name: str = "actual") -> np.ndarray:
    """``(N, d)`` positions [mm] of an array, a :class:`Trajectory` (its ``q``) or a
    :class:`DriveResponse` (its ``position``)."""
    if isinstance(actual, Trajectory):
        p = np.asarray(actual.q, dtype=np.float64)
    elif isinstance(actual, DriveResponse):
        p = np.asarray(actual.position, dtype=np.float64)
    else:
        p = np.asarray(actual, dtype=np.float64)
        if p.ndim == 1:
            p = p[:, None]
    if p.ndim != 2 or p.shape[0] < 1:
        raise ParameterError(f"{name} must be (N, d) positions in mm, got shape {p.shape}")
    if not np.all(np.isfinite(p)):
        i = int(np.argwhere(~np.isfinite(p))[0, 0])
        raise ParameterError(f"{name} has a non-finite position at sample {i}")
    return p


def trajectory_polyline(trajectory: Trajectory, spacing: float = TRAJECTORY_SPACING) -> Polyline:
    """The curve traced by ``trajectory`` as a polyline with vertices about ``spacing`` [mm] apart,
    from its exact profile (or the O(Ts^4) Hermite interpolant when it has none)."""
    t = np.asarray(trajectory.t, dtype=np.float64)
    q = np.asarray(trajectory.q, dtype=np.float64)
    if t.size < 2:
        raise PathError("a Trajectory used as a reference path needs at least 2 samples")
    step = np.linalg.norm(np.diff(q, axis=0), axis=1)
    k = max(1, int(np.ceil(step.max() / spacing)))
    fine = np.linspace(t[0], t[-1], (t.size - 1) * k + 1)
    pts = trajectory.evaluate(fine)
    return Polyline.from_points(pts, trajectory.axes, merge_duplicates=True, tol=1e-9)


def as_reference(path):
    """A :class:`Polyline` or :class:`BSplinePath` for any accepted reference path: those two as
    they are, a :class:`Trajectory` (the curve it traces) or an ``(M, d)`` array of points."""
    if isinstance(path, (Polyline, BSplinePath)):
        return path
    if isinstance(path, Trajectory):
        return trajectory_polyline(path)
    if isinstance(path, DriveResponse):
        raise ParameterError("a DriveResponse is an actual motion, not a reference path; pass its reference path")
    pts = np.asarray(path, dtype=np.float64)
    if pts.ndim != 2:
        raise PathError(f"reference path must be a Polyline, BSplinePath, Trajectory or (M, d) points, got shape {pts.shape}")
    return Polyline.from_points(pts, merge_duplicates=True, tol=1e-9)


def project(path, points) -> Projection:
    """Exact closest points on ``path`` (see :func:`as_reference`) for ``(N, d)`` ``points`` [mm]."""
    ref = as_reference(path)
    p = points_of(points, "points")
    if p.shape[1] != ref.dim:
        raise ParameterError(f"points have {p.shape[1]} coordinates but the reference path has {ref.dim}")
    if isinstance(ref, BSplinePath):
        d, u, foot = ref.project(p)
        tangent = ref(u, 1)
    else:
        d, seg, u = ref.project(p)
        a = ref.points[seg]
        foot = a + u[:, None] * (ref.points[seg + 1] - a)
        tangent = ref.directions[seg]
    tangent = tangent / np.maximum(np.linalg.norm(tangent, axis=1, keepdims=True), 1e-300)
    return Projection(d, foot, tangent)


def dense_polyline(path, spacing: float) -> tuple[np.ndarray, np.ndarray]:
    """Vertices ``(M + 1, d)`` of a polyline following ``path`` with pieces at most ``spacing`` [mm]
    long, and the arc length of each vertex [mm]. A B-spline is sampled equally in arc length (chord
    error ``spacing^2 kappa_max / 8``); a polyline keeps its vertices and subdivides its segments."""
    if not (np.isfinite(spacing) and spacing > 0):
        raise ParameterError(f"spacing must be a finite length > 0 mm, got {spacing!r}")
    ref = as_reference(path)
    if isinstance(ref, BSplinePath):
        n = max(2, int(np.ceil(ref.length / spacing)) + 1)
        pts = ref.sample(n)[1]
    else:
        pieces = np.maximum(1, np.ceil(ref.lengths / spacing).astype(np.int64))
        frac = [np.arange(k) / k for k in pieces]
        pts = np.concatenate(
            [ref.points[i] + f[:, None] * (ref.points[i + 1] - ref.points[i]) for i, f in enumerate(frac)]
            + [ref.points[-1:]]
        )
    arc = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(pts, axis=0), axis=1))])
    return pts, arc
