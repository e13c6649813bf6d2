"""Exact checks of an FIR plan against its tool path: vertex errors and path deviation.

Two measures of the distance between trajectory and programmed path, both on the exact profile:

* the **corner error** of Sencer 2015 (eq 13/14): distance from each vertex to the trajectory,
  searched around the instant the averaging window is centred on the corner's gap;
* the **path deviation**: distance from the trajectory to the path (lines and arcs), on samples
  every ``check_period`` plus the corner instants. Between vertices of short blocks and along
  arcs the trajectory can leave the path where no vertex sees it. Where no sample's averaging
  window holds an input break (a *steady span*, :func:`steady_spans`) the grid is thinned to
  :data:`STEADY_SAMPLES` samples, so that a check costs in proportion to the program's blocks,
  not its duration.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np
from jax import Array

from research.paths.toolpath import ToolPath
from research.interpolators._fir_certify import BETWEEN_RTOL, Certifier, PathFeatures
from research.interpolators._fir_kernels import verified_bound
from research.interpolators._fir_verify_kernels import corner_distances as _corner_kernel
from research.interpolators._fir_verify_kernels import (charge_samples, grid_times, nearest_times, overlay_spans,
                                                        sampled_line_distances, scatter_max, thinned_runs)
from research.piecewise import NumpyPiecewise, PiecewisePolynomial, bucket_size

_GRID = 9  # grid points per corner window for the corner-error search
_CHUNK = 1 << 12  # path samples checked at once (about 0.25 MB of work arrays; results do not depend on it)
#: refinement steps of the corner-error search after its grid. Each only lowers the distance found
#: (an upper bound on the true one, never optimistic). 4 before: a 13 um block at a start, split
#: off a straight line, measured 256 um where the trajectory passes through its vertex (5 steps
#: 4.7 um, 6 steps 1.7 nm), and the false error slowed the line to 153 of 250 mm/s (2 mm/s
#: before the Gauss-Newton fallback). Swept 4 / 5 / 6 / 8 on that vertex; with 6 the 83 plans of
#: benchmarks/fir_plan_compare.py are identical but two, which are faster (-0.14 %, -1e-9).
_NEWTON_STEPS = 6
#: at most this many further Newton steps of a corner search whose distance is above the tolerance
#: it is checked against (:func:`vertex_distances`); it stops earlier once a step leaves its time
#: where it is. The 6 steps of the grid's basin left a vertex 5.5 um before an exact stop, which the
#: trajectory passes at a crawl, 0.37 um from it at tolerance 0 (``G61``; a line split there): the
#: planner stopped it, and its neighbours in turn (+27 % on that program). Swept (benchmarks/README.md,
#: "Corner search near exact stops"): 3, 6, 12 and 24 all settle the sweep's cases at no measurable
#: cost (only searches above their bound take them); 24 keeps a margin for slower approaches.
_MORE_STEPS = 24
_BATCH = 1 << 10  # samples that wait for ToolPath.distance_bound together (:func:`_scan`)
#: grid samples kept in a steady span (:func:`steady_spans`): its window averages one input piece
#: only, a line's (on the line: distance 0 up to rounding) or one sub-arc's at one feed (a smooth
#: deviation: ``_fir_blocks`` holds a sub-arc to at most ``SUB_ARC`` = pi/8 rad, so 64 samples
#: are at most pi/512 rad apart on the arc, as close as the 1 ms grid at ``F = 6.1 R`` per second
#: and closer below). Only spans longer than 64 grid steps are thinned: before this, a program at
#: ``F0.001`` (mm/min) took one sample per ms of its 10^6 s and did not finish.
STEADY_SAMPLES = 64
#: intervals between grid samples up to this many grid periods apart are bounded (``_fir_certify``):
#: consecutive grid points (1), not the strides of the thinned steady spans (2 and more), over
#: which the output is a straight uniform motion on a line or a constant distance from an arc
CERTIFY_SPAN = 1.5


def certify_settings(check_period: float, extra: float = 0.0, rel: float = BETWEEN_RTOL) -> tuple[float, float, float]:
    """The ``certify`` argument of :func:`path_deviations` and :func:`_scan` for a check sampled every
    ``check_period`` [s]: ``(span [s], extra [mm], rel)``, intervals up to :data:`CERTIFY_SPAN` grid
    periods apart bounded, each against its samples' limits plus ``extra`` and ``rel`` of their
    tolerance (``plan_fir``'s checks: no extra, :data:`_fir_certify.BETWEEN_RTOL`; the mirror's:
    its margin, 0)."""
    return CERTIFY_SPAN * check_period, extra, rel


def corner_distances(position: PiecewisePolynomial, vertices: Array, centre: Array, half_window: Array) -> Array:
    """Distance [mm] from each vertex ``(C, d)`` to the profile, searched in ``centre +- half_window`` [s].

    A grid of 9 points finds the basin; safeguarded Newton steps on ``|p(t) - V|^2`` (exact
    derivatives of the profile; a Gauss-Newton step where Newton's curvature is not positive)
    refine it. Any point of the trajectory gives an upper bound on the
    true distance, so the result is never optimistic. Shapes are padded to bucketed sizes so paths
    of similar size share one compiled function.
    """
    C = vertices.shape[0]
    if C == 0:
        return jnp.zeros(0)
    pad = bucket_size(C, 16) - C
    centre_p = jnp.concatenate([jnp.asarray(centre), jnp.zeros(pad)])
    vert_p = jnp.concatenate([jnp.asarray(vertices), jnp.zeros((pad, vertices.shape[1]))])
    return _corner_distances(position, vert_p, centre_p, jnp.asarray(half_window), jnp.arange(C + pad) < C)[:C]


@jax.jit
def _corner_distances(position, vertices, centre, half_window, real):
    offsets = jnp.linspace(-1.0, 1.0, _GRID)
    grid = centre[:, None] + half_window * offsets[None, :]  # (C, G)
    p = position(grid)
    d2 = jnp.sum((p - vertices[:, None, :]) ** 2, axis=-1)
    best = jnp.argmin(d2, axis=1)
    t = jnp.take_along_axis(grid, best[:, None], axis=1)[:, 0]
    step = half_window * (offsets[1] - offsets[0])
    lo, hi = t - step, t + step

    def newton(_, t):
        p, v, a = position.derivatives(t, 3)
        e = p - vertices
        slope = jnp.sum(e * v, axis=1)
        speed2 = jnp.sum(v * v, axis=1)
        curvature = speed2 + jnp.sum(e * a, axis=1)
        # Gauss-Newton (curvature |v|^2) where Newton's has none: a vertex passed while the motion
        # accelerates hard (e.a < -|v|^2, a grid point short of a collinear vertex at a start) kept
        # its grid point's distance, 63 um where the trajectory passes within 8 um
        gauss = jnp.where(speed2 > 0, t - slope / jnp.where(speed2 > 0, speed2, 1.0), t)
        t_new = jnp.where(curvature > 0, t - slope / jnp.where(curvature > 0, curvature, 1.0), gauss)
        return jnp.clip(t_new, lo, hi)

    t = jax.lax.fori_loop(0, _NEWTON_STEPS, newton, t)
    squared = jnp.minimum(jnp.sum((position(t) - vertices) ** 2, axis=1), jnp.min(d2, axis=1))
    positive = squared > 0
    return jnp.where(real & positive, jnp.sqrt(jnp.where(positive, squared, 1.0)), 0.0)


def vertex_distances(position: NumpyPiecewise, vertices: np.ndarray, centre: np.ndarray, half_window: float,
                     bound=None) -> np.ndarray:
    """:func:`corner_distances` on concrete arrays, compiled (``_fir_verify_kernels.corner_distances``): the
    same grid and Newton steps without JAX dispatch, for the planner's checks (the JAX form stays
    the differentiable one), and agreeing with it to rounding where a distance is within its
    ``bound`` [mm] (scalar or ``(C,)``; None: no bound, no further step). A distance above it is
    refined by up to :data:`_MORE_STEPS` further Newton steps, until one leaves its time where it
    is (the least distance met: an upper bound still)."""
    if vertices.shape[0] == 0:
        return np.zeros(0)
    C = vertices.shape[0]
    bound = np.full(C, np.inf) if bound is None else np.ascontiguousarray(np.broadcast_to(bound, (C,)), dtype=np.float64)
    return _corner_kernel(np.ascontiguousarray(position.breaks), np.ascontiguousarray(position.coeffs),
                          np.ascontiguousarray(vertices, dtype=np.float64), np.ascontiguousarray(centre, dtype=np.float64),
                          float(half_window), _GRID, _NEWTON_STEPS, bound, _MORE_STEPS)


def nearest_instants(position: NumpyPiecewise, vertices: np.ndarray, centre: np.ndarray,
                     half_window: float) -> np.ndarray:
    """``(C,)`` time [s] of the profile's point nearest each vertex ``(C, d)`` within ``centre +-
    half_window`` [s]: the grid and Newton steps of :func:`vertex_distances` (compiled,
    ``_fir_verify_kernels.nearest_times``), returning where the search settles instead of how far
    it is."""
    if vertices.shape[0] == 0:
        return np.zeros(0)
    return nearest_times(np.ascontiguousarray(position.breaks), np.ascontiguousarray(position.coeffs),
                         np.ascontiguousarray(vertices, dtype=np.float64), np.ascontiguousarray(centre, dtype=np.float64),
                         float(half_window), _GRID, _NEWTON_STEPS)


def profile_rounding(position: NumpyPiecewise, end: np.ndarray) -> float:
    """The rounding [mm] a profile has accumulated by its end: the distance from its last value
    (the machine at rest) to the point ``end`` ``(d,)`` where its input ends, which the exact
    profile reaches exactly.

    The profile is built piece by piece in absolute time (each filter merges the breaks ``b`` and
    ``b + T_i`` and re-centres its pieces there), so its rounding grows with the time it spans:
    measured on bench_adaptive's programs, 0.6 nm after 427 s and 10 nm after 1,696 s (as the time
    squared), far above the 1 pm of ``VERIFY_ATOL``. A check that held such a profile to the
    tolerance up to 1 pm would repair rounding: the arcs whose eq 8 feed puts their deviation at
    the tolerance exactly, and the vertices repaired to it, were slowed (by 2 % and more) from
    about 530 s into a program on, more of them the longer it ran. The planner's checks add this
    measured rounding to ``verified_bound`` (10 nm against a tolerance of tens of um)."""
    return float(np.linalg.norm(position.coeffs[-1, 0] - end))


def stop_rounding(errors: np.ndarray, stops: np.ndarray) -> float:
    """The rounding [mm] a profile shows at its exact stops: the largest vertex error ``errors``
    ``(M - 1,)`` [mm] where ``stops`` ``(M - 1,)`` (overlap 0; 0 if none).

    At an exact stop the input rests for ``T_d`` after its block (``T_k = 0``), so the exact
    profile is at the vertex when the window has passed: whatever distance the check finds there
    is the profile's rounding at that instant (as :func:`profile_rounding` at the end, where it
    rests at the path's end). The rounding grows with the time a profile spans and is not smallest
    at its end: measured on a 300-block raster of 1 m lines at 50 mm/s (tolerance 0, every corner
    an exact stop, 3,000 s), 1e-9 to 1e-8 mm at the stops against less at the end, which left 48
    exact stops "violating" a tolerance they cannot be repaired towards (``ConvergenceError``)."""
    return float(np.max(errors[stops], initial=0.0))


def charged_repairs(j: int, deviation: float, stops: np.ndarray, centre: np.ndarray, tol_vertex: np.ndarray,
                    tol_block: np.ndarray, is_arc: np.ndarray, Td: float):
    """Where a path deviation charged to vertex ``j`` (:func:`path_deviations`) is repaired:
    ``(vertices, arcs)``, lists of ``(index, deviation)`` for the planner's vertex and arc repairs,
    each deviation scaled to that corner's or arc's own tolerance (the same violated ratio).

    ``[(j, deviation)], []`` unless ``j`` is an exact stop (``stops`` ``(M - 1,)``). An exact stop's
    profile passes through its vertex and no repair of the vertex changes the profile near it any
    more, so the deviation comes from motion next to it: the neighbours ``j - 1``, ``j + 1`` that
    are not exact stops and whose corner instants ``centre`` [s] lie within ``T_d`` of its own
    (their windows overlap its own) take it; if there are none, the arc blocks of the stop
    (``j``, ``j + 1`` where ``is_arc``), whose radial deviation falls with their feed (eq 8); if
    there are none either, ``j`` keeps it. Measured without this: lines of tolerances 1 / 1 /
    1e-4 mm with a 0.02 mm middle block, whose 1e-4 mm vertex stopped while the blend of the 1 mm
    corner before it stayed 14 um from the path within half a window of the stop, and a quarter
    arc of 0.01 mm between lines of 1e-4 mm, both corners stopped with the arc's start 3 um off
    within half a window of them: ``ConvergenceError`` after 36 rounds, each.

    Args:
        tol_vertex: ``(M - 1,)``, tol_block: ``(M,)`` tolerances [mm]; is_arc: ``(M,)``; Td: [s].
    """
    if not stops[j]:
        return [(j, deviation)], []

    def scaled(tol):
        return deviation * tol / tol_vertex[j] if tol_vertex[j] > 0 else deviation

    near = [(i, scaled(tol_vertex[i])) for i in (j - 1, j + 1)
            if 0 <= i < stops.size and not stops[i] and abs(centre[i] - centre[j]) <= Td]
    if near:
        return near, []
    arcs = [(k, scaled(tol_block[k])) for k in (j, j + 1) if is_arc[k]]
    return ([], arcs) if arcs else ([(j, deviation)], [])


def path_deviations(position: NumpyPiecewise, path: ToolPath, starts: np.ndarray, centre: np.ndarray, Td: float,
                    tol_block: np.ndarray, check_period: float, durations=None, slack: float = 0.0, stopped=None,
                    stride_cap=None, spans=None, keys_only: bool = False, certify=None):
    """Largest sampled distance from the trajectory to ``path`` and where it breaks the tolerance.

    Args:
        position: the exact profile (NumPy evaluator); path: the programmed path.
        starts: ``(M,)`` pulse start of each block [s]; centre: ``(M - 1,)`` corner instants [s].
        Td: total filter delay [s]; tol_block: ``(M,)`` tolerance per block [mm].
        check_period: sample spacing [s].
        durations: ``(P,)`` lengths [s] of the input pieces (gaps included) from ``starts[0]``,
            to thin the grid over steady spans (:func:`steady_spans`); None: the full grid.
        slack: rounding [mm] allowed above ``verified_bound`` of each tolerance
            (:func:`profile_rounding`).
        stopped: ``(M - 1,)`` the corners that are exact stops (``T_k = 0``: no blend; a sample by
            one is charged to its block on that side, as ``RoundChecks`` does), or None: none.
        stride_cap: ``(P,)`` the largest stride of the thinned grid over each input piece's
            steady span (:func:`steady_spans`' ``cap``), or None: none.
        spans: ``(first, last, stride)`` grid-index spans (sorted, disjoint) thinned elsewhere
            than over the steady spans, which take precedence where the two meet (the mirror's
            local strides, ``_fir_mirror_check.local_strides``), or None: none.
        keys_only: only which vertices and blocks break the tolerance is wanted: where some do,
            their values and the largest distance are lower bounds (:func:`_bound_waiting`);
            where none does, the result is the same.
        certify: ``(span [s], extra [mm], rel)``: the intervals between grid samples bounded as
            well (:func:`_scan`, ``_fir_certify``), or None: the samples only.

    Returns:
        ``(max_deviation [mm], {vertex: deviation}, {block: deviation})``; distances are upper
        bounds (:meth:`ToolPath.distance_bound`), equal to the distance on all but crowded paths.
        Violations within
        ``T_d / 2`` of a corner instant are charged to that corner, others to the block whose input
        the window is centred on (the inside of an arc); each charged value is the largest
        violating distance scaled to the vertex's or block's own tolerance (:func:`_bound_waiting`:
        the plain distance wherever the tolerances are equal).
    """
    t0, t1 = float(position.breaks[0]), float(position.breaks[-1])
    n = int(np.ceil((t1 - t0) / check_period)) + 1
    M = path.n_blocks
    worst, bad = np.full(2 * M - 1, -np.inf), np.full(2 * M - 1, -np.inf)
    steady = None if durations is None else steady_spans(starts, durations, t0, Td, check_period, cap=stride_cap)
    if spans is not None:
        none = np.zeros(0, np.int64)
        steady = overlay_spans(*(steady if steady is not None else (none, none, none)), *spans)
    _, times = _sample_times(np.zeros(1, np.int64), np.array([n - 1]), t0, t1, check_period, centre, steady)
    deviation = _scan(position, path, times, starts, centre, Td, tol_block, worst, bad, None, slack, stopped, keys_only,
                      certify)
    at_vertex = {int(v): float(bad[v]) for v in np.flatnonzero(bad[: M - 1] > -np.inf)}
    at_block = {int(b): float(bad[M - 1 + b]) for b in np.flatnonzero(bad[M - 1:] > -np.inf)}
    return deviation, at_vertex, at_block


def steady_spans(starts: np.ndarray, durations: np.ndarray, t0: float, Td: float, period: float,
                 joined: np.ndarray | None = None, cap: np.ndarray | None = None):
    """The stretches of the sample grid ``t0 + i period`` where a check learns nothing new per
    sample: grid-index spans ``(first, last, stride)`` (sorted, disjoint) over which only every
    ``stride``-th index is sampled.

    The output at ``t`` averages the input over ``[t - T_d, t]`` (nonnegative weights). The input
    pieces follow one another from ``starts[0]`` (motion pieces and dwell gaps, ``durations``
    ``(P,)`` [s]), so between two input breaks ``b_k < b_k+1`` every output time in ``[b_k + T_d,
    b_k+1]`` averages a single piece: a line's points (the output lies on the line), a gap's (the
    vertex) or one sub-arc's at one feed (a smooth deviation from the arc). Those spans, less one
    period at each end for rounding, that hold more than :data:`STEADY_SAMPLES` grid points are
    thinned to about that many (``stride = ceil(n / STEADY_SAMPLES)``); the grid next to them stays
    dense, so every window that meets a break is sampled at the full rate. ``joined``: indices of
    pieces that go on with the polynomial of the piece before them at its feed (a cut sub-arc's
    pieces, ``PulseTable.joins``): the two are one input piece, and the break between them is none.
    ``cap``: ``(P,)`` the largest stride over each piece's span (at least 1), or None: none (with
    ``joined`` None: the mirror's paths of lines, ``_fir_mirror_check.violations``)."""
    breaks = float(starts[0]) + np.concatenate([[0.0], np.cumsum(durations)])
    if joined is not None and joined.size:
        if cap is not None:
            raise ValueError("steady_spans: cap is per input piece, without joined pieces")
        breaks = np.delete(breaks, joined)
    first = np.ceil((breaks[:-1] + Td + period - t0) / period)
    last = np.floor((breaks[1:] - period - t0) / period)
    n = last - first + 1
    keep = n > STEADY_SAMPLES
    stride = np.ceil(n[keep] / STEADY_SAMPLES)
    if cap is not None:
        stride = np.maximum(np.minimum(stride, cap[keep]), 1.0)
    return first[keep].astype(np.int64), last[keep].astype(np.int64), stride.astype(np.int64)


def _sample_times(first: np.ndarray, last: np.ndarray, t0: float, t1: float, period: float, extra: np.ndarray,
                  steady=None):
    """The check's sample times in chunks of at most :data:`_CHUNK` (bounded memory, never the
    whole list at once), each with a flag: True for the grid (in time order), False for the rest:
    the grid points ``t0 + i period`` for ``i`` in ``first[r] .. last[r]`` of
    each run ``r`` (sorted, disjoint), thinned over the ``steady`` spans (:func:`steady_spans`;
    None: none), then the times ``extra`` and ``t1``, all clipped to ``[t0, t1]``. Returns the
    number of samples and their chunks; the values are those of the full list, whatever the
    chunking."""
    if steady is None:
        first, count, stride = first, np.maximum(last - first + 1, 0), np.ones(first.size, np.int64)
    else:
        first, count, stride = thinned_runs(first, last, *steady)
    ends = np.cumsum(count)  # sample index after each run
    n_grid = int(ends[-1]) if ends.size else 0
    tail = np.append(extra, t1)

    def chunks():
        for i in range(0, n_grid, _CHUNK):
            yield grid_times(i, min(i + _CHUNK, n_grid), first, count, stride, ends, t0, t1, period), True  # compiled
        for i in range(0, tail.size, _CHUNK):
            yield np.clip(tail[i: i + _CHUNK], t0, t1), False

    return n_grid + tail.size, chunks()


def _scan(position, path, times, starts, centre, Td, tol_block, worst, bad, redo, slack: float = 0.0,
          stopped=None, keys_only: bool = False, certify=None) -> float:
    """Check the sample chunks ``times`` (an iterable of ``(time array, on the grid)``,
    :func:`_sample_times`): the largest distance of each charge key into ``worst`` and of its
    violations into ``bad`` (keys where ``redo``, all if None). Returns the largest distance over
    all samples.

    ``certify``: ``(span [s], extra [mm], rel)``, or None: the intervals between consecutive grid
    samples up to ``span`` apart are bounded too (``_fir_certify``: what hides between samples),
    each against its samples' limits plus ``extra`` and ``rel`` of their tolerance, and sampled
    more densely where the bound is above that (those samples charged as any other).

    The samples outside tolerance of their three blocks (:func:`_charged_samples`) wait in a batch
    of about :data:`_BATCH` for :meth:`ToolPath.distance_bound` (a fixed cost per call that would
    otherwise come with every chunk); each sample's distance is its own, so the batching changes
    no value, and the maxima are the same in any order. ``keys_only``: :func:`_bound_waiting`'s."""
    arrays = _ScanArrays(position, path, starts, centre, tol_block, redo, slack, stopped)
    deviation = -np.inf
    waiting: list[tuple[np.ndarray, ...]] = []
    n_waiting = 0
    def check(t):
        """Charge the samples at ``t``; returns their fields for the certifier."""
        nonlocal deviation, waiting, n_waiting
        near_max, wait, fields = _charged_samples(arrays, path, t, Td, worst)
        deviation = max(deviation, near_max)
        if wait is not None:
            waiting.append(wait)
            n_waiting += wait[0].shape[0]
        if n_waiting >= _BATCH:
            deviation = max(deviation, _bound_waiting(path, waiting, worst, bad, arrays.slack, arrays.key_tol, keys_only))
            waiting, n_waiting = [], 0
        if certifier is None:
            return None
        q, block, d2, lim, key = fields
        kept = key >= 0 if arrays.redo.size == 0 else arrays.redo[np.maximum(key, 0)] & (key >= 0)
        return t, q, block, d2, lim, kept

    certifier = None
    if certify is not None:
        span, extra, rel = certify
        certifier = Certifier(position, PathFeatures(path, arrays.segments), check, span, extra + arrays.slack, rel)
    for t, grid in times:
        fields = check(t)
        if grid and fields is not None:
            certifier.add(fields)
    if certifier is not None:
        certifier.close()
        certifier.evaluate = None  # it and ``check`` refer to each other: freed now, not by the cycle collector
    if waiting:
        deviation = max(deviation, _bound_waiting(path, waiting, worst, bad, arrays.slack, arrays.key_tol, keys_only))
    return deviation


class _ScanArrays:
    """The arrays of one path check, made contiguous once for all its chunks: the profile's
    breaks and coefficients, the block starts and corner instants [s], the tolerances [mm], the
    path's arc flags and line segments (:func:`_line_segments`), and ``redo`` (empty: every key)."""

    __slots__ = ("breaks", "coeffs", "starts", "centre", "tol", "key_tol", "is_arc", "has_arc", "segments", "redo",
                 "slack", "stopped")

    def __init__(self, position: NumpyPiecewise, path: ToolPath, starts, centre, tol_block, redo, slack=0.0,
                 stopped=None):
        self.breaks, self.coeffs = np.ascontiguousarray(position.breaks), np.ascontiguousarray(position.coeffs)
        self.starts = np.ascontiguousarray(starts)
        self.centre = np.ascontiguousarray(centre, dtype=np.float64)
        self.tol = np.ascontiguousarray(tol_block, dtype=np.float64)
        # the tolerance each charge key is repaired against: a vertex's (the smaller of its two
        # blocks'), an arc block's own (:func:`_bound_waiting`)
        self.key_tol = np.concatenate([np.minimum(self.tol[:-1], self.tol[1:]), self.tol])
        self.is_arc = np.ascontiguousarray(path.is_arc)
        self.has_arc = bool(self.is_arc.any())
        self.segments = _line_segments(path)
        self.redo = np.zeros(0, bool) if redo is None else np.ascontiguousarray(redo)
        self.slack = float(slack)
        self.stopped = np.zeros(0, bool) if stopped is None else np.ascontiguousarray(stopped, dtype=bool)


def _bound_waiting(path: ToolPath, waiting, worst, bad, slack: float, key_tol: np.ndarray, keys_only: bool = False) -> float:
    """The distances of the waiting samples (``(q, block, dist, limit, key, keep)`` rows of
    :func:`_charged_samples`) to the path by :meth:`ToolPath.distance_bound` (the smaller of it and
    the three-block distance), into ``worst`` and ``bad``; returns their largest.

    A violation goes into ``bad`` scaled to its key's tolerance ``key_tol[key]`` (``_ScanArrays``):
    ``dist * key_tol / limit``, so that ``key_tol / value`` is the ratio ``limit / dist`` of the
    tolerance the sample broke, which the planner's repairs read against the key's tolerance. A
    sample near a corner takes the smaller of its block's and the vertex's tolerance; where a short
    block lets a window centred on a tighter neighbour reach the corner, the sample's limit is below
    the vertex's, and its plain distance over the vertex's tolerance gave a ratio above 1 (a
    "repair" that sped the window up; measured on three lines of tolerances 0.1 / 50 / 50 um at
    F 50 mm/s: planned feeds of 816 mm/s). Equal where the two tolerances are equal (all of a
    program with one tolerance); 1 where the sample's limit or the key's tolerance is 0.

    ``keys_only``: only which keys break the tolerance is wanted (the mirror's search). A key shown
    broken, in ``bad`` already or by its sample of largest three-block distance (bounded first),
    has its other samples dropped unbounded; the values of such keys, and the largest distance
    where any key breaks, are then lower bounds. Where none breaks, every sample is bounded and
    the values are the same as without it."""
    q, block, dist, limit, key, keep = (np.concatenate(parts) for parts in zip(*waiting))
    todo = np.ones(dist.size, dtype=bool)
    if keys_only:
        broken = bad > -np.inf  # keys shown broken by an earlier batch
        counted = ~broken[key]
        cand = np.flatnonzero(keep & counted)
        if cand.size:  # each key's sample of largest three-block distance, bounded first
            order = cand[np.lexsort((-dist[cand], key[cand]))]
            head = order[np.r_[True, key[order][1:] != key[order][:-1]]]
            dist[head] = np.minimum(dist[head], path.distance_bound(q[head], near=block[head]))
            todo[head] = False
            broken[key[head][dist[head] > verified_bound(limit[head]) + slack]] = True
            counted[broken[key]] = False
            counted[head] = True
        todo &= counted
        keep &= counted
        dist = np.where(counted, dist, -np.inf)  # dropped samples count nowhere
    rest = np.flatnonzero(todo)
    if rest.size:
        dist[rest] = np.minimum(dist[rest], path.distance_bound(q[rest], near=block[rest]))
    scatter_max(worst, key[keep], dist[keep])
    keep &= dist > verified_bound(limit) + slack
    k, lim = key[keep], limit[keep]
    own = key_tol[k]
    scale = np.where((lim > 0) & (own > 0) & (lim != own), own / np.where(lim > 0, lim, 1.0), 1.0)
    scatter_max(bad, k, dist[keep] * scale)
    return float(dist.max())


def _charged_samples(arrays: _ScanArrays, path: ToolPath, t: np.ndarray, Td: float, worst: np.ndarray):
    """One chunk of a path check at sample times ``t``: the distance [mm] from the trajectory to
    the three blocks around the one its window is centred on (:func:`_three_block_distance`), each
    sample charged to a key (vertex ``j < M - 1``, or ``M - 1 + block``: see
    :func:`path_deviations`) and, unless it breaks its tolerance, into ``worst`` where kept
    (``_fir_verify_kernels.charge_samples``). Returns ``(largest distance of the samples within
    tolerance, rows (q, block, dist, limit, key, keep) of those that break it (the nearest path
    samples are to be tried for those as well, :func:`_scan`; None if none), (q, block, d2,
    tolerance, key) of every sample)``: ``d2`` ``(N, 3)`` as :func:`_three_block_distance`."""
    q, block, d2 = _three_block_distance(arrays, path, t, Td)
    near_max, over, dist, limit, key, keep, s_limit, s_key = charge_samples(
        t, d2, block, arrays.centre, arrays.tol, arrays.is_arc, 0.5 * Td, arrays.redo, worst, arrays.slack, arrays.stopped)
    rows = (q[over], block[over], dist, limit, key, keep) if over.size else None
    return near_max, rows, (q, block, d2, s_limit, s_key)


class RoundChecks:
    """The checks of ``plan_fir``'s verification rounds on one path, redone only where the profile
    changed since the last check.

    A repair changes the input pulses of some blocks (feeds, overlaps); the filtered output changes
    over ``[start of the change, its end + T_d]`` (the window averages the last ``T_d`` of input),
    and everything later is the old output shifted in time. So a vertex error is recomputed when its
    search window ``centre +- T_d / 2`` meets a changed span, and the path samples of a charge key
    (vertex or arc block, :func:`path_deviations`) when the times it collects samples from meet
    one: ``[min(start_j + T_d / 2, centre_j - T_d / 2), centre_j + T_d / 2]`` for vertex ``j``
    (samples near its corner instant, and those on the line before it), ``[start_b + T_d / 2,
    start_b+1 + T_d / 2]`` for block ``b``. Those keys are sampled afresh on the same grid as a full
    check (``t0 + i check_period``, the corner instants, the end); the others keep their last
    values, which the new profile reproduces up to the time shift. The first check is the full one,
    unless the check starts from another candidate's (:meth:`adopt`): the candidates of one plan
    share the pulse table and differ in a few dwells and feeds, so a candidate after the first is
    checked like a next round of the one checked last (measured: an 8,112-block adaptive-clearing
    program, whose branch and bound checks 8 candidates, 7.2 -> 2.0 million path samples).

    Args:
        path: the programmed path; tol_block: ``(M,)`` tolerance per block [mm];
        piece_block: ``(P,)`` block of each input piece (``PulseTable.block``); Td: total delay [s];
        check_period: sample spacing [s]; fraction, joins: ``(P,)`` the table's piece shares and
        ``PulseTable.joins`` (None: no piece goes on with the one before it), whose pieces at
        their predecessor's feed the sample grid's thinning takes as one (:func:`steady_spans`).
    """

    def __init__(self, path: ToolPath, tol_block: np.ndarray, piece_block: np.ndarray, Td: float, check_period: float,
                 fraction: np.ndarray | None = None, joins: np.ndarray | None = None):
        self.path, self.tol, self.Td, self.period = path, tol_block, Td, check_period
        self.certify = certify_settings(check_period)  # the intervals between grid samples
        self.piece_block = piece_block  # padding pieces (block M_pad) count as the last block's
        self.joins = None if joins is None else np.flatnonzero(joins)
        self.fraction = fraction
        self.durations, self.samples, self._pending = None, 0, None
        self.slack = 0.0  # [mm] added to the tolerance of the path samples: the profile's rounding
        self.stops = None  # (M - 1,) exact stops of the profile checked (charge_samples), None: none
        self.certified = None  # (2 M - 1,) charge keys whose values came from a check bounded between its samples

    def __call__(self, position: NumpyPiecewise, starts: np.ndarray, centre: np.ndarray, durations: np.ndarray,
                 vertex_errors: bool):
        """Checks of the plan whose input pieces last ``durations`` ``(P,)`` [s] (gaps included;
        kept until the next call, which compares against it: not to be changed in place):
        :meth:`vertices` then :meth:`samples_check`.

        Returns:
            ``(vertex errors (M - 1,), max deviation, {vertex: deviation}, {block: deviation})`` as
            :func:`vertex_distances` (zeros unless ``vertex_errors``) and :func:`path_deviations`.
        """
        errors = self.vertices(position, starts, centre, durations, vertex_errors)
        return (errors,) + self.samples_check()

    def vertices(self, position: NumpyPiecewise, starts: np.ndarray, centre: np.ndarray, durations: np.ndarray,
                 vertex_errors: bool) -> np.ndarray:
        """First half of a check: the vertex errors ``(M - 1,)`` [mm] (zeros unless
        ``vertex_errors``), recomputed where the profile changed; it also marks the charge keys
        whose path samples :meth:`samples_check` (the second half, on the same profile) redoes.
        The planner looks at the vertex errors first: their repairs alone can already rule a
        candidate out, and the path samples cost more."""
        path, M, half = self.path, self.path.n_blocks, 0.5 * self.Td
        self._pending = (position, starts, centre, durations)
        if M == 1:
            return np.zeros(0)
        lo_v, hi_v, lo_b, hi_b = self._spans(position, starts, centre)
        if self.durations is None:
            err_v, redo_v, redo_b = np.ones(M - 1, bool), np.ones(M - 1, bool), np.ones(M, bool)
            self.errors, self.worst = np.zeros(M - 1), np.full(2 * M - 1, -np.inf)
            self.bad = (np.zeros(0, np.int64), np.zeros(0))
            self.certified = np.zeros(2 * M - 1, bool)
        else:
            changed = np.unique(np.minimum(self.piece_block[durations != self.durations], M - 1))
            r_lo, r_hi = starts[changed], np.append(starts, np.inf)[changed + 1] + self.Td
            r_lo, r_hi = _merged(r_lo, r_hi)
            err_v = _meets(centre - half, hi_v, r_lo, r_hi)
            redo_v = _meets(lo_v, hi_v, r_lo, r_hi)
            redo_b = _meets(lo_b, hi_b, r_lo, r_hi)
        self.durations = durations  # kept, not copied: the planner builds a new array every round
        if vertex_errors and err_v.any():
            tol_v = np.minimum(self.tol[: M - 1], self.tol[1:M])[err_v]
            self.errors[err_v] = vertex_distances(position, path.vertices[err_v], centre[err_v], half,
                                                  verified_bound(tol_v) + self.slack)
        self._pending = (position, starts, centre, redo_v, redo_b)
        return self.errors.copy() if vertex_errors else np.zeros(M - 1)

    def _spans(self, position: NumpyPiecewise, starts: np.ndarray, centre: np.ndarray):
        """``(lo_v, hi_v, lo_b, hi_b)``: the times each vertex ``(M - 1,)`` and block ``(M,)``
        charge key collects samples from (class docstring), clipped to the profile."""
        half = 0.5 * self.Td
        t0, t1 = float(position.breaks[0]), float(position.breaks[-1])
        lo_v = np.minimum(starts[:-1] + half, centre - half)
        hi_v = centre + half
        lo_v[0], hi_v[-1] = t0, t1
        return lo_v, hi_v, starts + half, np.append(starts[1:] + half, t1)

    def snapshot(self):
        """The state a later check compares against (copies): another candidate of the same plan
        (same pulse table) can :meth:`adopt` it and check afresh only where its input differs."""
        if self.durations is None or self._pending is not None:
            return None
        return (self.durations, self.errors.copy(), self.worst.copy(), (self.bad[0].copy(), self.bad[1].copy()),
                self.certified.copy())

    def adopt(self, snap) -> None:
        """Start from ``snap`` (:meth:`snapshot` of another candidate's last complete check)."""
        if snap is not None:
            self.durations, errors, worst, bad, certified = snap
            self.errors, self.worst, self.bad = errors.copy(), worst.copy(), (bad[0].copy(), bad[1].copy())
            self.certified = certified.copy()

    def swap_profile(self, position, starts=None, centre=None) -> None:
        """Hand the check pending between :meth:`vertices` and :meth:`samples_check` another
        profile: ``None`` to release it (with its block starts and corner instants) while the
        planner suspends the candidate, the same profile rebuilt (identical arrays) with its
        ``starts`` and ``centre`` to resume it."""
        self._pending = (position, starts, centre) + self._pending[3:]

    def _joined(self):
        """The pieces of :attr:`joins` whose feed is their predecessor's (pulse lengths
        ``durations / fraction`` equal to 1e-14: the same feed up to the division's rounding)."""
        j = self.joins
        if j is None or not j.size:
            return None
        tv = self.durations[j] / self.fraction[j]
        return j[np.abs(tv - self.durations[j - 1] / self.fraction[j - 1]) <= 1e-14 * tv]

    def samples_check(self, certify: bool = True):
        """Second half of a check (after :meth:`vertices`, on its profile): the path samples of
        the charge keys it marked. Returns ``(max deviation, {vertex: deviation}, {block:
        deviation})`` as :func:`path_deviations`.

        ``certify``: bound the intervals between the samples as well (``_fir_certify``; with it,
        also every key whose values came from a check without it). ``plan_fir`` leaves it out in a
        round that cannot return its plan (a vertex error or an axis limit already broken: the
        round repairs and checks again), where bounding the whole path's intervals cost three to
        four times its samples; the plan it returns comes from a round in which every key was
        certified."""
        path, M = self.path, self.path.n_blocks
        if M == 1:
            position, starts, centre, durations = self._pending
            return path_deviations(position, path, starts, centre, self.Td, self.tol, self.period, durations,
                                   certify=self.certify)
        position, starts, centre, redo_v, redo_b = self._pending
        self._pending = None
        t0, t1 = float(position.breaks[0]), float(position.breaks[-1])
        lo_v, hi_v, lo_b, hi_b = self._spans(position, starts, centre)
        redo = np.concatenate([redo_v, redo_b])
        if certify:
            redo |= ~self.certified
            redo_v, redo_b = redo[: M - 1], redo[M - 1:]
        self.certified[redo] = certify
        self.samples = 0  # path samples taken by this check
        if redo.any():
            s_lo, s_hi = _merged(np.concatenate([lo_v[redo_v], lo_b[redo_b]]), np.concatenate([hi_v[redo_v], hi_b[redo_b]]))
            first = np.maximum(np.ceil((s_lo - t0) / self.period), 0).astype(np.int64)
            n = int(np.ceil((t1 - t0) / self.period)) + 1
            last = np.minimum(np.floor((s_hi - t0) / self.period).astype(np.int64), n - 1)
            extra = centre[redo_v[: M - 1]]
            steady = steady_spans(starts, self.durations, t0, self.Td, self.period, self._joined())
            self.samples, times = _sample_times(first, last, t0, t1, self.period, extra, steady)
            bad = np.full(2 * M - 1, -np.inf)  # dense while checking, its few entries kept between checks
            bad[self.bad[0]] = self.bad[1]
            self.worst[redo], bad[redo] = -np.inf, -np.inf
            _scan(position, path, times, starts, centre, self.Td, self.tol, self.worst, bad, redo, self.slack,
                  self.stops, certify=self.certify if certify else None)
            keys = np.flatnonzero(bad > -np.inf)
            self.bad = (keys, bad[keys])
        keys, values = self.bad
        at_vertex = {int(k): float(e) for k, e in zip(keys, values) if k < M - 1}
        at_block = {int(k) - (M - 1): float(e) for k, e in zip(keys, values) if k >= M - 1}
        return float(self.worst.max()), at_vertex, at_block


def _merged(lo: np.ndarray, hi: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The union of the intervals ``[lo_i, hi_i]`` as sorted, disjoint intervals."""
    order = np.argsort(lo, kind="stable")
    lo, hi = lo[order], np.maximum.accumulate(hi[order])
    start = np.concatenate([[True], lo[1:] > hi[:-1]]) if lo.size else np.zeros(0, bool)
    ends = np.append(np.flatnonzero(start)[1:] - 1, lo.size - 1) if lo.size else np.zeros(0, np.int64)
    return lo[start], hi[ends]


def _meets(lo: np.ndarray, hi: np.ndarray, r_lo: np.ndarray, r_hi: np.ndarray) -> np.ndarray:
    """Whether each interval ``[lo, hi]`` meets one of the sorted disjoint intervals ``[r_lo, r_hi]``."""
    i = np.searchsorted(r_hi, lo, side="left")  # the first that ends at or after lo
    return (i < r_lo.size) & (r_lo[np.minimum(i, max(r_lo.size - 1, 0))] <= hi) if r_lo.size else np.zeros(lo.size, bool)


def _line_segments(path: ToolPath):
    """``(start (M, d), end - start (M, d), 1 / |end - start|^2 (M,))`` of every block as a segment
    (0 for a zero-length one), kept in the path's cache."""
    if "line_segments" not in path._cache:
        ab = np.ascontiguousarray(path.ends - path.starts)
        ab2 = np.einsum("kd,kd->k", ab, ab)
        inv = np.where(ab2 > 0, 1.0 / np.where(ab2 > 0, ab2, 1.0), 0.0)
        path._cache["line_segments"] = (np.ascontiguousarray(path.starts, dtype=np.float64), ab, inv)
    return path._cache["line_segments"]


def _three_block_distance(arrays: _ScanArrays, path: ToolPath, t: np.ndarray, Td: float):
    """Trajectory samples at ``t``, the block each one's window is centred on, and the squared
    distances [mm^2] from each sample to blocks ``block - 1 .. block + 1`` (clipped to the path).

    Lines by one compiled pass (``_fir_verify_kernels.sampled_line_distances``); arc candidates through
    ``ToolPath.arc_distance`` (exact for planar arcs). Returns ``(q (N, d), block (N,), d2 (N, 3))``."""
    M = path.n_blocks
    q, block, d2 = sampled_line_distances(arrays.breaks, arrays.coeffs, t, arrays.starts, 0.5 * Td, *arrays.segments)
    if arrays.has_arc:
        nb = np.clip(block[:, None] + np.arange(-1, 2)[None, :], 0, M - 1)
        arc = arrays.is_arc[nb]
        if arc.any():
            rows = np.nonzero(arc)
            d2[rows] = path.arc_distance(q[rows[0]], nb[rows]) ** 2
    return q, block, d2
