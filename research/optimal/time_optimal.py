"""Time-optimal reference motion along a polyline within a tolerance tube (issue 6).

:func:`time_optimal` solves the minimum-time optimal-control problem of ``_ocp`` (per-axis triple
integrator with piecewise-constant jerk, per-axis ``|v|, |a|, |j|`` limits, optional feed limit
``|v| <= F``, a tube of radius ``eps`` around the polyline with one free-duration phase per segment,
start and end at rest) with CasADi ``Opti`` and IPOPT, warm-started from an S-curve (default) or
any other trajectory along the path (e.g. FIR overlap), over the whole path or in receding windows
(``_windowing``, Sencer 2009 thesis §3.5). It is the yardstick of the interpolators: under equal
limits and tolerance no interpolator can be faster than the OCP, up to the discretisation of the
jerk on ``N`` equal intervals per segment (finer ``N``: closer to the continuous optimum).

What is approximated, and by how much (measured in ``tests/optimal`` and ``bench_optimal``):

- the grid: jerk switching times fall between grid points, so the cycle time is an upper bound on
  the continuous optimum; on a 100 mm line (Sencer 2015 envelope) it is 0.3 % above the S-curve
  optimum with ``N = 24`` and 0.06 % with ``N = 48``; on the diamond with the 20/10 ms FIR's peaks
  ``N = 16`` is 2.1 % above ``N = 81``. :func:`~research.optimal.converged_time_optimal` refines
  ``N`` until the cycle time changes by < 0.1 % (issue 19);
- between grid points the tube and the velocity / feed limits are imposed at ``checks_per_interval``
  points only; the dense check (:class:`Verification`) finds at most 0.9 % excess at ``N = 16-24``
  on the 20/10 ms sets and 0.22 % at converged ``N`` on the benchmark paths (acceleration and jerk
  are exact: linear and constant on each interval);
- the tube is the rectangle (cylinder) of each segment between its end caps, not the full
  ``eps``-capsule: the motion may not overshoot a vertex on the outer side of a corner;
- windows end at rest on their last vertex (``_windowing``), which slows the committed part only
  when the look-ahead is shorter than the braking distance.

With ``modes`` it is the vibration-aware OCP (issue 19): every structural mode (a base-excited
2nd-order system driven by its axis' acceleration, ``_vibration``) is part of the state with its
exact flow on each interval, its residual vibration at the end bounded (default: zero) and,
optionally, its deflection during the motion.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from research.errors import InfeasibleProblem, ParameterError
from research.interpolators.scurve import (
    scurve_interpolate,
    scurve_phases,
    scurve_profile,
)
from research.limits import AxisLimits
from research.optimal._arrays import frozen
from research.optimal._ocp import Geometry, PhaseGrid, ProblemSpec, flow
from research.optimal._vibration import check_modes, grid_vibration, mode_states
from research.optimal._warm import grid_from_result, grid_from_trajectory
from research.optimal._windowing import (
    WindowFailure,
    WindowReport,
    braking_distance,
    solve_windows,
    window_schedule,
)
from research.paths.polyline import Polyline
from research.piecewise import PiecewisePolynomial
from research.trajectory import Trajectory

_DENSE = 16  # verification points per interval


@dataclass(frozen=True)
class Verification:
    """The solution resampled at ``16`` points per interval on its exact cubic profile.

    Attributes:
        max_deviation: largest distance from the path [mm].
        deviation_ratio: ``max_deviation / eps``.
        velocity_ratio, acceleration_ratio, jerk_ratio: ``(d,)`` per-axis peak / limit.
        feed_ratio: peak ``|v|`` / ``F`` (``nan`` without a feed limit).
        residual_vibration: ``(m,)`` envelope of each structural mode's free vibration at the end
            (eq V3) [mm], re-simulated from rest on the solution's jerk; empty without modes.
        peak_deflection: ``(m,)`` peak ``|delta|`` of each mode during the motion [mm].
    """

    max_deviation: float
    deviation_ratio: float
    velocity_ratio: np.ndarray
    acceleration_ratio: np.ndarray
    jerk_ratio: np.ndarray
    feed_ratio: float
    residual_vibration: np.ndarray = field(default_factory=lambda: frozen(np.zeros(0)))
    peak_deflection: np.ndarray = field(default_factory=lambda: frozen(np.zeros(0)))

    @property
    def worst_ratio(self) -> float:
        """Largest of all the ratios (1.01 = 1 % over a limit or the tube)."""
        vals = [self.deviation_ratio, *self.velocity_ratio, *self.acceleration_ratio, *self.jerk_ratio]
        if np.isfinite(self.feed_ratio):
            vals.append(self.feed_ratio)
        return float(max(vals))


@dataclass(frozen=True)
class TimeOptimalResult:
    """Outcome of :func:`time_optimal`.

    Attributes:
        trajectory: the motion, sampled at ``sample_period``, with its exact profile (one cubic per
            interval: piecewise-constant jerk).
        phase_durations: ``(M,)`` time spent in each segment's phase [s] (phase ``k`` ends at the
            boundary node within ``eps`` of vertex ``k + 1``); their sum is the cycle time, an
            upper bound on the continuous optimum (see the module docstring).
        status: IPOPT return status (``"Solve_Succeeded"`` when every window succeeded, else the
            first non-exact one, e.g. ``"Solved_To_Acceptable_Level"``); ``"exact stop"`` for
            ``eps = 0``, which needs no NLP.
        iterations: IPOPT iterations summed over the windows.
        solve_time: IPOPT wall-clock time summed over the windows [s].
        build_time: time spent building the NLPs (Opti + SX expansion) [s].
        windows: one :class:`WindowReport` per window.
        intervals_per_segment: ``N``.
        tolerance: ``eps`` [mm].
        verification: dense check of tube and limits between grid points.
        modes: the structural modes in the dynamics (``()``: the plain OCP).
    """

    trajectory: Trajectory
    phase_durations: np.ndarray
    status: str
    iterations: int
    solve_time: float
    build_time: float
    windows: tuple[WindowReport, ...]
    intervals_per_segment: int
    tolerance: float
    verification: Verification = field(repr=False)
    modes: tuple = ()

    @property
    def cycle_time(self) -> float:
        """Total motion time [s], ``sum_k T_k``."""
        return float(np.sum(self.phase_durations))


def time_optimal(
    path: Polyline,
    limits: AxisLimits,
    tolerance: float,
    *,
    feed: float | None = None,
    intervals_per_segment: int = 24,
    window: int | None = None,
    overlap: int = 4,
    lookahead: float | str | None = None,
    warm_start: Trajectory | TimeOptimalResult | None = None,
    sample_period: float = 1e-3,
    solver_options: dict | None = None,
    checks_per_interval: int = 3,
    modes=(),
    residual_vibration=0.0,
    max_deflection: float | None = None,
) -> TimeOptimalResult:
    """Minimum-time motion along ``path`` that stays within ``tolerance`` of it.

    Args:
        path: G01 tool path [mm], 1-3 axes.
        limits: per-axis velocity, acceleration and jerk limits (all finite) [mm/s, mm/s^2, mm/s^3].
        tolerance: tube radius ``eps`` [mm], >= 0. ``eps = 0`` forces a stop at every vertex, where
            the exact-stop S-curve is the optimum; it is returned without an NLP.
        feed: bound ``F`` on the path speed ``|v|`` [mm/s]; ``None``: per-axis velocity limits only.
        intervals_per_segment: equal jerk intervals ``N`` per segment phase (>= 1; a rest-to-rest
            single segment needs >= 3).
        window: segments per receding window (``None``: the whole path in one NLP).
        overlap: segments of look-ahead solved again by the next window (``0 <= overlap < window``).
        lookahead: path length [mm] a window keeps after what it commits (at least ``overlap``
            segments, fewer committed where they are short), or ``"braking"``: the braking
            distance from the feed cap under the limits (``_windowing.braking_distance``), with
            which each window's terminal stop costs its committed part nothing. ``None``: ``overlap``
            segments alone, which on chords much shorter than the braking distance makes every
            window slow down for a stop it never takes (on 100 chords of 0.85 mm of bench_cam's
            CAM file, F 200 mm/s, T 60/30 ms envelope, window 10: 0.8667 s against 0.5194 s for the
            whole path in one NLP; window 40 with ``"braking"`` (9 mm): 0.5235 s, +0.8 %; window 40
            with 20 segments of overlap: 0.5216 s: a window several braking distances long is what
            matters, and each extra window starts from the last one's stop, ``_windowing``).
        warm_start: a trajectory along the path (FIR, S-curve, ...) mapped onto the phase grid, or
            a :class:`TimeOptimalResult` on the same path (its phase boundaries kept, e.g. another
            ``N``); default: the exact-stop S-curve under the same limits (a feasible point).
        sample_period: ``Ts`` of the returned trajectory [s].
        solver_options: IPOPT options overriding the defaults (``print_level`` 0, ``tol`` 1e-8, ...).
        checks_per_interval: points inside each interval where tube, velocity and feed are also
            imposed (on the exact cubic), so the motion between grid points keeps them too.
        modes: :class:`StructuralMode` s in the dynamics (the vibration-aware OCP, ``_vibration``):
            each a base-excited 2nd-order system driven by its axis' acceleration (eq V1-V2).
        residual_vibration: bound ``r`` [mm] on every mode's residual vibration envelope at the end
            of the motion (eq V3), or one bound per mode; ``0``: the modes end at rest; ``None``:
            free. Only with ``modes``.
        max_deflection: bound ``D`` [mm] on every mode's deflection during the motion, or ``None``.

    Returns:
        A :class:`TimeOptimalResult`.

    Raises:
        ParameterError: malformed input (wrong axes, non-finite limits, bad grid sizes, NaN).
        InfeasibleProblem: no motion can satisfy the constraints (``tolerance < 0``,
            ``feed <= 0``), or IPOPT stops without an acceptable solution; the message and the
            attributes ``constraint``, ``segment``, ``status``, ``violation`` say where.

    Example:
        >>> from research.paths import named_path
        >>> lim = AxisLimits.fir_envelope(2, 250.0, [0.148, 0.089])
        >>> res = time_optimal(named_path("corner90"), lim, 0.5, feed=250.0, intervals_per_segment=12)
        >>> res.status, res.cycle_time < 0.7777   # faster than FIR overlap (0.7777 s)
        ('Solve_Succeeded', True)
    """
    _check(path, limits, tolerance, feed, intervals_per_segment, window, overlap, sample_period, checks_per_interval)
    modes = check_modes(modes, path.dim)
    residual = None if residual_vibration is None else np.atleast_1d(np.asarray(residual_vibration, dtype=np.float64))
    if residual is not None and residual.size == 1:
        residual = np.repeat(residual, len(modes))
    if residual is not None and not (residual.shape == (len(modes),) and np.all(np.isfinite(residual) & (residual >= 0))):
        raise ParameterError(f"residual_vibration must be None or finite bounds >= 0 mm (one, or one per mode), got {residual_vibration!r}")
    if max_deflection is not None and not (np.isfinite(max_deflection) and max_deflection > 0):
        raise ParameterError(f"max_deflection must be None or a finite bound > 0 mm, got {max_deflection!r}")
    if modes and tolerance == 0:
        raise ParameterError("modes need tolerance > 0: the eps = 0 exact stop is solved without an NLP")
    if tolerance == 0:
        return _exact_stop(path, limits, feed, intervals_per_segment, sample_period)
    d, M, N = path.dim, path.n_segments, int(intervals_per_segment)
    cap = feed if feed is not None else float(np.linalg.norm(limits.velocity))
    ahead = _lookahead(lookahead, limits, cap)  # [mm], refused before any warm start is built
    if isinstance(warm_start, TimeOptimalResult):
        if warm_start.phase_durations.size != M:
            raise ParameterError(f"warm_start is a solution with {warm_start.phase_durations.size} phases, the path has {M} segments")
        guess = grid_from_result(warm_start.phase_durations, warm_start.trajectory, path, N)
    else:
        guess = grid_from_trajectory(warm_start if warm_start is not None else _scurve_warm_start(path, limits, feed), path, N)
    if modes:
        guess = replace(guess, modes=mode_states(guess.states, guess.jerks, np.repeat(guess.durations / N, N), modes))
    geometry = Geometry(
        path.points[:-1], path.points[1:], path.directions, path.lengths,
        np.maximum((path.lengths - 2 * tolerance) / min(cap, float(np.linalg.norm(limits.velocity))), 1e-6),
    )
    schedule = window_schedule(M, window, overlap, path.lengths, ahead)
    n_max = max(stop - first for first, stop, _ in schedule)
    spec = ProblemSpec(
        n_phases=n_max, intervals=N, dim=d,
        velocity=tuple(map(float, limits.velocity)), acceleration=tuple(map(float, limits.acceleration)),
        jerk=tuple(map(float, limits.jerk)), feed=None if feed is None else float(feed),
        tolerance=float(tolerance), checks=int(checks_per_interval),
        length_scale=float(np.median(path.lengths)) * n_max, time_scale=float(np.median(guess.durations)),
        modes=modes, residual=None if residual is None else tuple(map(float, residual)),
        deflection=None if max_deflection is None else float(max_deflection),
    )
    start = np.zeros((3, d))
    start[0] = path.points[0]
    try:
        solution, reports, build_time = solve_windows(geometry, spec, guess, start, schedule, solver_options)
    except WindowFailure as exc:
        raise _infeasible(exc, path) from None
    statuses = [r.status for r in reports]
    status = next((s for s in statuses if s != "Solve_Succeeded"), "Solve_Succeeded")
    trajectory = _trajectory(solution, N, path.axes, sample_period)
    return TimeOptimalResult(
        trajectory=trajectory,
        phase_durations=frozen(solution.durations),
        status=status,
        iterations=int(sum(r.iterations for r in reports)),
        solve_time=float(sum(r.solve_time for r in reports)),
        build_time=float(build_time),
        windows=tuple(reports),
        intervals_per_segment=N,
        tolerance=float(tolerance),
        verification=verify(solution, N, path, limits, tolerance, feed, modes),
        modes=modes,
    )


def verify(grid: PhaseGrid, intervals: int, path: Polyline, limits: AxisLimits, tolerance: float, feed: float | None,
           modes=()) -> Verification:
    """Resample the exact piecewise-cubic solution at 16 points per interval and compare it with
    the tube and the limits (the between-grid-points check of issue 6); re-simulate the modes from
    rest on the solution's jerk (eq V2, not the NLP's mode variables).

    Args:
        grid: solution on the phase grid.
        intervals: ``N`` per phase.
        path, limits, tolerance, feed: the problem data (``tolerance`` [mm], ``feed`` [mm/s]).
        modes: structural modes whose residual vibration and peak deflection are reported.

    Returns:
        A :class:`Verification`.
    """
    h = np.repeat(grid.durations / intervals, intervals)
    theta = np.linspace(0.0, 1.0, _DENSE + 1)
    x = flow(np.repeat(grid.states[:-1, None], theta.size, axis=1), np.repeat(grid.jerks[:, None], theta.size, axis=1), h[:, None] * theta[None, :])
    q, v, a = (x[..., i, :].reshape(-1, path.dim) for i in range(3))
    dev = float(path.distance(q).max())

    def peak(y):
        return np.abs(y).max(axis=0)

    residual, deflection = grid_vibration(grid.states, grid.jerks, h, modes, theta)
    return Verification(
        max_deviation=dev,
        deviation_ratio=dev / tolerance if tolerance > 0 else (0.0 if dev == 0 else np.inf),
        velocity_ratio=frozen(peak(v) / limits.velocity),
        acceleration_ratio=frozen(peak(a) / limits.acceleration),
        jerk_ratio=frozen(peak(grid.jerks) / limits.jerk),
        feed_ratio=float(np.linalg.norm(v, axis=1).max() / feed) if feed is not None else float("nan"),
        residual_vibration=frozen(residual), peak_deflection=frozen(deflection),
    )


# -- helpers -----------------------------------------------------------------------------------
def _trajectory(grid: PhaseGrid, intervals: int, axes, sample_period: float) -> Trajectory:
    """Exact profile: on interval ``i`` the cubic ``p_i + v_i t + a_i t^2 / 2 + j_i t^3 / 6``."""
    h = np.repeat(grid.durations / intervals, intervals)
    breaks = np.concatenate([[0.0], np.cumsum(h)])
    coeffs = np.stack([grid.states[:-1, 0], grid.states[:-1, 1], grid.states[:-1, 2] / 2, grid.jerks / 6], axis=1)
    return Trajectory.from_piecewise(PiecewisePolynomial(breaks, coeffs), sample_period, tuple(axes))


def _scurve_warm_start(path: Polyline, limits: AxisLimits, feed) -> Trajectory:
    """Exact-stop S-curve under the OCP's own limits (the motion of :func:`scurve_interpolate`):
    a feasible point of the continuous problem. Built block by block from :func:`scurve_profile`
    in NumPy (``q = P_k + u_k s_k(t)``) and sampled coarsely: only its exact profile is used."""
    along = np.array([limits.along(u) for u in path.directions])
    vmax = np.minimum(along[:, 0], _scurve_feed(limits, feed))
    breaks, coeffs, t0 = [np.zeros(1)], [], 0.0
    for k, u in enumerate(path.directions):
        s = scurve_profile(float(path.lengths[k]), float(vmax[k]), float(along[k, 1]), float(along[k, 2]))
        c = np.asarray(s.coeffs)[:, :, 0, None] * u[None, None, :]  # (7, 4, d)
        c[:, 0, :] += path.points[k]
        breaks.append(t0 + np.asarray(s.breaks)[1:])
        coeffs.append(c)
        t0 = float(breaks[-1][-1])
    breaks, coeffs = np.concatenate(breaks), np.concatenate(coeffs)
    return Trajectory.from_piecewise(PiecewisePolynomial(breaks, coeffs), max(t0 / 200, 1e-6), path.axes)


def _exact_stop(path, limits, feed, intervals, sample_period) -> TimeOptimalResult:
    """``eps = 0``: every vertex is passed at rest with zero acceleration (the velocity must be
    along both segments, the acceleration continuous), so segment by segment the rest-to-rest
    S-curve under the tangential limits is time-optimal (Biagiotti & Melchiorri 2008, §3.4)."""
    traj = scurve_interpolate(path, _scurve_feed(limits, feed), limits, sample_period)
    along = np.array([limits.along(u) for u in path.directions])
    vmax = along[:, 0] if feed is None else np.minimum(along[:, 0], feed)
    _, Ta, Tv = scurve_phases(path.lengths, vmax, along[:, 1], along[:, 2])
    durations = 2 * Ta + Tv
    return TimeOptimalResult(
        trajectory=traj, phase_durations=frozen(durations), status="exact stop", iterations=0,
        solve_time=0.0, build_time=0.0, windows=(), intervals_per_segment=intervals, tolerance=0.0,
        verification=_verify_sampled(traj, path, limits, feed),
    )


def _verify_sampled(traj: Trajectory, path: Polyline, limits: AxisLimits, feed) -> Verification:
    """Verification of an exact-profile trajectory resampled at 0.1 ms."""
    fine = traj.resample(1e-4)
    q, v, a, j = (np.asarray(x) for x in (fine.q, fine.v, fine.a, fine.j))
    dev = float(path.distance(q).max())
    return Verification(
        max_deviation=dev, deviation_ratio=0.0 if dev < 1e-9 else np.inf,
        velocity_ratio=frozen(np.abs(v).max(0) / limits.velocity),
        acceleration_ratio=frozen(np.abs(a).max(0) / limits.acceleration),
        jerk_ratio=frozen(np.abs(j).max(0) / limits.jerk),
        feed_ratio=float(np.linalg.norm(v, axis=1).max() / feed) if feed is not None else float("nan"),
    )


def _scurve_feed(limits: AxisLimits, feed) -> float:
    """Feed for the S-curve warm start: ``F``, or one above every tangential velocity limit."""
    return float(feed) if feed is not None else float(np.sqrt(limits.n_axes) * limits.velocity.max() * (1 + 1e-9))


def _infeasible(exc: WindowFailure, path: Polyline) -> InfeasibleProblem:
    f = exc.failure
    segment = None if f.phase is None else exc.first + f.phase
    where = "" if segment is None else f" in segment {segment} ({path.points[segment].tolist()} -> {path.points[segment + 1].tolist()})"
    err = InfeasibleProblem(
        f"time-optimal OCP: IPOPT stopped with status {f.stats.status!r} after {f.stats.iterations} iterations "
        f"(window of segments {exc.first}..{exc.stop - 1}); worst violated constraint: {f.constraint!r}{where}, "
        f"violation {f.violation:.3g} (scaled units)"
    )
    err.status, err.constraint, err.segment, err.violation, err.iterations = f.stats.status, f.constraint, segment, f.violation, f.stats.iterations
    return err


def _bad_input(message: str, constraint: str) -> InfeasibleProblem:
    err = InfeasibleProblem(message)
    err.status, err.constraint, err.segment, err.violation, err.iterations = "not solved", constraint, None, float("nan"), 0
    return err


def _lookahead(lookahead, limits: AxisLimits, cap: float) -> float:
    """The look-ahead length [mm] of ``time_optimal``'s ``lookahead`` argument."""
    if lookahead is None:
        return 0.0
    if isinstance(lookahead, str):
        if lookahead != "braking":
            raise ParameterError(f"lookahead must be None, a length >= 0 mm or 'braking', got {lookahead!r}")
        return braking_distance(limits, cap)
    value = float(lookahead)
    if not (np.isfinite(value) and value >= 0):
        raise ParameterError(f"lookahead must be None, a length >= 0 mm or 'braking', got {lookahead!r}")
    return value


def _check(path, limits, tolerance, feed, intervals, window, overlap, sample_period, checks) -> None:
    if not isinstance(path, Polyline):
        raise ParameterError(f"path must be a Polyline, got {type(path).__name__}")
    if not isinstance(limits, AxisLimits):
        raise ParameterError(f"limits must be AxisLimits, got {type(limits).__name__}")
    if limits.n_axes != path.dim:
        raise ParameterError(f"limits have {limits.n_axes} axes but the path has {path.dim} ({path.axes})")
    for name in ("velocity", "acceleration", "jerk"):
        if not np.all(np.isfinite(getattr(limits, name))):
            raise ParameterError(f"time_optimal needs finite {name} limits on every axis, got {getattr(limits, name).tolist()}")
    if not np.isfinite(tolerance):
        raise ParameterError(f"tolerance must be a finite number of mm, got {tolerance!r}")
    if tolerance < 0:
        raise _bad_input(f"tolerance tube radius eps = {tolerance} mm < 0: no point is within it, the problem is infeasible", "tolerance tube")
    if feed is not None:
        if not np.isfinite(feed):
            raise ParameterError(f"feed must be a finite number of mm/s or None, got {feed!r}")
        if feed <= 0:
            raise _bad_input(f"feed limit |v| <= F = {feed} mm/s leaves no motion: the path of length {path.length:.6g} mm cannot be traversed", "feed limit")
    if not (isinstance(intervals, (int, np.integer)) and intervals >= 1):
        raise ParameterError(f"intervals_per_segment must be an integer >= 1, got {intervals!r}")
    if window is not None and not (isinstance(window, (int, np.integer)) and window >= 1):
        raise ParameterError(f"window must be None or an integer >= 1 segments, got {window!r}")
    if not (isinstance(overlap, (int, np.integer)) and overlap >= 0):
        raise ParameterError(f"overlap must be an integer >= 0 segments, got {overlap!r}")
    if window is not None and overlap >= window and window < path.n_segments:
        raise ParameterError(f"overlap ({overlap}) must be smaller than window ({window}) so that windows advance")
    if not (isinstance(checks, (int, np.integer)) and checks >= 0):
        raise ParameterError(f"checks_per_interval must be an integer >= 0, got {checks!r}")
    if not (np.isfinite(sample_period) and sample_period > 0):
        raise ParameterError(f"sample_period must be finite and > 0 s, got {sample_period!r}")
