"""Feed-rate scheduling along smooth 5-axis tool paths under axis velocity, acceleration and jerk
limits (Sencer 2009 thesis ch 3, issue 8).

The tool path is a B-spline in tool tip and tool axis (:class:`~research.paths.pose_spline.PoseSpline`),
mapped to axis positions ``Q(s)`` of an A/C table-tilting machine by the inverse kinematics (eq 3.21,
4.6), with ``Q_s, Q_ss, Q_sss`` along the tool-tip arc length ``s`` (eq 3.27-3.28).

- :func:`optimize_feedrate`: the thesis' method. The feed ``f(s)`` is a cubic B-spline in arc length
  (eq 3.31-3.38); its control points are optimized by IPOPT (CasADi) for minimum time (eq 3.30 /
  3.58) under every axis' velocity, acceleration and jerk limit (eq 3.39-3.56) and a feed cap
  (eq 3.57), over the whole path or in overlapping windows (§3.5). Rest ends are constant-jerk
  ramps in time joined to the spline (see ``_feedrate_spline``: a feed polynomial in ``s`` cannot
  start from rest in finite time).
- :func:`reference_ocp`: a direct path-parametrized optimal-control problem in time (states ``s, s',
  s''``, control ``s'''``) to compare against.
- :func:`constant_feed`: the constant-feed baseline (thesis: 15 mm/s, 20.18 s).
- :func:`axis_feed_limits`: the axis limits reflected on the feed (Fig 3.10); ``result.binding`` says
  which axis limit binds where.

Every result carries a :class:`~research.trajectory.Trajectory` (axes ``x, y, z, a, c`` [mm, rad])
and a dense check of all limits (:class:`LimitCheck`).
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np
from scipy.interpolate import BSpline

from research.errors import InfeasibleProblem, ParameterError
from research.interpolators.scurve import scurve_profile
from research.limits import AxisLimits
from research.optimal._arrays import frozen
from research.optimal._feedrate_check import (
    AXES,
    Binding,
    LimitCheck,
    axis_feed_limits,
    axis_motion,
    binding_intervals,
    check,
    limit_ratios,
)
from research.optimal._feedrate_ocp import solve_ocp
from research.optimal._feedrate_setup import (
    Problem,
    braking_distance,
    check_creep,
    failed_ends,
    rest_ramp,
    warm_start,
)
from research.optimal._feedrate_spline import (
    FeedTimeLaw,
    RestRamp,
    clamped_knots,
    span_points,
)
from research.optimal._feedrate_windows import (
    DENSE,
    FeedWindowReport,
    WindowFailed,
    feed_window_schedule,
    solve_passes,
)
from research.paths.kinematics5 import TableTiltingAC
from research.paths.pose_spline import PoseSpline
from research.piecewise import PiecewisePolynomial
from research.trajectory import Trajectory

__all__ = ["Binding", "FeedWindowReport", "FeedrateResult", "LimitCheck", "axis_feed_limits", "constant_feed",
           "optimize_feedrate", "reference_ocp", "table31_limits"]

#: Table 3.1 A / C jerk as printed ([deg/s^3]); read here as rad/s^3, see :func:`table31_limits`
TABLE31_ROTARY_JERK = (250.0, 200.0)


def table31_limits(rotary_jerk_unit: str = "rad") -> AxisLimits:
    """The drive limits of thesis Table 3.1 in package units (mm, rad).

    X, Y, Z: 250 mm/s, 2000 mm/s^2, 3000 mm/s^3. A: 166 deg/s, 2500 deg/s^2; C: 290 deg/s,
    2000 deg/s^2. The table lists A / C jerk as 250 / 200 deg/s^3, which is inconsistent with the
    accelerations (10 s to build up 2500 deg/s^2). We read those two numbers as rad/s^3 (14 324 and
    11 459 deg/s^3, jerk / acceleration about 5.7 /s, the same order as X-Z's 1.5 /s) by default;
    ``rotary_jerk_unit="deg"`` gives the literal reading.
    """
    if rotary_jerk_unit not in ("rad", "deg"):
        raise ParameterError(f"rotary_jerk_unit must be 'rad' or 'deg', got {rotary_jerk_unit!r}")
    jA, jC = TABLE31_ROTARY_JERK if rotary_jerk_unit == "rad" else np.radians(TABLE31_ROTARY_JERK)
    d = np.radians
    return AxisLimits(np.array([250.0, 250.0, 250.0, d(166.0), d(290.0)]),
                      np.array([2000.0, 2000.0, 2000.0, d(2500.0), d(2000.0)]),
                      np.array([3000.0, 3000.0, 3000.0, jA, jC]))


@dataclass(frozen=True)
class FeedrateResult:
    """A feed schedule along a 5-axis path and its axis motion.

    Attributes:
        trajectory: axis motion ``x, y, z, a, c`` [mm, rad] sampled at ``sample_period`` (``exact``
            is ``None``: the motion is not piecewise polynomial in time).
        cycle_time: ``T_Sigma`` [s].
        method: ``"bspline"``, ``"bspline-windowed"``, ``"ocp"`` or ``"constant"``.
        s, feed: dense arc-length grid [mm] and the feed there [mm/s] (Fig 3.11).
        check: dense verification of all limits (32 points per knot span; 16 per interval for the
            OCP; 4000 or more points in time for the constant feed).
        binding: where an axis limit or the feed cap is active (ratio >= 0.98).
        status, iterations, solve_time [s], build_time [s]: solver outcome (summed over windows).
        windows: window reports (B-spline method).
        knots, control_points: the feed B-spline ``f(s)`` (B-spline method).
        rest_feed: creep feed at the ends of non-final windows [mm/s].
        ramps: the start and stop ramps (:class:`RestRamp`, B-spline method).
        path_states: ``(4, N)`` path position ``s`` and its first three time derivatives at the
            trajectory's sample times [mm, mm/s^k].
    """

    trajectory: Trajectory
    cycle_time: float
    method: str
    s: np.ndarray
    feed: np.ndarray
    check: LimitCheck
    binding: tuple[Binding, ...]
    status: str = "n/a"
    iterations: int = 0
    solve_time: float = 0.0
    build_time: float = 0.0
    windows: tuple[FeedWindowReport, ...] = ()
    knots: np.ndarray | None = field(default=None, repr=False)
    control_points: np.ndarray | None = field(default=None, repr=False)
    rest_feed: float = 0.0
    ramps: tuple[RestRamp, RestRamp] | None = None
    path_states: np.ndarray | None = field(default=None, repr=False)

    def binding_summary(self) -> str:
        """One line per binding stretch, e.g. ``"  34.1- 36.0 mm  x jerk (1.000)"``."""
        return "\n".join(f"{b.s_start:7.1f}-{b.s_end:6.1f} mm  {b.axis} {b.kind} ({b.peak:.3f})" for b in self.binding)


def optimize_feedrate(
    path: PoseSpline,
    limits: AxisLimits,
    feed: float,
    *,
    machine: TableTiltingAC | None = None,
    control_points: int | None = None,
    checks_per_span: int = 4,
    window: int | None = None,
    overlap: int | None = None,
    rest_feed: float = 1.0,
    ramp: str = "s-curve",
    constraint_form: str = "per_axis",
    objective: str = "time",
    sample_period: float = 1e-3,
    refinements: int = 3,
    tolerance: float = 2e-3,
    solver_options: dict | None = None,
) -> FeedrateResult:
    """Minimum-time B-spline feed schedule along ``path`` (thesis eq 3.31-3.58, §3.5).

    Args:
        path: the tool path (tip arc length ``S`` [mm]).
        limits: ``x, y, z, a, c`` velocity, acceleration, jerk limits [mm, rad per s^k], finite.
        feed: programmed feed cap ``F`` [mm/s] (eq 3.57, ``C_F+``); thesis: 150 mm/s.
        machine: kinematics (default: ``TableTiltingAC()``, zero offsets).
        control_points: feed control points ``n`` (default: about one per mm, ``ceil(S) + 3``;
            thesis: 276 on 300 mm).
        checks_per_span: constraint check points per knot span (thesis: ``Delta s`` 0.1-1 mm).
        window: control points per window (``None``: the whole path in one NLP; thesis: about 20).
        overlap: control points of look-ahead re-solved by the next window (>= 4; default: the
            braking distance from ``F`` under the path's tangential limits, plus 4).
        rest_feed: creep feed ``f_b`` [mm/s] at the end of every non-final window (zero path
            acceleration there, see ``_feedrate_windows``); must be feasible everywhere on the path.
        ramp: start / stop joined to the spline at zero path acceleration (``"s-curve"``, robust)
            or while still accelerating (``"accelerating"``: closer to the time optimum; falls back
            to ``"s-curve"`` when the spline's first spans cannot follow it); see ``_feedrate_spline``.
        constraint_form: ``"per_axis"`` (eq 3.41/3.46/3.53) or ``"combined"`` (eq 3.43/3.49/3.56).
        objective: ``"time"`` (``int ds / f``, eq 3.30) or ``"sum"`` (``max sum f_i``, eq 3.58).
        sample_period: ``Ts`` of the returned trajectory [s].
        refinements: passes that double the check points of spans where the dense check finds a
            limit exceeded by more than ``tolerance`` (relative).
        solver_options: IPOPT options (override ``print_level`` 0, ``tol`` 1e-9, ...).

    Returns:
        A :class:`FeedrateResult` (``method`` ``"bspline"`` or ``"bspline-windowed"``).

    Raises:
        ParameterError: malformed arguments.
        InfeasibleProblem: ``feed <= 0``; the limits cannot hold even ``rest_feed`` somewhere (the
            message names the place, axis and limit); or IPOPT fails in a window.
    """
    machine = machine or TableTiltingAC()
    _check_args(path, limits, feed, sample_period)
    S = path.length
    n = int(control_points) if control_points is not None else int(np.ceil(S)) + 3
    if not (isinstance(checks_per_span, (int, np.integer)) and checks_per_span >= 1) or n < 8:
        raise ParameterError(f"need control_points >= 8 and checks_per_span >= 1, got {n} and {checks_per_span!r}")
    if constraint_form not in ("per_axis", "combined") or objective not in ("time", "sum"):
        raise ParameterError(f"constraint_form must be 'per_axis' or 'combined' and objective 'time' or 'sum', "
                             f"got {constraint_form!r}, {objective!r}")
    if not (np.isfinite(rest_feed) and 0 < rest_feed < feed):
        raise ParameterError(f"rest_feed must be in (0, feed = {feed}) mm/s, got {rest_feed!r}")
    if overlap is None:
        overlap = int(np.ceil(braking_distance(path, machine, limits, feed) / (S / (n - 3)))) + 4
    if window is not None and not (isinstance(window, (int, np.integer)) and 4 <= overlap < window):
        raise ParameterError(f"need 4 <= overlap < window (control points), got window {window!r}, overlap {overlap!r}")
    if ramp not in ("s-curve", "accelerating"):
        raise ParameterError(f"ramp must be 's-curve' or 'accelerating', got {ramp!r}")
    schedule = feed_window_schedule(n, window, int(overlap))
    s_env = np.linspace(0.0, S, max(4001, int(S / 0.05)))
    env = axis_feed_limits(path, limits, s_env, machine)
    check_creep(s_env, env, float(rest_feed))
    args = (path, machine, limits, float(rest_feed), float(feed), s_env, env)
    # per end (start, stop): the joints to try, closest to the optimum first; the S-curve joint
    # always works (its constant-feed warm start is feasible)
    options = [[rest_ramp(*args, end, None, False)] for end in (0, 1)]
    if ramp == "accelerating":
        options = [[rest_ramp(*args, end, S / (n - 3), True), rest_ramp(*args, end, None, True)] + options[end]
                   for end in (0, 1)]
    level = [0, 0]
    while True:
        ramps = (options[0][level[0]], options[1][level[1]])
        knots = clamped_knots(n, ramps[0].length, S - ramps[1].length)
        problem = Problem(path, machine, limits, float(feed), knots, float(rest_feed), int(checks_per_span),
                           constraint_form, objective, ramps[0].end_controls(knots), ramps[1].end_controls(knots))
        try:
            values, reports, _ = solve_passes(problem, warm_start(problem), schedule, refinements, tolerance,
                                              solver_options)
            break
        except WindowFailed as exc:
            stepped = False
            for end in failed_ends(problem, exc):  # the first spans could not follow this joint
                if level[end] + 1 < len(options[end]):
                    level[end] += 1
                    stepped = True
            if not stepped:
                raise _failure(exc, problem) from None
    spline = BSpline(knots, values, 3, extrapolate=False)
    law = FeedTimeLaw(spline, ramps[0], ramps[1], S)
    result = _result(path, machine, limits, feed, law.states, law.duration, sample_period,
                     "bspline" if len(schedule) == 1 else "bspline-windowed", _dense_s(knots, ramps, S))
    statuses = [r.status for r in reports]
    return _replace(result, status=next((s for s in statuses if s != "Solve_Succeeded"), "Solve_Succeeded"),
                    iterations=sum(r.iterations for r in reports), solve_time=sum(r.solve_time for r in reports),
                    build_time=sum(r.build_time for r in reports), windows=tuple(reports), knots=knots,
                    control_points=values, rest_feed=float(rest_feed), ramps=ramps)


def constant_feed(path: PoseSpline, limits: AxisLimits, feed: float, *, machine: TableTiltingAC | None = None,
                  sample_period: float = 1e-3) -> FeedrateResult:
    """Constant feed ``F`` along the whole path with jerk-limited S-curve start and stop in ``s``.

    The tangential acceleration and jerk of the start and stop are 90 % of the smallest
    ``limit_i / |Q_s,i|`` over the path (what the axes allow at low speed, with room for the
    curvature terms of eq 3.27). The axis limits are *not* enforced elsewhere:
    ``result.check`` says whether ``F`` respects them (thesis §3.6: 15 mm/s does, 150 mm/s does not).
    """
    machine = machine or TableTiltingAC()
    _check_args(path, limits, feed, sample_period)
    S = path.length
    qs = np.abs(path.axis_derivatives(machine, np.linspace(0.0, S, 2001)).Q_s).max(axis=0)
    with np.errstate(divide="ignore"):
        A, J = 0.9 * float(np.min(limits.acceleration / qs)), 0.9 * float(np.min(limits.jerk / qs))
    prof = scurve_profile(S, float(feed), A, J)

    def states(t):
        t = np.clip(np.asarray(t, dtype=np.float64), 0.0, float(prof.end))
        return tuple(prof.evaluate_numpy(t, nu)[:, 0] for nu in range(4))

    T = float(prof.end)
    return _result(path, machine, limits, feed, states, T, sample_period, "constant",
                   None, times=np.linspace(0.0, T, max(4001, int(T / 1e-3) + 1)), cap=False)


def reference_ocp(path: PoseSpline, limits: AxisLimits, feed: float, *, machine: TableTiltingAC | None = None,
                  intervals: int = 200, checks: int = 1, warm_start: FeedrateResult | None = None,
                  sample_period: float = 1e-3, solver_options: dict | None = None) -> FeedrateResult:
    """Minimum-time motion along ``path`` from the direct path-parametrized OCP (states: ``s`` and
    its first two time derivatives; control: the third; see ``_feedrate_ocp``), the reference for
    :func:`optimize_feedrate`.

    Args:
        intervals: ``N`` equal time intervals (piecewise-constant path jerk).
        checks: extra constraint points inside each interval.
        warm_start: a schedule along the same path (default: :func:`optimize_feedrate` with one
            control point per 3 mm).

    Returns:
        A :class:`FeedrateResult` with ``method = "ocp"``; ``check`` samples 16 points per interval.

    Raises:
        ParameterError: malformed arguments; InfeasibleProblem: ``feed <= 0`` or IPOPT fails.
    """
    machine = machine or TableTiltingAC()
    _check_args(path, limits, feed, sample_period)
    if not (isinstance(intervals, (int, np.integer)) and intervals >= 4 and isinstance(checks, (int, np.integer)) and checks >= 0):
        raise ParameterError(f"need intervals >= 4 and checks >= 0, got {intervals!r}, {checks!r}")
    if warm_start is None:
        warm_start = optimize_feedrate(path, limits, feed, machine=machine,
                                       control_points=max(12, int(np.ceil(path.length / 3)) + 3), refinements=1)
    ws_t = np.asarray(warm_start.trajectory.t)
    nodes = np.linspace(0.0, warm_start.cycle_time, intervals + 1)
    guess = np.vstack([np.interp(nodes, ws_t, x) for x in warm_start.path_states])
    guess[:, -1] = [path.length, 0.0, 0.0, 0.0]
    T, X, U, stats = solve_ocp(path, machine, limits, float(feed), int(intervals), guess, warm_start.cycle_time,
                               int(checks), options=solver_options)
    if not stats["success"]:
        err = InfeasibleProblem(f"reference OCP: IPOPT stopped with status {stats['status']!r} after "
                                f"{stats['iterations']} iterations ({intervals} intervals)")
        err.status, err.constraint, err.iterations = stats["status"], "ocp", stats["iterations"]
        raise err
    h = T / intervals
    coeffs = np.stack([X[0, :-1], X[1, :-1], X[2, :-1] / 2, U / 6], axis=1)[:, :, None]
    pp = PiecewisePolynomial(np.arange(intervals + 1) * h, coeffs)

    def states(t):
        t = np.clip(np.asarray(t, dtype=np.float64), 0.0, T)
        return tuple(pp.evaluate_numpy(t, nu)[:, 0] for nu in range(4))

    dense = (np.arange(intervals)[:, None] * h + h * np.linspace(0, 1, 17)[None, :]).ravel()
    result = _result(path, machine, limits, feed, states, T, sample_period, "ocp", None, times=np.unique(dense))
    return _replace(result, status=stats["status"], iterations=stats["iterations"], solve_time=stats["solve_time"],
                    build_time=stats["build_time"])


# -- shared helpers -----------------------------------------------------------------------------
def _result(path, machine, limits, feed, states, duration, Ts, method, s_dense, times=None, cap=True) -> FeedrateResult:
    """Trajectory at ``Ts``, dense check on ``s_dense`` (points in ``s``) or ``times``."""
    n = int(np.ceil(duration / Ts - 1e-9)) + 1
    t = np.arange(n) * Ts
    st = states(t)
    q, v, a, j = axis_motion(path, machine, *st)
    traj = Trajectory(t, q, v, a, j, np.float64(duration), None, AXES, float(Ts))
    dense_t = times if times is not None else _times_of(states, s_dense, duration)
    ds = states(dense_t)
    _, v, a, j = axis_motion(path, machine, *ds)
    ratios = limit_ratios(v, a, j, limits)
    return FeedrateResult(
        trajectory=traj, cycle_time=float(duration), method=method, s=frozen(ds[0]), feed=frozen(ds[1]),
        path_states=frozen(np.vstack(st)),
        check=check(v, a, j, ds[1], limits, feed if cap else None),
        binding=binding_intervals(ds[0], ratios, ds[1] / feed if cap else None),
    )


def _times_of(states, s_dense, duration) -> np.ndarray:
    """Times at which the motion passes ``s_dense`` (bisection-free: states are monotone in t)."""
    t = np.linspace(0.0, duration, max(20 * s_dense.size, 20001))
    s = states(t)[0]
    return np.interp(s_dense, s, t)


def _dense_s(knots, ramps, S: float) -> np.ndarray:
    spans = np.arange(knots.size - 7)
    inner = span_points(knots, spans, DENSE)
    r0, r1 = (r.profile().evaluate_numpy(np.linspace(0.0, r.duration, 65), 0)[:, 0] for r in ramps)
    return np.unique(np.concatenate([r0, inner, S - r1[::-1]]))


def _failure(exc: WindowFailed, problem: Problem) -> InfeasibleProblem:
    kn = problem.knots
    err = InfeasibleProblem(
        f"feed optimization: IPOPT stopped with status {exc.solution.status!r} after {exc.solution.iterations} "
        f"iterations in the window of control points {exc.first}..{exc.stop - 1} (s = {kn[min(exc.first + 2, kn.size - 1)]:.4g}"
        f"-{kn[min(exc.stop + 2, kn.size - 1)]:.4g} mm)")
    err.status, err.constraint, err.iterations = exc.solution.status, "window", exc.solution.iterations
    return err


def _check_args(path, limits, feed, sample_period) -> None:
    if not isinstance(path, PoseSpline):
        raise ParameterError(f"path must be a PoseSpline, got {type(path).__name__}")
    if not isinstance(limits, AxisLimits) or limits.n_axes != 5:
        raise ParameterError(f"limits must be AxisLimits for the 5 axes x, y, z, a, c, got {limits!r}")
    for name in ("velocity", "acceleration", "jerk"):
        if not np.all(np.isfinite(getattr(limits, name))):
            raise ParameterError(f"feed optimization needs finite {name} limits on every axis, got {getattr(limits, name).tolist()}")
    if not np.isfinite(feed):
        raise ParameterError(f"feed must be a finite number of mm/s, got {feed!r}")
    if feed <= 0:
        err = InfeasibleProblem(f"feed cap F = {feed} mm/s <= 0 leaves no forward motion (eq 3.57): the path of "
                                f"{path.length:.6g} mm cannot be traversed")
        err.constraint = "feed"
        raise err
    if not (np.isfinite(sample_period) and sample_period > 0):
        raise ParameterError(f"sample_period must be finite and > 0 s, got {sample_period!r}")


def _replace(result: FeedrateResult, **kw) -> FeedrateResult:
    return replace(result, **kw)
