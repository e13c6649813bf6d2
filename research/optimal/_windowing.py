"""Receding-window solution of long paths (Sencer 2009 thesis, §3.5, Fig 3.7).

The thesis optimises the feed of a long tool path in a moving window of about 20 control points
that advances with an overlap of 5 points from the previous solution. Here a window holds
``window`` consecutive segments (phases); after it is solved, its first ``window - overlap``
segments are committed and the next window starts from the committed state ``[p, v, a]`` at the
last committed node (position, velocity and acceleration are continuous across the joint; the jerk
is piecewise constant anyway). The ``overlap`` segments left over are look-ahead: they are solved
again in the next window, warm-started from this window's solution.

Every window ends at rest on its last vertex. That terminal state makes the scheme recursively
feasible (the next window can always repeat the committed tail of the previous solution, stop on
the same vertex and go on from rest), and it costs nothing on the committed part as long as the
look-ahead is longer than the braking distance (about ``F (T_a + T_j) / 2`` for an S-curve stop;
30 mm at 250 mm/s and the Sencer 2015 envelope). The last window runs to the path end; only there
is a residual-vibration bound imposed (structural modes, ``_vibration``).

A look-ahead of ``overlap`` segments is shorter than the braking distance on CAM chords (0.25-1 mm
against 9 mm at 200 mm/s under a 60/30 ms envelope): every window then brakes within its few
look-ahead chords and commits a slow-down it never needed. ``lookahead`` (a length, e.g.
:func:`braking_distance`) makes each window commit only up to where that much of its path is left.
What is left above the whole-path NLP comes from the warm start: the next window starts from the
last one's solution, which stops on its last vertex, and IPOPT can keep a slow-down there (a
30-chord arc of 0.5 mm: +29 %; writing back only the committed part made the next window's start
inconsistent with its guess and IPOPT reported it infeasible).
"""

from __future__ import annotations

import time
from dataclasses import dataclass, replace

import numpy as np
from tqdm.auto import tqdm

from research.errors import ParameterError

from research.optimal._ocp import (
    Geometry,
    PhaseGrid,
    PhaseProblem,
    ProblemSpec,
    SolveFailure,
    SolveStats,
)


#: windows from which :func:`solve_windows` shows a progress bar (each window is one IPOPT solve of
#: about 0.5 s at 10 segments x 16 intervals: a bar from about 10 s of solving)
PROGRESS_WINDOWS = 20


@dataclass(frozen=True)
class WindowReport:
    """One window of the receding-window solution.

    Attributes:
        first_segment: first segment (phase) of the window.
        stop_segment: one past its last segment.
        committed_stop: one past the last segment kept from this window.
        status: IPOPT return status.
        iterations: IPOPT iterations.
        solve_time: wall-clock time of the IPOPT solve [s].
        duration: motion time of the whole window in its solution [s] (look-ahead included).
    """

    first_segment: int
    stop_segment: int
    committed_stop: int
    status: str
    iterations: int
    solve_time: float
    duration: float


def window_schedule(n_segments: int, window: int | None, overlap: int, lengths=None,
                    lookahead: float = 0.0) -> list[tuple[int, int, int]]:
    """``(first, stop, committed_stop)`` of each window; one window when ``window`` is ``None`` or
    covers the path. Consecutive windows share at least ``overlap`` segments, and with
    ``lookahead > 0`` [mm] (``lengths``: ``(n_segments,)`` [mm]) at least that much path: a window
    commits no segment from which less than ``lookahead`` of its own path is left (the braking
    distance, :func:`braking_distance`, is what makes the terminal stop cost nothing on the
    committed part: module docstring).

    Raises:
        ParameterError: a window of ``window`` segments that cannot commit one segment and keep
            ``lookahead`` after it (naming the window and the length it holds).
    """
    if window is None or window >= n_segments:
        return [(0, n_segments, n_segments)]
    cum = None
    if lookahead > 0:
        cum = np.concatenate([[0.0], np.cumsum(np.asarray(lengths, dtype=np.float64))])
    out, first = [], 0
    while first + window < n_segments:
        stop = first + window
        commit = stop - overlap
        if cum is not None:
            # the last vertex from which the window's path still holds the look-ahead
            commit = min(commit, int(np.searchsorted(cum, cum[stop] - lookahead, side="right")) - 1)
            if commit <= first:
                raise ParameterError(
                    f"window of {window} segments from segment {first} holds {cum[stop] - cum[first + 1]:.4g} mm after "
                    f"its first segment, less than the look-ahead {lookahead:.4g} mm (the braking distance): "
                    "use a larger window")
        out.append((first, stop, commit))
        first = commit
    out.append((first, n_segments, n_segments))
    return out


def braking_distance(limits, feed: float) -> float:
    """Longest distance [mm] a jerk-limited stop from the path speed ``feed`` [mm/s] may need under
    per-axis ``limits``: along any direction ``u`` the tangential acceleration and jerk the axes
    allow are at least the smallest limits ``A = min A_i``, ``J = min J_i`` (``A_i / |u_i| >= A_i``),
    and an S-curve stop from ``V`` at those takes ``V (V / A + A / J) / 2`` when it reaches ``A``
    (``V >= A^2 / J``), ``V sqrt(V / J)`` when it does not (the double-S law, Biagiotti &
    Melchiorri 2008 §3.4)."""
    A, J = float(np.min(limits.acceleration)), float(np.min(limits.jerk))
    V = float(feed)
    if not np.isfinite(J):
        return V * V / (2.0 * A)
    return 0.5 * V * (V / A + A / J) if V >= A * A / J else V * np.sqrt(V / J)


class WindowFailure(Exception):
    """Internal: a window did not solve; ``failure`` is the IPOPT outcome, ``first`` its first
    segment (phases are local to the window)."""

    def __init__(self, failure: SolveFailure, first: int, stop: int):
        self.failure, self.first, self.stop = failure, first, stop
        super().__init__(failure.stats.status)


def solve_windows(
    geometry: Geometry, spec: ProblemSpec, guess: PhaseGrid, initial_state: np.ndarray,
    schedule: list[tuple[int, int, int]], ipopt_options: dict | None,
) -> tuple[PhaseGrid, list[WindowReport], float]:
    """Solve window after window and stitch the committed parts.

    Args:
        geometry: all segments of the path.
        spec: problem constants; ``n_phases`` is replaced by each window's size.
        guess: warm start on the whole path's phase grid.
        initial_state: ``(3, d)`` start state (the first vertex, at rest); the modes start from
            ``guess.modes[0]`` and their state is carried across windows like ``[p, v, a]``.
        schedule: from :func:`window_schedule`; from :data:`PROGRESS_WINDOWS` windows on, a
            progress bar (tqdm, on stderr) follows them.
        ipopt_options: IPOPT options.

    Returns:
        ``(solution on the whole grid, window reports, time spent building NLPs [s])``.
    """
    N, M = spec.intervals, guess.durations.size
    durations, states, jerks = guess.durations.copy(), guess.states.copy(), guess.jerks.copy()
    modes = None if guess.modes is None else guess.modes.copy()
    problems: dict[tuple[int, bool], PhaseProblem] = {}
    build_time = 0.0
    reports = []
    state = np.asarray(initial_state, dtype=np.float64)
    mode_state = None if modes is None else modes[0].copy()
    bar = tqdm(schedule, desc="time-optimal windows", unit="window", disable=len(schedule) < PROGRESS_WINDOWS,
               leave=False)
    for first, stop, commit in bar:
        n, terminal = stop - first, stop == M
        if (n, terminal) not in problems:
            t0 = time.perf_counter()
            problems[n, terminal] = PhaseProblem(replace(spec, n_phases=n, terminal=terminal), ipopt_options)
            build_time += time.perf_counter() - t0
        window_geometry = Geometry(*(np.asarray(x)[first:stop] for x in (
            geometry.start, geometry.end, geometry.direction, geometry.length, geometry.min_duration)))
        window_modes = None if modes is None else modes[first * N : stop * N + 1].copy()
        window_guess = PhaseGrid(durations[first:stop], states[first * N : stop * N + 1].copy(), jerks[first * N : stop * N], window_modes)
        window_guess.states[0] = state
        try:
            solution, stats = problems[n, terminal].solve(window_geometry, state, window_guess, mode_state)
        except SolveFailure as failure:
            raise WindowFailure(failure, first, stop) from None
        solution.states[0] = state  # the joint state is the committed one, bit for bit
        durations[first:stop] = solution.durations
        states[first * N : stop * N + 1] = solution.states
        jerks[first * N : stop * N] = solution.jerks
        state = solution.states[(commit - first) * N].copy()
        if modes is not None:
            solution.modes[0] = mode_state
            modes[first * N : stop * N + 1] = solution.modes
            mode_state = solution.modes[(commit - first) * N].copy()
        reports.append(_report(first, stop, commit, stats, float(solution.durations.sum())))
    return PhaseGrid(durations, states, jerks, modes), reports, build_time


def _report(first: int, stop: int, commit: int, stats: SolveStats, duration: float) -> WindowReport:
    return WindowReport(first, stop, commit, stats.status, stats.iterations, stats.solve_time, duration)
