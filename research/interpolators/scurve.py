"""Jerk-limited S-curve ("linear interpolator") with an exact stop at every corner.

The baseline of Sencer 2015 (§1) and DiMarco 2015 (the "linear interpolator"): each G01 block
is traversed rest to rest with a seven-phase profile, jerk ``+-J`` or 0, acceleration bounded by
``A``, feed by ``V`` (Biagiotti & Melchiorri, *Trajectory Planning for Automatic Machines and
Robots*, 2008, §3.4). The tangential limits of a block come from the per-axis limits along its
direction (:meth:`AxisLimits.along`), so every axis stays within its own limits. The profile is
time-optimal for a rest-to-rest move under those limits (checked against ruckig in the tests).
"""

from __future__ import annotations

import numpy as np

from research.errors import ParameterError
from research.limits import AxisLimits
from research.paths.polyline import Polyline
from research.piecewise import PiecewisePolynomial
from research.trajectory import Trajectory


def scurve_phases(length, velocity, acceleration, jerk) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Phase times of the rest-to-rest seven-phase profile (vectorised over moves).

    Args:
        length: move length ``L`` [mm], > 0 (array or scalar).
        velocity, acceleration, jerk: limits ``V`` [mm/s], ``A`` [mm/s^2], ``J`` [mm/s^3], > 0.

    Returns:
        ``(Tj, Ta, Tv)`` [s]: jerk phase, whole acceleration phase (``Ta >= 2 Tj``), cruise.
        The move takes ``2 Ta + Tv``.

    Cases (Biagiotti & Melchiorri 2008, eq 3.30-3.31 for zero boundary velocities): ``A`` is
    reached when ``V J >= A^2``; ``V`` is reached when the move is long enough; otherwise the
    peak velocity is lowered, with or without reaching ``A``.
    """
    L, V, A, J = np.broadcast_arrays(*(np.asarray(x, dtype=np.float64) for x in (length, velocity, acceleration, jerk)))
    reach_a = V * J >= A**2
    Tj = np.where(reach_a, A / J, np.sqrt(V / J))
    Ta = np.where(reach_a, Tj + V / A, 2 * Tj)
    Tv = L / V - Ta
    short = Tv < 0
    # V not reached: the largest peak velocity that fits the length
    long_enough_for_a = L >= 2 * A**3 / J**2
    Tj_s = np.where(long_enough_for_a, A / J, np.cbrt(L / (2 * J)))
    Ta_s = np.where(long_enough_for_a, 0.5 * Tj_s + np.sqrt((0.5 * Tj_s) ** 2 + L / A), 2 * Tj_s)
    Tj = np.where(short, Tj_s, Tj)
    Ta = np.where(short, Ta_s, Ta)
    Tv = np.where(short, 0.0, Tv)
    return Tj, Ta, Tv


def scurve_profile(length: float, velocity: float, acceleration: float, jerk: float) -> PiecewisePolynomial:
    """Exact position ``s(t)`` [mm] of one rest-to-rest move of ``length`` [mm] (1 channel).

    Example:
        >>> s = scurve_profile(10.0, 100.0, 1000.0, 1e5)
        >>> round(float(s.end), 6), round(float(s.end_values()[0]), 9)
        (0.21025, 10.0)
    """
    _check_positive(length=length, velocity=velocity, acceleration=acceleration, jerk=jerk)
    return _profiles(np.atleast_1d(float(length)), np.atleast_1d(float(velocity)),
                     np.atleast_1d(float(acceleration)), np.atleast_1d(float(jerk)))


def scurve_interpolate(path: Polyline, feed, limits: AxisLimits, sample_period: float = 1e-3) -> Trajectory:
    """Traverse ``path`` block by block with S-curves, stopping exactly at every vertex.

    Args:
        path: G01 tool path [mm].
        feed: commanded feed ``F`` [mm/s], scalar or one per segment.
        limits: per-axis velocity, acceleration and jerk limits (jerk must be finite).
        sample_period: interpolation period ``Ts`` [s].

    Returns:
        A :class:`Trajectory` with its exact profile; ``duration`` is the sum of the block times.
    """
    if limits.n_axes != path.dim:
        raise ParameterError(f"limits have {limits.n_axes} axes but the path has {path.dim}")
    if not np.all(np.isfinite(limits.jerk)):
        raise ParameterError("the S-curve needs finite jerk limits on every axis")
    feeds = np.broadcast_to(np.asarray(feed, dtype=np.float64), (path.n_segments,))
    _check_positive(feed=feeds)
    along = np.array([limits.along(u) for u in path.directions])  # (M, 3): v, a, j along each block
    s = _profiles(path.lengths, np.minimum(feeds, along[:, 0]), along[:, 1], along[:, 2])
    # map arc length to the axes block by block: q = P_k + u_k (s - S_k)
    block = np.repeat(np.arange(path.n_segments), 7)
    u = path.directions[block]  # (7M, d)
    c = np.asarray(s.coeffs)[:, :, 0]  # (7M, 4)
    offset = path.points[block] - u * path.arc_length[block][:, None]
    coeffs = c[:, :, None] * u[:, None, :]
    coeffs[:, 0, :] += offset
    return Trajectory.from_piecewise(PiecewisePolynomial(s.breaks, coeffs), sample_period, path.axes)


def _profiles(L, V, A, J) -> PiecewisePolynomial:
    """Consecutive rest-to-rest S-curves (one per move), as one scalar arc-length profile.

    Each phase is a cubic in local time with coefficients ``[s, v, a / 2, j / 6]`` at its start,
    integrated exactly within each move from rest, so nothing drifts over many moves.
    """
    Tj, Ta, Tv = scurve_phases(L, V, A, J)
    durations = np.stack([Tj, Ta - 2 * Tj, Tj, Tv, Tj, Ta - 2 * Tj, Tj], axis=1)  # (M, 7)
    jerks = np.array([1.0, 0.0, -1.0, 0.0, -1.0, 0.0, 1.0])[None, :] * J[:, None]
    M = durations.shape[0]
    coeffs = np.zeros((M, 7, 4))
    s = np.concatenate([[0.0], np.cumsum(L)[:-1]])  # arc length at the start of each move
    v = a = np.zeros(M)
    for k in range(7):
        h, jk = durations[:, k], jerks[:, k]
        coeffs[:, k] = np.stack([s, v, a / 2, jk / 6], axis=1)
        s, v, a = s + v * h + a * h**2 / 2 + jk * h**3 / 6, v + a * h + jk * h**2 / 2, a + jk * h
    breaks = np.concatenate([[0.0], np.cumsum(durations.ravel())])
    return PiecewisePolynomial(breaks, coeffs.reshape(-1, 4, 1))


def _check_positive(**values) -> None:
    for name, value in values.items():
        x = np.asarray(value, dtype=np.float64)
        bad = ~(np.isfinite(x) & (x > 0))
        if bad.any():
            raise ParameterError(f"S-curve {name} must be finite and > 0, got {np.ravel(x)[np.argmax(np.ravel(bad))]!r}")
