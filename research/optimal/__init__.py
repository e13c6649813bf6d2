"""CasADi optimal-control problems: the time-optimal reference motion (issue 6).

Public API:

- :func:`time_optimal` — minimum-time motion along a polyline within a tolerance tube, under
  per-axis velocity / acceleration / jerk limits and an optional feed limit.
- :class:`TimeOptimalResult` — its trajectory, cycle time, phase durations, solver statistics and
  the dense between-grid-point verification (:class:`Verification`).
- :class:`WindowReport` — one window of the receding-window solution (Sencer 2009 thesis §3.5).
- :func:`window_schedule` — which segments each window solves and commits.
- :func:`phase_boundaries` — when a trajectory passes the vertices of a path (used to map warm
  starts onto the phase grid).
- :func:`converged_time_optimal` — :func:`time_optimal` with ``N`` refined until the cycle time
  changes by < 0.1 % (issue 19); :class:`ConvergedOptimum`.
- :class:`StructuralMode` — a base-excited structural mode for the vibration-aware OCP
  (``time_optimal(..., modes=..., residual_vibration=...)``); :func:`trajectory_vibration` —
  residual vibration and in-motion deflection of any motion (eq V1-V3 of ``_vibration``).
- :func:`optimize_feedrate` — B-spline feed-rate scheduling along 5-axis paths under axis v/a/j
  limits (Sencer 2009 thesis ch 3, issue 8); :func:`constant_feed`, :func:`reference_ocp`,
  :func:`axis_feed_limits`, :func:`table31_limits`, :class:`FeedrateResult`.
"""

from research.optimal._convergence import ConvergedOptimum, converged_time_optimal
from research.optimal._vibration import StructuralMode, trajectory_vibration
from research.optimal._warm import phase_boundaries
from research.optimal._windowing import WindowReport, window_schedule
from research.optimal.feedrate import (
    FeedrateResult,
    axis_feed_limits,
    constant_feed,
    optimize_feedrate,
    reference_ocp,
    table31_limits,
)
from research.optimal.time_optimal import TimeOptimalResult, Verification, time_optimal

__all__ = [
    "ConvergedOptimum",
    "StructuralMode",
    "converged_time_optimal",
    "trajectory_vibration",
    "FeedrateResult",
    "TimeOptimalResult",
    "Verification",
    "WindowReport",
    "axis_feed_limits",
    "constant_feed",
    "optimize_feedrate",
    "phase_boundaries",
    "reference_ocp",
    "table31_limits",
    "time_optimal",
    "window_schedule",
]
