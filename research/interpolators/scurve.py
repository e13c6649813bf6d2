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
from research.paths.gcode import checked_pauses
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
    pp = _profiles(np.atleast_1d(float(length)), np.atleast_1d(float(velocity)),
                   np.atleast_1d(float(acceleration)), np.atleast_1d(float(jerk)), np.zeros(2))
    return PiecewisePolynomial(pp.breaks[1:-1], pp.coeffs[1:-1])  # the seven phases (no holds)


def scurve_interpolate(path: Polyline, feed, limits: AxisLimits, sample_period: float = 1e-3, *,
                       pauses=None) -> Trajectory:
    """Traverse ``path`` block by block with S-curves, stopping exactly at every vertex.

    Args:
        path: G01 tool path [mm].
        feed: commanded feed ``F`` [mm/s], scalar or one per segment.
        limits: per-axis velocity, acceleration and jerk limits (jerk must be finite).
        sample_period: interpolation period ``Ts`` [s].
        pauses: ``(M + 1,)`` dwell at each vertex [s] (index 0 the start; NaN or 0: none), e.g. a
            G-code program's ``pauses`` (``G4 P``): the motion already stops at every vertex, so
            a dwell is a constant piece there.

    Returns:
        A :class:`Trajectory` with its exact profile; ``duration`` is the sum of the block times
        and the dwells.
    """
    if limits.n_axes != path.dim:
        raise ParameterError(f"limits have {limits.n_axes} axes but the path has {path.dim}")
    if not np.all(np.isfinite(limits.jerk)):
        raise ParameterError("the S-curve needs finite jerk limits on every axis")
    feeds = np.broadcast_to(np.asarray(feed, dtype=np.float64), (path.n_segments,))
    _check_positive(feed=feeds)
    dwell = np.zeros(path.n_segments + 1)
    if pauses is not None:
        dwell = np.nan_to_num(checked_pauses(pauses, path.n_segments), nan=0.0)
    along = np.array([limits.along(u) for u in path.directions])  # (M, 3): v, a, j along each block
    s = _profiles(path.lengths, np.minimum(feeds, along[:, 0]), along[:, 1], along[:, 2], dwell)
    # map arc length to the axes block by block: q = P_k + u_k (s - S_k); the start dwell holds P_0
    block = np.concatenate([[0], np.repeat(np.arange(path.n_segments), 8)])
    u = path.directions[block]  # (7M, d)
    c = np.asarray(s.coeffs)[:, :, 0]  # (7M, 4)
    offset = path.points[block] - u * path.arc_length[block][:, None]
    coeffs = c[:, :, None] * u[:, None, :]
    coeffs[:, 0, :] += offset
    return Trajectory.from_piecewise(PiecewisePolynomial(s.breaks, coeffs), sample_period, path.axes)


def _profiles(L, V, A, J, dwell) -> PiecewisePolynomial:
    """Consecutive rest-to-rest S-curves (one per move), as one scalar arc-length profile: a first
    piece holding the start for ``dwell[0]`` [s], then each move's seven phases and an eighth
    holding its end for ``dwell[k + 1]`` (pieces of zero length where there is no dwell).

    Each phase is a cubic in local time with coefficients ``[s, v, a / 2, j / 6]`` at its start,
    integrated exactly within each move from rest, so nothing drifts over many moves.
    """
    Tj, Ta, Tv = scurve_phases(L, V, A, J)
    durations = np.stack([Tj, Ta - 2 * Tj, Tj, Tv, Tj, Ta - 2 * Tj, Tj, dwell[1:]], axis=1)  # (M, 8)
    jerks = np.array([1.0, 0.0, -1.0, 0.0, -1.0, 0.0, 1.0, 0.0])[None, :] * J[:, None]
    M = durations.shape[0]
    coeffs = np.zeros((M, 8, 4))
    s = np.concatenate([[0.0], np.cumsum(L)[:-1]])  # arc length at the start of each move
    v = a = np.zeros(M)
    for k in range(8):
        h, jk = durations[:, k], jerks[:, k]
        coeffs[:, k] = np.stack([s, v, a / 2, jk / 6], axis=1)
        s, v, a = s + v * h + a * h**2 / 2 + jk * h**3 / 6, v + a * h + jk * h**2 / 2, a + jk * h
    coeffs[:, 7, 1:] = 0.0  # the dwell: at rest on the move's end (its v, a are rounding residues of 0)
    coeffs[:, 7, 0] = np.cumsum(L)
    breaks = np.concatenate([[0.0], dwell[0] + np.concatenate([[0.0], np.cumsum(durations.ravel())])])
    return PiecewisePolynomial(breaks, np.concatenate([np.zeros((1, 4)), coeffs.reshape(-1, 4)])[:, :, None])


def _check_positive(**values) -> None:
    for name, value in values.items():
        x = np.asarray(value, dtype=np.float64)
        bad = ~(np.isfinite(x) & (x > 0))
        if bad.any():
            raise ParameterError(f"S-curve {name} must be finite and > 0, got {np.ravel(x)[np.argmax(np.ravel(bad))]!r}")


def double_s(length: float, v_start: float, v_end: float, velocity: float, acceleration: float, jerk: float):
    """Time-optimal jerk-limited move of ``length`` [mm] from speed ``v_start`` to ``v_end`` [mm/s],
    starting and ending with zero acceleration.

    The double-S profile (Biagiotti & Melchiorri 2008, §3.4.2): a speed-up phase to a peak speed
    ``v_p``, a cruise at ``v_p``, a slow-down phase, each phase a time-optimal speed change with
    jerk ``+-J`` or 0. ``v_p = V`` when the move is long enough (then the cruise takes up the
    rest); otherwise ``v_p`` is the speed whose two phases exactly cover the length (bisection: the
    covered length grows with ``v_p``). Unlike the book's symmetric reduction of the acceleration
    limit, each phase keeps its own jerk time, so the result equals ruckig's (tested).

    Returns:
        The scalar :class:`PiecewisePolynomial` ``s(t)`` (7 cubic pieces, some of zero length).

    Raises:
        ParameterError: the speed change cannot be made within the length (see :func:`max_end_speed`).
    """
    h, v0, v1, V, A, J = (float(x) for x in (length, v_start, v_end, velocity, acceleration, jerk))
    if not (h > 0 and 0 <= v0 <= V and 0 <= v1 <= V and A > 0 and J > 0):
        raise ParameterError(f"double_s: need length > 0 and 0 <= v_start, v_end <= V, got {h}, {v0}, {v1}, {V}")
    if not _speed_change_fits(h, v0, v1, A, J):
        raise ParameterError(f"double_s: cannot go from {v0:g} to {v1:g} mm/s within {h:g} mm under A = {A:g}, J = {J:g}")

    def covered(vp):  # length of the two phases through peak speed vp
        return 0.5 * (v0 + vp) * _speed_change(vp - v0, A, J)[1] + 0.5 * (vp + v1) * _speed_change(vp - v1, A, J)[1]

    if covered(V) <= h:
        vp, Tv = V, (h - covered(V)) / V
    else:
        lo, hi = max(v0, v1), V
        for _ in range(100):
            mid = 0.5 * (lo + hi)
            lo, hi = (mid, hi) if covered(mid) <= h else (lo, mid)
        vp, Tv = lo, (h - covered(lo)) / max(lo, 1e-300)  # remainder below the bisection precision
    Tj1, Ta = _speed_change(vp - v0, A, J)
    Tj2, Td = _speed_change(vp - v1, A, J)
    durations = np.array([Tj1, Ta - 2 * Tj1, Tj1, Tv, Tj2, Td - 2 * Tj2, Tj2])
    jerks = np.array([J, 0.0, -J, 0.0, -J, 0.0, J])
    coeffs = np.zeros((7, 4, 1))
    s, v, a = 0.0, v0, 0.0
    for k in range(7):
        coeffs[k, :, 0] = [s, v, a / 2, jerks[k] / 6]
        dt = durations[k]
        s, v, a = s + v * dt + a * dt**2 / 2 + jerks[k] * dt**3 / 6, v + a * dt + jerks[k] * dt**2 / 2, a + jerks[k] * dt
    return PiecewisePolynomial(np.concatenate([[0.0], np.cumsum(durations)]), coeffs)


def _speed_change(dv: float, A: float, J: float) -> tuple[float, float]:
    """Jerk time and total time of a time-optimal speed change by ``dv >= 0`` from and to zero
    acceleration (the acceleration limit is reached when ``dv J >= A^2``)."""
    if dv * J < A * A:
        Tj = float(np.sqrt(max(dv, 0.0) / J))
        return Tj, 2 * Tj
    return A / J, A / J + dv / A


def max_end_speed(length: float, v_start: float, velocity: float, acceleration: float, jerk: float) -> float:
    """Highest speed [mm/s] reachable (up or down are symmetric) from ``v_start`` within ``length``."""
    lo, hi = v_start, velocity
    if _speed_change_fits(length, v_start, hi, acceleration, jerk):
        return hi
    for _ in range(80):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if _speed_change_fits(length, v_start, mid, acceleration, jerk) else (lo, mid)
    return lo


def _speed_change_fits(h, v0, v1, A, J) -> bool:
    """Biagiotti & Melchiorri eq 3.17-3.18: can the speed go from v0 to v1 within h?"""
    dv = abs(v1 - v0)
    Tj = min(np.sqrt(dv / J), A / J)
    needed = Tj * (v0 + v1) if Tj < A / J else 0.5 * (v0 + v1) * (Tj + dv / A)
    return h >= needed * (1 - 1e-12)
