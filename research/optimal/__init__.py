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
"""

from research.optimal._warm import phase_boundaries
from research.optimal._windowing import WindowReport, window_schedule
from research.optimal.time_optimal import TimeOptimalResult, Verification, time_optimal

__all__ = [
    "TimeOptimalResult",
    "Verification",
    "WindowReport",
    "phase_boundaries",
    "time_optimal",
    "window_schedule",
]
