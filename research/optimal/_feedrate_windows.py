"""Whole-path or windowed solution of the B-spline feed optimization (Sencer 2009 thesis §3.5,
Fig 3.7), with dense verification and refinement of the check points.

Windows. The thesis optimizes about 20 control points at a time and moves on with an overlap of
5. Here window ``w`` frees control points ``[first, first + window - 3)``; the three control points
before it are fixed to the committed solution (they shape the first spans of the window) and, except
in the last window, its last three are fixed to the rest feed ``f_b``. That terminal creep makes the
scheme recursively feasible (the next window can always repeat the look-ahead and creep on), and it
costs nothing on the committed part ``[first, first + window - overlap)`` as long as the look-ahead
(``overlap`` control points) is longer than the braking distance. Each window's constraints cover
every knot span that its free control points touch.

Refinement. Constraints hold at the check points only. After each pass the motion is checked on 32
points per knot span; spans where a limit is exceeded by more than ``tolerance`` get twice the check
points and the pass is repeated, warm-started (at most ``refinements`` times).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from research.optimal._feedrate_nlp import WindowData, WindowSolution, solve_window
from research.optimal._feedrate_spline import gauss_nodes, span_points
from research.optimal._windowing import window_schedule

DENSE = 32  # verification points per knot span


@dataclass(frozen=True)
class FeedWindowReport:
    """One window of the feed optimization.

    Attributes:
        first, stop: control points ``[first, stop)`` in the window; committed_stop: one past the
            last control point kept from it.
        status, iterations, solve_time [s], build_time [s]: IPOPT outcome and costs.
        pass_index: refinement pass (0 = first).
    """

    first: int
    stop: int
    committed_stop: int
    status: str
    iterations: int
    solve_time: float
    build_time: float
    pass_index: int


def feed_window_schedule(n: int, window: int | None, overlap: int) -> list[tuple[int, int, int]]:
    """``(first, stop, committed_stop)`` over the free control points ``[2, n - 2)``: the schedule of
    :func:`research.optimal._windowing.window_schedule`, shifted past the two fixed points at each end."""
    return [(first + 2, stop + 2, committed + 2) for first, stop, committed in window_schedule(n - 4, window, overlap)]


class WindowFailed(Exception):
    """A window NLP failed; ``solution.values`` holds IPOPT's last point over ``columns``."""

    def __init__(self, solution: WindowSolution, first: int, stop: int, columns: np.ndarray):
        self.solution, self.first, self.stop, self.columns = solution, first, stop, columns
        super().__init__(solution.status)


def solve_passes(problem, values: np.ndarray, schedule, refinements: int, tolerance: float, options):
    """Run the windows, verify densely, refine check points where needed.

    Args:
        problem: the ``_Problem`` of ``feedrate.py`` (knots, derivative lookup, limits, ...).
        values: ``(n,)`` initial control values [mm/s] (warm start; ends at ``f_b``).
    Returns:
        ``(values, reports, dense worst ratio per span)``.
    """
    n_spans = problem.knots.size - 7
    per_span = np.full(n_spans, problem.checks_per_span)
    per_span[[0, 1, -2, -1]] *= 4  # next to the rest ramps the feed changes fastest relative to itself
    reports: list[FeedWindowReport] = []
    for p in range(refinements + 1):
        values = values.copy()
        for first, stop, commit in schedule:
            last = stop == problem.n - 2
            data = _window(problem, values, first, stop, last, per_span)
            sol = solve_window(data, options)
            if not sol.success:
                raise WindowFailed(sol, first, stop, data.columns)
            # committed part and look-ahead (the warm start of the next window) alike
            values[data.columns[data.free]] = sol.values[data.free]
            reports.append(FeedWindowReport(first, stop, stop if last else commit, sol.status, sol.iterations,
                                            sol.solve_time, sol.build_time, p))
        worst = span_worst(problem, values)
        bad = worst > 1 + tolerance
        if not bad.any() or p == refinements:
            return values, reports, worst
        per_span = np.where(bad, per_span * 2, per_span)
    raise AssertionError("unreachable")


def _window(problem, values, first, stop, last, per_span) -> WindowData:
    n = problem.n
    end = n if last else stop  # the last window also holds the two rest-feed end points
    cols = np.arange(max(first - 3, 0), end)
    free = (cols >= first) & (cols < (stop if last else stop - 3))
    vals = values[cols].copy()
    if not last:
        vals[cols >= stop - 3] = problem.rest_feed
    spans = np.arange(max(first - 3, 0), end - 3)  # span j uses control points j..j+3
    checks = span_points(problem.knots, spans, per_span)
    d = problem.derivatives(checks)
    nodes, weights = gauss_nodes(problem.knots, spans)
    return WindowData(
        knots=problem.knots, columns=cols, free=free, values=vals, checks=checks,
        Qs=d.Q_s, Qss=d.Q_ss, Qsss=d.Q_sss, nodes=nodes, weights=weights,
        velocity=problem.limits.velocity, acceleration=problem.limits.acceleration, jerk=problem.limits.jerk,
        feed=problem.feed, feed_min=0.5 * problem.rest_feed, form=problem.form, objective=problem.objective,
    )


def span_worst(problem, values: np.ndarray) -> np.ndarray:
    """Largest limit ratio (axes and feed cap) on ``DENSE + 1`` points of every knot span."""
    n_spans = problem.knots.size - 7
    s = span_points(problem.knots, np.arange(n_spans), DENSE)
    ratios = problem.ratios(s, values)  # (N,)
    h = problem.knots[4] - problem.knots[3]
    span = np.clip(((s - problem.knots[3]) / h).astype(int), 0, n_spans - 1)
    worst = np.zeros(n_spans)
    np.maximum.at(worst, span, ratios)
    # a point on a knot belongs to both neighbouring spans
    on_knot = np.isclose((s - problem.knots[3]) / h, np.round((s - problem.knots[3]) / h)) & (span > 0)
    np.maximum.at(worst, span[on_knot] - 1, ratios[on_knot])
    return worst

