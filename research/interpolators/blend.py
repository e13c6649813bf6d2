"""Geometric corner smoothing: the baseline of Sencer 2015 Fig 6.

Each corner is replaced by a curvature-continuous blend whose deviation from the vertex is the
tolerance, and the smoothed path is traversed with a feed profile that respects every axis'
velocity, acceleration and jerk limits (Sencer 2015 §4: "the tool must cruise at a constant speed
through the corners so that axis acceleration limits are respected").

Geometry. The blend of corner k is a quintic Bezier curve with three control points on each line,
at distances ``d, 2d/3, d/3`` from the vertex: it leaves and joins the lines with zero curvature
(G2), as in the curvature-continuous corner blends of Sencer's reference [4]. Its midpoint is the
point closest to the vertex, at ``epsilon = (23/48) d sin(beta/2)`` (Bernstein weights at 1/2), so
``d = 48 epsilon / (23 sin(beta/2))``, capped at half of each adjacent segment.

Timing. A blend is traversed at a constant *parametric* rate ``lambda' `` (so that its axis
positions are quintics in time): the largest rate for which ``lambda'^k max|B^(k)|`` stays within
the axis limits for k = 1, 2, 3 and the feed stays within ``F``. The straight parts between blends
are time-optimal double-S moves (:func:`double_s`) between the blends' entry and exit speeds, which
a forward-backward pass lowers where a straight part is too short to change speed. The whole
trajectory is piecewise polynomial and kept exactly.
"""

from __future__ import annotations

import math

import numpy as np

from research.errors import ParameterError
from research.interpolators.scurve import double_s, max_end_speed
from research.limits import AxisLimits
from research.paths.polyline import Polyline
from research.piecewise import PiecewisePolynomial
from research.trajectory import Trajectory

_SPACING = np.array([1.0, 2.0 / 3.0, 1.0 / 3.0])  # control points at d, 2d/3, d/3 from the vertex
_MID_WEIGHT = (1 + 5 * _SPACING[1] + 10 * _SPACING[2]) / 32  # = 23/96: B(1/2) - V = 2 w d sin(b/2)
# Bernstein -> power basis for degree 5: B(l) = sum_m l^m (BERNSTEIN_TO_POWER @ P)_m
_BERNSTEIN_TO_POWER = np.array(
    [[(-1) ** (m - i) * math.comb(5, m) * math.comb(m, i) if m >= i else 0 for i in range(6)] for m in range(6)],
    dtype=np.float64,
)


def corner_blends(path: Polyline, tolerance: float) -> tuple[np.ndarray, np.ndarray]:
    """Control points ``(M - 1, 6, d)`` of every corner blend and their half-lengths ``d_k`` [mm]."""
    u = path.directions
    beta = path.turning_angles
    with np.errstate(divide="ignore"):
        d = np.where(beta > 1e-12, tolerance / (2 * _MID_WEIGHT * np.sin(beta / 2)), np.inf)
    L = path.lengths
    d = np.minimum(d, 0.5 * np.minimum(L[:-1], L[1:]))
    V = path.corners
    before = V[:, None, :] - (d[:, None] * _SPACING[None, :])[:, :, None] * u[:-1, None, :]
    after = V[:, None, :] + (d[:, None] * _SPACING[::-1][None, :])[:, :, None] * u[1:, None, :]
    return np.concatenate([before, after], axis=1), d


def blend_interpolate(path: Polyline, feed, tolerance: float, limits: AxisLimits, sample_period: float = 1e-3) -> Trajectory:
    """Smooth every corner within ``tolerance`` and traverse the result within ``limits``.

    Args:
        path: G01 tool path [mm].
        feed: feed ``F`` [mm/s] (scalar or one per segment).
        tolerance: corner deviation ``epsilon`` [mm], > 0.
        limits: per-axis limits; jerk must be finite.
        sample_period: ``Ts`` [s].

    Returns:
        The :class:`Trajectory`, with its exact piecewise-polynomial profile.
    """
    if limits.n_axes != path.dim:
        raise ParameterError(f"limits have {limits.n_axes} axes but the path has {path.dim}")
    if not np.all(np.isfinite(limits.jerk)):
        raise ParameterError("geometric blending needs finite jerk limits on every axis")
    if not (np.isfinite(tolerance) and tolerance > 0):
        raise ParameterError(f"blend tolerance epsilon must be finite and > 0 mm, got {tolerance!r}")
    feeds = np.broadcast_to(np.asarray(feed, dtype=np.float64), (path.n_segments,))
    if not np.all(np.isfinite(feeds) & (feeds > 0)):
        raise ParameterError(f"feed must be finite and > 0 mm/s, got {feeds.tolist()}")
    controls, d = corner_blends(path, tolerance)
    power = np.einsum("mi,kid->kmd", _BERNSTEIN_TO_POWER, controls)  # (C, 6, dim): B(l) = sum c_m l^m
    rate = _blend_rates(power, limits, np.minimum(feeds[:-1], feeds[1:]))
    entry = rate * 5 * _SPACING[0] / 3 * d  # speed at a blend's ends: |B'(0)| = 5 |P1 - P0| = 5 d / 3
    # straight parts: segment k runs between the blends at corners k-1 and k
    along = np.array([limits.along(u) for u in path.directions])
    v_line = np.minimum(feeds, along[:, 0])
    h = path.lengths - np.concatenate([[0.0], d]) - np.concatenate([d, [0.0]])
    speeds = _reachable(np.concatenate([[0.0], entry, [0.0]]), h, v_line, along)
    rate = speeds[1:-1] / (5 * _SPACING[0] / 3 * d)  # lowered where a straight part is too short
    starts, ends = speeds[:-1], speeds[1:]

    pieces_t, pieces_c = [], []  # durations and (degree 5, dim) coefficients in local time
    for k in range(path.n_segments):
        P = path.points[k] + path.directions[k] * (d[k - 1] if k > 0 else 0.0)
        if h[k] > 1e-12:
            s = double_s(h[k], starts[k], ends[k], v_line[k], along[k, 1], along[k, 2])
            for i in range(7):
                c = np.zeros((6, path.dim))
                c[:4] = np.asarray(s.coeffs)[i, :, 0][:, None] * path.directions[k][None, :]
                c[0] += P
                pieces_t.append(float(s.breaks[i + 1] - s.breaks[i]))
                pieces_c.append(c)
        if k < path.n_segments - 1:
            r = rate[k]
            pieces_t.append(1.0 / r)
            pieces_c.append(power[k] * (r ** np.arange(6))[:, None])
    breaks = np.concatenate([[0.0], np.cumsum(pieces_t)])
    position = PiecewisePolynomial(breaks, np.stack(pieces_c))
    return Trajectory.from_piecewise(position, sample_period, path.axes)


def _blend_rates(power: np.ndarray, limits: AxisLimits, feed: np.ndarray) -> np.ndarray:
    """Largest parametric rate ``lambda'`` per blend [1/s] within the axis limits and the feed."""
    lam = np.linspace(0.0, 1.0, 2001)
    rates = []
    for c, F in zip(power, feed):
        derivs = []
        for k in (1, 2, 3):
            m = np.arange(k, 6)
            coef = c[k:] * np.array([math.perm(int(i), k) for i in m])[:, None]
            derivs.append(np.abs((lam[:, None] ** (m - k)[None, :]) @ coef).max(axis=0))  # max |B^(k)| per axis
        speed = np.linalg.norm(np.stack([lam**0, lam, lam**2, lam**3, lam**4], axis=1) @ (c[1:] * np.arange(1, 6)[:, None]), axis=1).max()
        with np.errstate(divide="ignore"):
            bounds = [
                F / speed,
                np.min(limits.velocity / derivs[0]),
                np.min(np.sqrt(limits.acceleration / derivs[1])),
                np.min(np.cbrt(limits.jerk / derivs[2])),
            ]
        rates.append(min(bounds) * (1 - 1e-9))
    return np.asarray(rates)


def _reachable(speeds: np.ndarray, h: np.ndarray, v_line: np.ndarray, along: np.ndarray) -> np.ndarray:
    """Forward-backward pass: lower blend speeds until every straight part can make its change."""
    v = speeds.copy()
    for _ in range(len(v) + 1):
        changed = False
        for k in range(len(h)):  # forward: end speed reachable from start speed
            cap = v_line[k] if h[k] <= 1e-12 else max_end_speed(h[k], min(v[k], v_line[k]), v_line[k], along[k, 1], along[k, 2])
            if h[k] <= 1e-12:
                cap = min(cap, v[k])
            if v[k + 1] > cap * (1 + 1e-12):
                v[k + 1], changed = cap, True
        for k in reversed(range(len(h))):  # backward: start speed can slow down to end speed
            cap = v_line[k] if h[k] <= 1e-12 else max_end_speed(h[k], min(v[k + 1], v_line[k]), v_line[k], along[k, 1], along[k, 2])
            if h[k] <= 1e-12:
                cap = min(cap, v[k + 1])
            if v[k] > cap * (1 + 1e-12):
                v[k], changed = cap, True
        if not changed:
            break
    return v
