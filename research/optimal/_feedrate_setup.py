"""Setting up the B-spline feed optimization (``feedrate.py``): the problem data, the start / stop
ramps (``_feedrate_spline``), the warm start and the look-ahead estimate."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from research.errors import InfeasibleProblem
from research.limits import AxisLimits
from research.optimal._feedrate_check import (
    AXES,
    axis_feed_limits,
    axis_motion,
    limit_ratios,
)
from research.optimal._feedrate_spline import RestRamp, basis, span_points
from research.optimal._feedrate_windows import WindowFailed
from research.paths.kinematics5 import TableTiltingAC
from research.paths.pose_spline import PoseSpline


@dataclass(frozen=True)
class Problem:
    """One feed optimization: path, kinematics, limits, feed cap ``F`` [mm/s], the feed knot vector,
    the creep ``rest_feed`` [mm/s], check points per span, constraint form, objective and the fixed
    control values joining the start and stop ramps."""

    path: PoseSpline
    machine: TableTiltingAC
    limits: AxisLimits
    feed: float
    knots: np.ndarray
    rest_feed: float
    checks_per_span: int
    form: str
    objective: str
    start_ends: tuple[float, float]  # (f_0, f_1) joining the start ramp
    stop_ends: tuple[float, float]  # (f_(n-1), f_(n-2)) joining the stop ramp

    @property
    def n(self) -> int:
        return self.knots.size - 4

    def derivatives(self, s):
        return self.path.axis_derivatives(self.machine, s)

    def ratios(self, s, values) -> np.ndarray:
        """Largest limit ratio (axes and feed cap) at ``s`` [mm] for control values ``values``."""
        f, f1, f2 = (basis(self.knots, s, nu) @ values for nu in range(3))
        _, v, a, j = axis_motion(self.path, self.machine, s, f, f * f1, f * (f1 * f1 + f * f2))
        return np.maximum(limit_ratios(v, a, j, self.limits).max(axis=(1, 2)), f / self.feed)


def check_creep(s, env: dict[str, np.ndarray], rest_feed: float) -> None:
    """The creep ``rest_feed`` must be feasible everywhere (with a factor 2 to spare): it is the
    terminal feed of every non-final window. Raises :class:`InfeasibleProblem` naming where not."""
    for kind, lim in env.items():
        k, i = np.unravel_index(np.argmin(lim), lim.shape)
        if lim[k, i] < 2 * rest_feed:
            err = InfeasibleProblem(
                f"feed optimization: the {AXES[i]} {kind} limit allows at most {lim[k, i]:.4g} mm/s at s = {s[k]:.4g} mm "
                f"(eq 3.42/3.50/3.54), below twice the rest feed {rest_feed:g} mm/s that the window ends creep "
                "at; raise the limits or lower rest_feed")
            err.constraint, err.axis, err.s = kind, AXES[i], float(s[k])
            raise err


def rest_ramp(path, machine, limits: AxisLimits, rest_feed: float, feed: float, s, env, end: int,
               spacing: float | None, accelerating: bool) -> RestRamp:
    """The start (``end = 0``) or stop (``end = 1``) ramp (``_feedrate_spline``): path jerk ``J_r``
    the smallest ``j_i / |Q_s,i|`` over the 0.5 mm at that end; ramp feed ``f_r`` the smallest of
    ``F / 2``, half the envelope of eq 3.42/3.50/3.54 over the 10 mm at that end, the feed that keeps
    the ramp's peak acceleration within 90 % of ``a_i / |Q_s,i|`` and, if ``spacing`` is given, the
    feed at which the ramp is a third of a knot span long (``spacing`` [mm]; shorter ramps leave more
    to the spline, which then follows the optimal start closely, measured against the OCP); both
    scaled down until a dense check of the ramp gives at most 99 % of every limit."""
    S = path.length
    dist = s if end == 0 else S - s
    near = dist <= min(10.0, S / 4)
    envelope = min(float(e[near].min()) for e in env.values())
    qs = np.abs(path.axis_derivatives(machine, s[dist <= min(0.5, S / 8)]).Q_s).max(axis=0)
    with np.errstate(divide="ignore"):
        J, A = float(np.min(limits.jerk / qs)), 0.9 * float(np.min(limits.acceleration / qs))
    short = np.inf if spacing is None else 0.5 * J * (2 * spacing / J) ** (2 / 3)  # s_r = spacing / 3
    f = max(rest_feed, min(0.5 * feed, 0.5 * envelope, A * A / (2 * J) if accelerating else A * A / J, short))
    sign, origin = (1.0, 0.0) if end == 0 else (-1.0, S)  # the stop ramp runs backwards from S
    for _ in range(20):
        ramp = RestRamp(f, J, accelerating)
        if ramp.length > S / 8:
            f *= 0.5
            continue
        st = [ramp.profile().evaluate_numpy(np.linspace(0.0, ramp.duration, 201), nu)[:, 0] for nu in range(4)]
        _, v, a, j = axis_motion(path, machine, origin + sign * st[0], st[1], sign * st[2], st[3])
        worst = float(limit_ratios(v, a, j, limits).max())
        if worst <= 0.99:
            return ramp
        J, f = J * 0.99 / worst, max(rest_feed, f * 0.99 / worst)
    return ramp


def failed_ends(problem: Problem, exc: WindowFailed) -> list[int]:
    """Which ends' joints to give up after a failed window: where the failed point violates the
    limits by more than 1 % within 10 knot spans of the start (0) or of the end (1); both when the
    violation is elsewhere."""
    values = warm_start(problem)
    values[exc.columns] = exc.solution.values
    kn = problem.knots
    s = span_points(kn, np.arange(kn.size - 7), 8)
    bad = s[problem.ratios(s, values) > 1.01]
    h = kn[4] - kn[3]
    ends = [e for e, hit in enumerate((bad <= kn[3] + 10 * h, bad >= kn[-4] - 10 * h)) if hit.any()]
    return ends or [0, 1]


def braking_distance(path, machine, limits, feed) -> float:
    """Stop distance from ``feed`` under the path's smallest tangential acceleration / jerk [mm]."""
    qs = np.abs(path.axis_derivatives(machine, np.linspace(0.0, path.length, 1001)).Q_s).max(axis=0)
    with np.errstate(divide="ignore"):
        A, J = float(np.min(limits.acceleration / qs)), float(np.min(limits.jerk / qs))
    T = feed / A + A / J if feed * J >= A * A else 2 * np.sqrt(feed / J)
    return 0.5 * feed * T


def warm_start(problem: Problem) -> np.ndarray:
    """Control values: the ramp feed, lowered to half the envelope of eq 3.42/3.50/3.54 (and
    the cap) within two knot spans of each control point; a constant feed below the envelope is
    feasible, so this is close to a feasible point. The four end values join the ramps."""
    kn, n = problem.knots, problem.n
    s = span_points(kn, np.arange(n - 3), 4)
    env = axis_feed_limits(problem.path, problem.limits, s, problem.machine)
    low = np.minimum.reduce([e.min(axis=1) for e in env.values()] + [np.full(s.size, problem.feed)])
    greville = np.array([kn[i + 1:i + 4].mean() for i in range(n)])
    h = kn[4] - kn[3]
    vals = np.array([low[np.abs(s - g) <= 2 * h].min() for g in greville]) / 2
    vals = np.clip(vals, problem.rest_feed, max(problem.start_ends[1], problem.stop_ends[1]))
    vals[[0, 1]] = problem.start_ends
    vals[[-1, -2]] = problem.stop_ends
    return vals


