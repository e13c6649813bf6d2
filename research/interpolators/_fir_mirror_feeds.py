"""Block feeds of the mirror search (``_fir_mirror``): the caps its timing starts from and the
factors its rounds lower and raise them by.

Once the mirror has moved the filters' input, the output runs on the programmed path at the
planned timing, so what bounds its feed is what bounds any motion along that path: the per-axis
limits on the path's curvature, as in a time-optimal plan (Sencer 2009 ch 3: ``v^2 kappa <= A``
and, on steady circular motion, ``v^3 kappa^2 <= J``). :func:`curvature_caps` starts every block
there. Where the moved input still breaks a limit (feed steps, the start and stop pulses, the
chords' discrete turns), :func:`limit_factors` lowers the feeds of the blocks whose input makes the
profile at that instant; the search lowers the blocks around a tolerance violation by
:data:`TOLERANCE_STEP`. :func:`shrink_caps` caps the eq 13/14 timing where the filters' shrink of
the curve exceeds the relaxed tolerance (eq 8). Lowering by steps overshoots: a block lowered for
a peak that its neighbours' lowering then removed stays low. Once a plan verifies,
:func:`raise_factors` lifts every block whose output span keeps below the limits
(:func:`span_ratios`) by its headroom, the same exponent as the lowering, at most a step that
starts at :data:`RAISE_STEP`.

Constants (swept with ``benchmarks/fir_mirror.py --sweep-feeds`` on the first 100 and 300 chords
of bench_cam's CAM file, its quick file and its part 4 micro-chord program rounded to 0.1 and 2.54
um, limits = the envelope; benchmarks/README.md):

* :data:`LIMIT_EXPONENT`: a block at ``peak / limit = r`` takes ``r^-LIMIT_EXPONENT``; a jerk
  that grows as ``F^3`` would need ``1/3``, a pulse edge's as ``F`` a full ``1``; 1/4 lowers less
  than either, since the instant's peak is shared by several blocks that are all lowered.
* :data:`LIMIT_REACH`: the blocks lowered lie within this share of the shortest delay of each
  instant (:func:`limit_factors`); 0 lowers single 16 um chords of the micro-chord program among
  their neighbours, whose speed steps are jerk of their own.
* :data:`LEAST_STEP`: at least this much, so that a peak a hair above its limit does not take many
  rounds.
* :data:`TOLERANCE_STEP`: the step of the feeds around a tolerance violation.
* :data:`RAISE_STEP`: the largest raise of a block in one round (:func:`raise_factors`), halved
  for the blocks a raise broke something with (``_fir_mirror``, step 4). Swept (``fir_mirror.py
  --sweep-raise``: the first 100, 300 and 1,000 chords, the quick file at eps 10-200 um, the
  micro-chord program at 0.1 and 2.54 um) 0.01 / 0.03 / 0.05 / 0.1 / 0.2: sums 105.07 / 104.95 /
  104.91 / 104.89 / 104.81 s (no raise: 105.92 s); on the 10^4-chord file 0.03 is fastest
  (44.7339 s against 44.8583 / 44.8880 s at 0.1 / 0.2), and that is the file the issue measures.
"""

from __future__ import annotations

import math

import numpy as np

from research.interpolators._fir_piece_peaks import range_max
from research.interpolators._fir_profile import _subsets
from research.limits import AxisLimits
from research.paths.toolpath import ToolPath

LIMIT_EXPONENT = 0.25
LIMIT_REACH = 0.05
LEAST_STEP = 0.01
TOLERANCE_STEP = 0.03
RAISE_STEP = 0.03


def vertex_curvature(tp: ToolPath, feed: np.ndarray, corners: np.ndarray, delays: np.ndarray) -> np.ndarray:
    """``(M - 1, d)`` curvature [1/mm, per axis] of the path at each vertex, over the stretch the
    filters average there.

    The tangent steps ``t_in - t_out`` of the vertices around it, weighted by a triangle of
    half-width ``b = sqrt(6) F sigma`` along the path and summed as vectors, over ``b`` (the
    triangle's area). ``F`` is the larger commanded feed of the vertex's two blocks (``feed``
    ``(M,)`` [mm/s]) and ``sigma = sqrt(sum T_i^2 / 12)`` the kernel's rms half-width in time
    (``delays`` [s]), so the triangle spreads as far as the kernel does along the path (rms ``F
    sigma``; ``_fir_lookahead``'s window reach). On a regular polygon of radius ``R`` that is
    ``1 / R`` to second order in ``b / R``; the turns of chords rounded to a grid alternate and
    cancel, instead of each reading as a tight curve, and the triangle's weights fade at its edges,
    where a box would count one turn of a pair only. The ``corners`` ``(M - 1,)`` (vertices where
    eq 13/14 dwells: a corner, not a curve, whose error the dwell holds) add no turn.
    """
    if tp.n_blocks < 2:
        return np.zeros((0, tp.dim))
    feed = np.asarray(feed, dtype=np.float64)
    t_in, t_out = tp.tangents()
    step = np.where(np.asarray(corners, dtype=bool)[:, None], 0.0, t_in[1:] - t_out[:-1])
    s = np.cumsum(tp.lengths)[:-1]  # arc length at the interior vertices [mm]
    b = math.sqrt(6.0) * np.maximum(feed[:-1], feed[1:]) * _sigma(delays)  # the triangle's half-width
    return triangle_sum(s, step, b) / b[:, None]


def curvature_caps(tp: ToolPath, feed: np.ndarray, kappa: np.ndarray, delays: np.ndarray,
                   limits: AxisLimits | None) -> np.ndarray:
    """``(M,)`` feed [mm/s] per block: the commanded ``feed`` ``(M,)`` capped by the limits on the
    path's curvature (module docstring).

    A vertex of curvature ``kappa`` ``(M - 1, d)`` [1/mm] (:func:`vertex_curvature`) caps both of
    its blocks at ``min_a sqrt(A_a / |kappa_a|)`` and ``(min J / |kappa|^2)^(1/3)``. An arc block
    of radius ``R`` takes ``sqrt(min A R)`` and ``(min J R^2)^(1/3)`` (its normal sweeps its
    plane); a line block ``min_a V_a / |u_a|``, ``u`` the direction from the path ``F sigma``
    before its start to ``F sigma`` after its end (the filters' averaged direction: a rounded
    chord's own zigzags by degrees; ``min V`` where those two points meet, a circle within the
    reach); an arc ``min V``. Without ``limits``: ``feed``.
    """
    feed = np.asarray(feed, dtype=np.float64)
    if limits is None:
        return feed.copy()
    A, J, V = (np.asarray(x, dtype=np.float64) for x in (limits.acceleration, limits.jerk, limits.velocity))
    arc = tp.is_arc
    S = np.concatenate([[0.0], np.cumsum(tp.lengths)])  # arc length at each vertex, the ends included [mm]
    reach = feed * _sigma(delays)
    with np.errstate(divide="ignore", invalid="ignore"):
        lo = np.searchsorted(S, S[:-1] - reach, side="left")
        hi = np.searchsorted(S, S[1:] + reach, side="right") - 1
        points = np.vstack([np.asarray(tp.start, dtype=np.float64)[None], np.asarray(tp.ends, dtype=np.float64)])
        chord = points[hi] - points[lo]
        size = np.linalg.norm(chord, axis=1, keepdims=True)
        # a span that comes back to where it started (a circle smaller than the reach) has no
        # direction: its cap is then the least velocity limit, which every direction keeps
        direction = np.where(size > 0, np.abs(chord) / np.where(size > 0, size, 1.0), 1.0)
        cap = np.minimum(feed, np.where(arc, np.min(V), np.min(V[None] / direction, axis=1)))
        r = tp.radii[arc]
        cap[arc] = np.minimum.reduce([cap[arc], np.sqrt(np.min(A) * r), np.cbrt(np.min(J) * r**2)])
        at_vertex = np.minimum(np.min(np.sqrt(A[None] / np.abs(kappa)), axis=1),
                               np.cbrt(np.min(J) / np.sum(kappa * kappa, axis=1)))
    return _at_blocks(cap, at_vertex)


def shrink_caps(kappa: np.ndarray, tolerance: np.ndarray, delays: np.ndarray) -> np.ndarray:
    """``(M,)`` feed [mm/s] per block at which the filters' shrink of the curve at its vertices,
    ``F^2 var |kappa| / 2`` (eq 8 to second order, ``var = sum T_i^2 / 12``), is the vertex's
    ``tolerance`` ``(M - 1,)`` [mm] (``inf`` where the path is straight, and at a tolerance of 0,
    an exact stop): the error the mirror passes then compensate is at most that, and their
    residual a share of it."""
    size = np.linalg.norm(kappa, axis=1)
    curved = (size > 0) & (tolerance > 0)  # a tolerance of 0: an exact stop (eq 11), the output rests on it
    at_vertex = np.full(size.shape, np.inf)
    at_vertex[curved] = np.sqrt(2.0 * tolerance[curved] / (_sigma(delays) ** 2 * size[curved]))
    return _at_blocks(np.full(kappa.shape[0] + 1, np.inf), at_vertex)


def _at_blocks(cap: np.ndarray, at_vertex: np.ndarray) -> np.ndarray:
    """``cap`` ``(M,)`` lowered to each vertex's ``at_vertex`` ``(M - 1,)`` on both of its blocks."""
    cap = cap.copy()
    cap[:-1] = np.minimum(cap[:-1], at_vertex)
    cap[1:] = np.minimum(cap[1:], at_vertex)
    return cap


def _sigma(delays: np.ndarray) -> float:
    """The FIR kernel's rms half-width [s]: ``sqrt(sum T_i^2 / 12)`` (its variance, each moving
    average's ``T_i^2 / 12`` summed)."""
    return math.sqrt(float(np.sum(np.asarray(delays, dtype=np.float64) ** 2)) / 12.0)


def triangle_sum(s: np.ndarray, step: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``(V, d)``: at each ``s_v`` [mm], ``sum_u max(0, 1 - |s_u - s_v| / b_v) step_u`` over the
    vertices ``u`` (``s`` ``(V,)`` nondecreasing), by running sums of ``step`` and ``s step``: the
    left half ``(b - s_v) sum step + sum s_u step`` and the right half ``(b + s_v) sum step - sum
    s_u step``, each over the vertices within ``b`` on its side."""
    zero = np.zeros((1, step.shape[1]))
    total = np.vstack([zero, np.cumsum(step, axis=0)])
    moment = np.vstack([zero, np.cumsum(s[:, None] * step, axis=0)])
    lo = np.searchsorted(s, s - b, side="right")  # strictly inside: the weight is 0 at distance b
    mid = np.arange(s.size)  # the vertex itself counted once, on the right
    hi = np.searchsorted(s, s + b, side="left")
    left = (b - s)[:, None] * (total[mid] - total[lo]) + (moment[mid] - moment[lo])
    right = (b + s)[:, None] * (total[hi] - total[mid]) - (moment[hi] - moment[mid])
    return (left + right) / b[:, None]


def jerk_push(position, times: np.ndarray, ratios: np.ndarray, limits: AxisLimits, delays: np.ndarray,
              tangents: np.ndarray):
    """:func:`limit_factors`' ``push`` for the limit violations at ``times`` [s] with ``ratios`` on
    ``position`` (a ``NumpyPiecewise``): each violating piece's jerk over the limit ``(P, A)`` (its
    row 0 where the piece's peak is not its jerk's) and the blocks' start ``tangents`` ``(M, A)``;
    None unless the profile is cubic under two filters (lines), whose jerk is the input's second
    difference."""
    if np.asarray(delays).size != 2 or position.coeffs.shape[1] != 4:
        return None
    piece = np.clip(np.searchsorted(position.breaks, times, side="right") - 1, 0, position.coeffs.shape[0] - 1)
    jerk = 6.0 * position.coeffs[piece, 3] / np.asarray(limits.jerk)[None]
    jerk[np.max(np.abs(jerk), axis=1) < ratios * (1.0 - 1e-9)] = 0.0  # a peak of v or a: every block in reach
    return jerk, tangents


def limit_factors(starts: np.ndarray, pulses: np.ndarray, times: np.ndarray, ratios: np.ndarray,
                  delays: np.ndarray, push=None) -> np.ndarray:
    """``(M,)`` factors ``<= 1`` on the block feeds for limit violations at ``times`` [s] with
    ``peak / limit`` ``ratios`` (module docstring): each violation lowers the blocks whose input
    was in use within ``LIMIT_REACH min T_i`` of ``times - s`` for each sum ``s`` of a subset of
    the delays (``_fir_profile._subsets``: the filter chain's highest derivative at ``t`` is a
    signed sum of its input at ``t`` less each of them; pulses from ``starts`` ``(M,)`` [s] for
    ``pulses`` ``(M,)`` [s]; the block whose pulse started last before then, in a dwell), by ``min(r^-LIMIT_EXPONENT, 1 -
    LEAST_STEP)`` for the largest ``r`` that reaches it. A span, not the one block: lowering one
    short block among its neighbours steps the input's speed down and up within the filters'
    memory, and those steps are jerk of their own.

    ``push``: None, or ``(jerk (P, A) / limit, tangents (M, A))`` for a cubic profile under two
    filters, whose jerk is the second difference ``sum_S (-1)^|S| v(t - s_S) / (T_1 T_2)`` of the
    input's velocity ``v``: then, where the piece's peak is its jerk's (a row of ``jerk`` not 0),
    only the blocks whose term has the sign of that jerk on its largest axis are lowered (lowering
    the others would push it further). A velocity or acceleration peak lowers every block in
    reach: signed by the piece's jerk as well, small excesses at eps 150 and 200 um on bench_cam's
    quick file stayed for 41 rounds (benchmarks/README.md)."""
    M = starts.size
    ends = starts + pulses
    reach = LIMIT_REACH * float(np.min(delays))
    worst = np.ones(M)
    for shift, sign_s in zip(*_subsets(tuple(np.asarray(delays, dtype=np.float64).reshape(-1).tolist()))):
        x = times - shift
        first = np.searchsorted(ends, x - reach, side="left")  # the first pulse ending at or after the span
        last = np.searchsorted(starts, x + reach, side="right") - 1  # the last starting before its end
        first = np.minimum(first, np.maximum(last, 0))  # in a dwell: the block before it
        keep = last >= 0
        if push is not None:  # only the blocks whose part of the peak has its sign
            jerk, tangents = push
            axis = np.argmax(np.abs(jerk), axis=1)
            largest = jerk[np.arange(jerk.shape[0]), axis]
            sign = sign_s * tangents[np.clip(last, 0, M - 1), axis] * largest
            keep &= (sign > 0) | (largest == 0.0)
        first, last, r = first[keep], last[keep], ratios[keep]
        count = last - first + 1
        index = np.repeat(first - np.cumsum(count) + count, count) + np.arange(int(count.sum()))
        np.maximum.at(worst, index, np.repeat(r, count))
    return np.where(worst > 1.0, np.minimum(worst ** -LIMIT_EXPONENT, 1.0 - LEAST_STEP), 1.0)


def raise_factors(ratios: np.ndarray, step) -> np.ndarray:
    """``(M,)`` factors ``>= 1`` on the block feeds of a verified plan (module docstring): each
    block takes ``min(r^-LIMIT_EXPONENT, 1 + step)`` of the largest ``peak / limit`` ``r`` over its
    output span (``ratios`` ``(M,)``, :func:`span_ratios`), 1 where ``r >= 1``; ``step``: the
    largest raise, one or ``(M,)`` (:data:`RAISE_STEP` at first)."""
    up = np.minimum(np.maximum(ratios, 1e-300) ** -LIMIT_EXPONENT, 1.0 + np.asarray(step, dtype=np.float64))
    return np.maximum(up, 1.0)


def span_ratios(starts: np.ndarray, pulses: np.ndarray, peaks, delays: np.ndarray) -> np.ndarray:
    """``(M,)`` the largest ``peak / limit`` of a profile's pieces (``peaks``: its ``PiecePeaks``,
    over orders and axes) that overlap each block's output span, from its pulse start to
    ``sum(delays)`` after its end (every instant its input is inside the filters' window:
    ``starts``, ``pulses`` ``(M,)`` [s]); 0 where no piece does. Narrower reaches were tried (per
    order, the instants the kernel's derivatives read: the jerk under two filters four instants,
    not the window's middle): within 0.3 % either way on the CAM excerpts and the quick file, 0.8 %
    slower on the 10^4-chord file (benchmarks/README.md)."""
    lo = np.searchsorted(peaks.breaks[1:], starts, side="right")  # the first piece ending after the start
    hi = np.searchsorted(peaks.breaks[:-1], starts + pulses + float(np.sum(delays)), side="left")  # past the last
    out = np.zeros(np.shape(starts))
    some = hi > lo
    if some.any():
        out[some] = range_max(peaks.per_piece, lo[some], hi[some])
    return out
