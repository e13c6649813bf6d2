"""The time-optimal reference at a converged grid: ``N`` refined until the cycle time settles.

The OCP's jerk is constant on ``N`` equal intervals per segment, so its cycle time is an upper bound
on the continuous optimum that falls as ``N`` grows (jerk switching times fall between grid points;
``time_optimal``'s module docstring). :func:`converged_time_optimal` solves at ``N``, then at
``ceil(growth N)`` warm-started from the previous solution, and stops when one refinement changes
the cycle time by less than ``rel_change`` (issue 19: 0.1 %). The refinement ratio 1.5 is the
middle of the usual 1.25-2 of grid-convergence studies: every step still moves the switching
times, and a step costs about 2.3x the previous one in IPOPT time (linear algebra ~ N).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from research.errors import ParameterError
from research.optimal.time_optimal import TimeOptimalResult, time_optimal


@dataclass(frozen=True)
class ConvergedOptimum:
    """Outcome of :func:`converged_time_optimal`.

    Attributes:
        result: the solution at the finest ``N`` solved.
        history: ``((N, cycle_time [s], iterations, IPOPT time [s]), ...)`` of every solve, coarse
            to fine.
        converged: the last refinement changed the cycle time by less than ``rel_change``.
        relative_change: ``|T_N - T_prev| / T_N`` of the last refinement.
    """

    result: TimeOptimalResult
    history: tuple[tuple[int, float, int, float], ...]
    converged: bool
    relative_change: float

    @property
    def cycle_time(self) -> float:
        """Cycle time at the finest ``N`` [s]."""
        return self.result.cycle_time

    @property
    def solve_time(self) -> float:
        """IPOPT time summed over every solve of the refinement [s]."""
        return float(sum(h[3] for h in self.history))

    @property
    def iterations(self) -> int:
        """IPOPT iterations summed over every solve of the refinement."""
        return int(sum(h[2] for h in self.history))

    @property
    def intervals(self) -> int:
        """The finest ``N``."""
        return self.result.intervals_per_segment


def converged_time_optimal(path, limits, tolerance, *, start_intervals: int = 16, growth: float = 1.5,
                           rel_change: float = 1e-3, max_intervals: int = 128, warm_start=None,
                           **kwargs) -> ConvergedOptimum:
    """:func:`time_optimal` with ``N`` refined until the cycle time changes by less than ``rel_change``.

    Args:
        path, limits, tolerance: as :func:`time_optimal`.
        start_intervals: the first ``N`` (>= 1).
        growth: refinement ratio (> 1); the next ``N`` is ``ceil(growth N)``.
        rel_change: convergence threshold on ``|T_N - T_prev| / T_N`` (> 0).
        max_intervals: largest ``N`` solved; stopping there unconverged is reported
            (``converged = False``), not raised.
        warm_start: warm start of the first solve (each refinement starts from the previous solution).
        **kwargs: passed to :func:`time_optimal` (feed, window, modes, residual_vibration, ...).

    Returns:
        A :class:`ConvergedOptimum`.

    Raises:
        ParameterError: bad refinement settings; :func:`time_optimal`'s own errors.
    """
    if not (isinstance(start_intervals, int) and 1 <= start_intervals <= max_intervals):
        raise ParameterError(f"start_intervals must be an integer in [1, max_intervals = {max_intervals}], got {start_intervals!r}")
    if not (math.isfinite(growth) and growth > 1):
        raise ParameterError(f"growth must be a finite ratio > 1, got {growth!r}")
    if not (math.isfinite(rel_change) and rel_change > 0):
        raise ParameterError(f"rel_change must be finite and > 0, got {rel_change!r}")
    N = start_intervals
    res = time_optimal(path, limits, tolerance, intervals_per_segment=N, warm_start=warm_start, **kwargs)
    history = [(N, res.cycle_time, res.iterations, res.solve_time)]
    change = math.inf
    while change >= rel_change and N < max_intervals:
        N = min(max(math.ceil(growth * N), N + 1), max_intervals)
        finer = time_optimal(path, limits, tolerance, intervals_per_segment=N, warm_start=res, **kwargs)
        change = abs(finer.cycle_time - res.cycle_time) / finer.cycle_time
        res = finer
        history.append((N, res.cycle_time, res.iterations, res.solve_time))
    return ConvergedOptimum(res, tuple(history), change < rel_change, change)
