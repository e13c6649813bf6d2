"""Figures of merit shared by every comparison: cycle time, contour and corner error, peak kinematics.

All take a :class:`~research.trajectory.Trajectory` (and the reference path where relevant). When
the trajectory carries its exact profile, extrema are refined between samples (golden-section
search on the exact profile), so results do not depend on where the samples happen to fall.
Units: s, mm, mm/s, mm/s^2, mm/s^3.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np
from scipy.spatial import cKDTree

from research.limits import AxisLimits
from research.paths.polyline import Polyline
from research.trajectory import Trajectory

_GOLDEN = 0.5 * (np.sqrt(5.0) - 1.0)


def cycle_time(traj: Trajectory) -> float:
    """Motion time [s] (exact when the producer knows it, e.g. FIR: ``sum T_v + T_d + sum (T_d - T_k)``)."""
    return float(traj.duration)


def contour_errors(traj: Trajectory, path: Polyline) -> np.ndarray:
    """Exact distance [mm] from each trajectory sample to the polyline, shape ``(N,)``."""
    return path.distance(np.asarray(traj.q))


def max_contour_error(traj: Trajectory, path: Polyline, candidates: int = 16) -> float:
    """Maximum distance [mm] from the trajectory to the polyline (or to a ``ToolPath``: any path
    with ``distance``), refined between samples.

    The ``candidates`` largest local maxima of the sampled distance are refined on
    ``[t_i - Ts, t_i + Ts]`` when the trajectory has an exact profile.
    """
    d = contour_errors(traj, path)
    if traj.exact is None or d.size < 3:
        return float(d.max())
    peaks = _top_local_extrema(d, candidates)
    t = np.asarray(traj.t)
    lo, hi = t[np.maximum(peaks - 1, 0)], t[np.minimum(peaks + 1, d.size - 1)]
    f = traj.evaluator()
    best = _golden_min(lambda s: -path.distance(f(s)), lo, hi)
    return float(max(d.max(), -best.min()))


def corner_errors(traj: Trajectory, path: Polyline, candidates: int = 8) -> np.ndarray:
    """Distance [mm] from each interior vertex of ``path`` to the trajectory, shape ``(M - 1,)``.

    The trajectory samples nearest to each vertex are found with a KD-tree; with an exact profile
    those that are local minima of the sampled distance to the vertex are refined on
    ``[t_i - Ts, t_i + Ts]`` (the others lie on a slope down to a sample next to them).
    """
    vertices = path.corners
    if vertices.shape[0] == 0:
        return np.zeros(0)
    q = np.asarray(traj.q)
    k = min(candidates, q.shape[0])
    d, idx = cKDTree(q).query(vertices, k=k)
    d, idx = d.reshape(len(vertices), k), idx.reshape(len(vertices), k)
    if traj.exact is None:
        return d.min(axis=1)
    t = np.asarray(traj.t)
    n = q.shape[0]
    # refined: the candidates that are local minima of the sampled distance to their vertex (the
    # others lie on a slope down to a neighbour, whose own bracket holds the minimum between them)
    before = np.linalg.norm(q[np.maximum(idx - 1, 0)] - vertices[:, None, :], axis=-1)
    after = np.linalg.norm(q[np.minimum(idx + 1, n - 1)] - vertices[:, None, :], axis=-1)
    row, col = np.nonzero((d <= before) & (d <= after))
    best = d.min(axis=1)
    if row.size:
        i = idx[row, col]
        lo, hi = t[np.maximum(i - 1, 0)], t[np.minimum(i + 1, n - 1)]
        f = traj.evaluator()
        refined = _golden_min(lambda s: np.linalg.norm(f(s) - vertices[row], axis=-1), lo, hi)
        np.minimum.at(best, row, refined)
    return best


def peak_axis_values(traj: Trajectory, nu: int) -> np.ndarray:
    """Peak ``|d^nu q / dt^nu|`` per axis over the motion (``nu`` = 1, 2, 3), shape ``(A,)``.

    With an exact profile the break points (where piecewise-polynomial derivatives peak) are added
    to the samples and the largest sampled local maxima are refined between samples.
    """
    return _peak_values(traj, _realized(traj), nu)


def _realized(traj: Trajectory):
    """The exact profile without pieces of rounding length, whose jumping derivative no motion
    realizes (a golden search found a 1.1e-16 s piece of a limit-holding plan at 1.7x its jerk
    limit); None without one."""
    return None if traj.exact is None else traj.evaluator().realized()


def _peak_values(traj: Trajectory, f, nu: int) -> np.ndarray:
    """:func:`peak_axis_values` on the realized profile ``f`` (:func:`_realized`, made once for
    every order by :func:`summarize`)."""
    samples = np.abs(np.asarray((traj.q, traj.v, traj.a, traj.j)[nu]))
    peak = samples.max(axis=0)
    if f is None:
        return peak
    breaks = f.breaks
    # both one-sided values at each break: derivatives of order >= degree jump there
    eps = 1e-12 * max(1.0, float(breaks[-1]))
    left, right = f(breaks - eps, nu), f(breaks + eps, nu)
    peak = np.maximum(peak, np.maximum(np.abs(left).max(axis=0), np.abs(right).max(axis=0)))
    # a jump in the derivative below (e.g. the acceleration of a single FIR filter) makes this one
    # a Dirac impulse: report it as unbounded rather than as the zero seen between the jumps
    # (less the change of a continuous one over the 2 eps between its one-sided values, the
    # trapezoid of this one's: at a break 1,200 s into a motion that change alone was 4e-5 mm/s)
    below = f(breaks + eps, nu - 1) - f(breaks - eps, nu - 1) - eps * (left + right)
    scale = np.abs(np.asarray((traj.q, traj.v, traj.a, traj.j)[nu - 1])).max(axis=0)
    # a jump counts from 1e-6 of its axis's peak and 1e-9 of the largest axis's: below that it is
    # the profile's rounding (an axis that barely moves read an acceleration step of 1.2e-7 mm/s^2,
    # 2e-6 of its own peak, as an impulse of jerk on a two-filter plan whose other axes ran at 10^3)
    jumps = np.abs(below).max(axis=0) > 1e-6 * np.maximum(scale, 1e-3 * float(scale.max()))
    peak = np.where(jumps, np.inf, peak)
    t = np.asarray(traj.t)
    for a in range(samples.shape[1]):
        peaks = _top_local_extrema(samples[:, a], 4)
        lo, hi = t[np.maximum(peaks - 1, 0)], t[np.minimum(peaks + 1, t.size - 1)]
        best = _golden_min(lambda s: -np.abs(f(s, nu)[..., a]), lo, hi)
        peak[a] = max(peak[a], -best.min())
    return peak


def peak_feed(traj: Trajectory) -> float:
    """Peak path speed ``max ||v||`` [mm/s] (sampled, refined between samples when exact)."""
    f = traj.feed
    if traj.exact is None or f.size < 3:
        return float(f.max())
    peaks = _top_local_extrema(f, 8)
    t = np.asarray(traj.t)
    lo, hi = t[np.maximum(peaks - 1, 0)], t[np.minimum(peaks + 1, f.size - 1)]
    ev = traj.evaluator()
    best = _golden_min(lambda s: -np.linalg.norm(ev(s, 1), axis=-1), lo, hi)
    return float(max(f.max(), -best.min()))


def limit_ratios(traj: Trajectory, limits: AxisLimits) -> dict[str, np.ndarray]:
    """Per-axis ``peak / limit`` of velocity, acceleration and jerk (exact peaks where possible);
    a value above 1 means the trajectory exceeds that limit."""
    return limits.ratios(*(peak_axis_values(traj, nu) for nu in (1, 2, 3)))


def within_limits(traj: Trajectory, limits: AxisLimits, rtol: float = 1e-6) -> bool:
    """True when every per-axis peak is at most ``limit * (1 + rtol)``."""
    return all(np.all(r <= 1 + rtol) for r in limit_ratios(traj, limits).values())


@dataclass(frozen=True)
class MotionMetrics:
    """The standard comparison row. Per-axis arrays follow ``axes``."""

    axes: tuple[str, ...]
    cycle_time: float  # s
    max_contour_error: float  # mm
    max_corner_error: float  # mm
    corner_errors: np.ndarray  # mm, one per interior vertex
    peak_velocity: np.ndarray  # mm/s per axis
    peak_acceleration: np.ndarray  # mm/s^2 per axis
    peak_jerk: np.ndarray  # mm/s^3 per axis
    peak_feed: float  # mm/s

    def as_dict(self) -> dict:
        """JSON-ready dictionary (arrays become lists)."""
        return {k: (v.tolist() if isinstance(v, np.ndarray) else v) for k, v in asdict(self).items()}


def summarize(traj: Trajectory, path: Polyline, programmed=None) -> MotionMetrics:
    """All metrics of ``traj`` against ``path``; the contour error against ``programmed`` instead
    where given (a G-code program's blocks, ``ToolPath``: its arcs exact, where ``path`` holds them
    as chords within a chord tolerance, which would count in the error)."""
    corners = corner_errors(traj, path)
    realized = _realized(traj)
    return MotionMetrics(
        axes=traj.axes,
        cycle_time=cycle_time(traj),
        max_contour_error=max_contour_error(traj, path if programmed is None else programmed),
        max_corner_error=float(corners.max()) if corners.size else 0.0,
        corner_errors=corners,
        peak_velocity=_peak_values(traj, realized, 1),
        peak_acceleration=_peak_values(traj, realized, 2),
        peak_jerk=_peak_values(traj, realized, 3),
        peak_feed=peak_feed(traj),
    )


def _top_local_extrema(x: np.ndarray, count: int) -> np.ndarray:
    """Indices of the ``count`` largest local maxima of a 1-D array (plateaus included)."""
    inner = np.flatnonzero((x[1:-1] >= x[:-2]) & (x[1:-1] >= x[2:])) + 1
    # ascending and distinct already (the ends are not among ``inner``, which lies in 1 .. n - 2)
    idx = np.concatenate([[0], inner, [x.size - 1]] if x.size > 1 else [np.arange(x.size)]).astype(np.int64)
    if idx.size <= count:
        return idx[np.argsort(x[idx])[::-1]]
    top = np.argpartition(x[idx], idx.size - count)[idx.size - count:]  # the count largest, unordered
    return idx[top[np.argsort(x[idx[top]])[::-1]]]


def _golden_min(f, lo: np.ndarray, hi: np.ndarray, steps: int = 60) -> np.ndarray:
    """Vectorised golden-section minimisation of ``f`` on each bracket ``[lo, hi]``; returns minima.

    Each step keeps one interior point and its value and evaluates ``f`` once, at the new point (the
    kept one is where the new bracket's golden point lies: ``1 - G = G^2``); ``steps`` shrinks of
    the bracket by ``G = 0.618`` (60: a bracket of 2 ms ends below 1e-15 s, under the float64
    resolution of the times)."""
    lo, hi = np.array(lo, dtype=np.float64), np.array(hi, dtype=np.float64)
    a, b = hi - _GOLDEN * (hi - lo), lo + _GOLDEN * (hi - lo)
    fa, fb = f(a), f(b)
    for _ in range(steps - 1):
        left = fa < fb  # the minimum is in [lo, b]: b moves to a; else in [a, hi]: a moves to b
        lo, hi = np.where(left, lo, a), np.where(left, b, hi)
        a, b = np.where(left, hi - _GOLDEN * (hi - lo), b), np.where(left, a, lo + _GOLDEN * (hi - lo))
        fx = f(np.where(left, a, b))
        fa, fb = np.where(left, fx, fb), np.where(left, fa, fx)
    left = fa < fb
    lo, hi = np.where(left, lo, a), np.where(left, b, hi)
    return f(0.5 * (lo + hi))
