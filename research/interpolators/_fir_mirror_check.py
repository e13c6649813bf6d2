"""The mirror's check of a plan against the programmed path and the limits (``_fir_mirror``, step 3).

The mirror drives the output's distance to the path towards the tolerance all along a curve, so
the check samples more densely than ``plan_fir``'s and holds the samples to the tolerance less
what can hide between two of them (:func:`sample_period`: a global period set by the largest
acceleration anywhere in the profile; where an arc's bend adds more, the grid stays at that
period). Where the profile is gentler the same margin holds at longer strides
(:func:`local_strides`, per piece of the profile), and over an input piece's steady span (the
output a straight uniform motion) at longer ones still (:func:`_steady_strides`).

The distance ``d(t)`` from the output to the path between two samples ``h`` apart exceeds the
larger sample by at most ``K h^2 / 8``, ``K`` a bound on ``-d''`` there. To a line of the path (and
to a point) ``d'' >= -|a|``; to an arc of radius ``R`` from its concave side ``d = R - |p - c|``,
``d'' >= -|a| - |v|^2 / rho`` with ``rho >= R - tol - 2 margin`` for samples within the tolerance
(:func:`piece_concavity`: per profile piece, from its local coefficients and the arcs within the
window of input it averages).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from research.interpolators._fir_certify import derivative_bound
from research.interpolators._fir_kernels import verified_bound
from research.interpolators._fir_limits import LIMIT_RTOL
from research.interpolators._fir_piece_peaks import PiecePeaks, range_max
from research.interpolators._fir_verify import certify_settings, path_deviations, profile_rounding, vertex_distances
from research.interpolators.fir import FIRPlan
from research.limits import AxisLimits
from research.paths.toolpath import ToolPath

#: share of the tolerance the sampled path check may miss between two samples (:func:`sample_period`):
#: the samples per ``check_period`` grow as its inverse square root (3 at eps 50 um under bench_cam's
#: envelope: the 10^4-chord file's planning 8.0 -> 9.5 s); plan_fir's own check allows none. Swept
#: with the local strides (benchmarks/README.md): 1e-3 / 3e-3 / 1e-2 give ``fir_mirror.py --quick``'s
#: 48 rows 136.7410 / 136.8000 / 136.7959 s (planning 13.4 / 11.9 / 11.2 s) and a real 394-block
#: program at eps 2.54 um 37.8235 / 37.7862 / 37.8351 s (planning 6.1 / 5.1 / 4.1 s): over the many
#: programs the least margin plans the fastest motion (the one program's 0.1 % moves either way
#: with the samples the search happens to see)
SAMPLE_MARGIN = 1e-3


@dataclass(frozen=True)
class Violations:
    """Where a plan's profile breaks the tolerance or the limits (:func:`violations`).

    Attributes:
        tolerance: ``(N,)`` times [s] of the tolerance violations, sorted.
        limits: ``(P,)`` middle times [s] of the profile pieces above a limit, and ``ratios``
            ``(P,)`` their largest ``peak / limit``.
        deviation: the largest sampled distance to the path [mm] (where the tolerance breaks, a
            lower bound: only which keys break it is sought).
        peaks: the profile's ``PiecePeaks`` under the limits (None without limits).
    """

    tolerance: np.ndarray
    limits: np.ndarray
    ratios: np.ndarray
    deviation: float
    peaks: PiecePeaks | None = None


def violations(plan: FIRPlan, tp: ToolPath, tol: np.ndarray, limits: AxisLimits | None,
               check_period: float) -> Violations:
    """Where ``plan``'s profile breaks the tolerance ``tol`` ``(M,)`` on the programmed path ``tp``
    or the ``limits`` (``_fir_mirror``'s step 3). The bounds are ``plan_fir``'s own:
    ``verified_bound`` plus the rounding the profile has accumulated by its end, and its limits'
    relative tolerance on the exact peaks; the path's samples are denser and keep the tolerance
    less their margin (:func:`sample_period`, :func:`local_strides`); only which corners and
    blocks break the tolerance is sought (``path_deviations``' ``keys_only``)."""
    pos = plan.position.numpy_evaluator()
    Td = float(np.sum(np.asarray(plan.delays)))
    slack = profile_rounding(pos, tp.ends[-1])
    centre = np.asarray(plan.corner_times)
    starts = np.asarray(plan.start_times)
    times = [np.zeros(0)]  # the corners above the tolerance first
    if tp.n_blocks > 1:
        tol_v = np.minimum(tol[:-1], tol[1:])
        errors = vertex_distances(pos, np.asarray(tp.vertices), centre, 0.5 * Td, tol_v)
        times[0] = centre[errors > verified_bound(tol_v) + slack]
    over_times, ratios, peaks = np.zeros(0), np.zeros(0), None
    if limits is not None:
        peaks = PiecePeaks(pos, limits)
        over = peaks.per_piece > 1.0 + LIMIT_RTOL
        over_times, ratios = 0.5 * (pos.breaks[:-1] + pos.breaks[1:])[over], peaks.per_piece[over]
    # the intervals between samples bounded only where the plan may be taken: no vertex error and
    # no limit broken already (a broken plan is never returned; plan_fir's rounds do the same)
    whole = not (over_times.size or times[0].size)
    positive = tol[tol > 0]
    accel = derivative_bound(pos, 2)
    period, margin = sample_period(accel, check_period, float(np.min(positive)) if positive.size else 0.0)
    held = np.where(tol > 0, tol - margin, tol)  # an exact stop's 0 stays 0 (its output is on the path)
    stopped = np.asarray(plan.overlaps) == 0.0  # exact stops: samples by them are their blocks' own (plan_fir's check)
    durations, cap = _steady_strides(plan, tp, tol, period, margin)
    pulses = np.asarray(plan.pulse_times)
    local = local_strides(pos, accel, tp, starts, pulses, Td, tol, check_period, period, margin)
    deviation, at_vertex, at_block = path_deviations(pos, tp, starts, centre, Td, held, period, durations=durations,
                                                     slack=slack, stopped=stopped, stride_cap=cap, spans=local,
                                                     keys_only=True,
                                                     certify=certify_settings(check_period, margin, 0.0) if whole else None)
    times.append(centre[sorted(at_vertex)] if at_vertex else np.zeros(0))
    middle = starts + 0.5 * pulses + 0.5 * Td  # the window centred on the block
    times.append(middle[sorted(at_block)] if at_block else np.zeros(0))
    return Violations(np.sort(np.concatenate(times)), over_times, ratios, float(deviation), peaks)


def _steady_strides(plan: FIRPlan, tp: ToolPath, tol: np.ndarray, period: float, margin: float):
    """``(durations (P,) [s], cap (P,))`` of the input pieces of ``plan`` (a path of lines, its
    profile a ``ProfileInputs``) for the thinned grid of the path check (``_fir_verify.steady_spans``):
    over a piece's steady span (the output averages that piece alone) the output moves along a
    straight line at the piece's speed ``v`` (chord over pulse length). Its distance to a line of
    the checked path ``tp`` is then convex in time, and so is its distance to an arc's circle
    outside it; inside, ``R - |p - c|`` is concave with ``|d''| <= v^2 / rho`` (``rho >= R - tol -
    2 margin`` for samples within the tolerance and a chord of at most ``v h``), so between samples
    ``h`` apart it exceeds the larger one by at most ``v^2 h^2 / (8 rho)``. ``cap`` keeps that at most
    ``margin`` [mm] (:func:`sample_period`'s, by which the samples are held below the tolerance),
    in strides of ``period`` [s]; unbounded on a path of lines, at rest or without a margin 1."""
    inputs = plan.profile
    table = inputs.pieces.table
    piece_tv = np.asarray(inputs.piece_tv)
    durations = inputs.durations()
    if not tp.is_arc.any():
        return durations, None
    rho = float(np.min(tp.radii[tp.is_arc])) - float(np.max(tol)) - 2.0 * margin
    chord = np.linalg.norm(table.geo[:, 0, :], axis=1)
    speed = np.where(table.gap | (piece_tv <= 0), 0.0, chord / np.where(piece_tv > 0, piece_tv, 1.0))
    if rho <= 0.0 or margin <= 0.0:
        return durations, np.ones(speed.size)
    with np.errstate(divide="ignore"):
        h = np.sqrt(8.0 * margin * rho) / speed  # inf at rest
    return durations, np.maximum(np.floor(h / period), 1.0)


def sample_period(accel: np.ndarray, check_period: float, tolerance: float) -> tuple[float, float]:
    """``(period [s], margin [mm])`` of the mirror's sampled path check (module docstring).

    The mirror drives the output's distance to the path towards the tolerance all along a curve,
    so its largest value often falls between two samples (the random chain of
    ``test_fir_mirror``'s seed 2: 50.016 um between the 1 ms samples, whose largest is 49.984 um,
    at eps 50 um). Near a peak the distance ``d`` to a line of the path has ``|d''| <= |a|`` (in
    the plane of the trajectory and the line), so between samples ``h`` apart it exceeds the
    larger sample by at most ``|a|_max h^2 / 8``. The check's grid is ``check_period / k``
    apart, ``k`` the least integer that makes that allowance at most ``SAMPLE_MARGIN`` of the
    ``tolerance`` [mm] (the smallest positive one over the blocks), and holds the samples to the
    tolerance less the allowance (the margin; a block of tolerance 0, an exact stop, keeps 0).
    ``accel``: ``(P,)`` bounds on ``|a|`` [mm/s^2] over the profile's pieces
    (:func:`derivative_bound`). A tolerance of 0 (every block an exact stop) keeps
    ``check_period`` and no margin."""
    if tolerance <= 0:
        return check_period, 0.0
    peak = float(np.max(accel, initial=0.0))
    k = max(1, math.ceil(check_period * math.sqrt(peak / (8.0 * SAMPLE_MARGIN * tolerance))))
    period = check_period / k
    return period, peak * period**2 / 8.0


def local_strides(position, accel: np.ndarray, tp: ToolPath, starts: np.ndarray, pulses: np.ndarray, Td: float,
                  tol: np.ndarray, check_period: float, period: float, margin: float):
    """Grid-index spans ``(first, last, stride)`` of the check's grid (``t0 + i period``) where the
    same ``margin`` holds at a stride longer than 1, or None (one sample per ``check_period`` at
    most: nothing to thin).

    :func:`sample_period` sets ``period`` by the largest ``|a|`` anywhere in the profile (a rapid,
    a sharp corner); elsewhere the distance bends less and the samples may lie further apart. Each
    piece ``[b_i, b_i+1)`` of the profile is a span of the grid, sampled at the stride
    ``floor(sqrt(8 margin / K) / period)`` within ``1 .. k`` (``k = check_period / period``), ``K``
    the largest concavity bound of the pieces that meet ``[b_i - check_period, b_i+1 +
    check_period]``: an interval between two consecutive samples is at most ``k period =
    check_period`` long and starts in the span, so it lies there, and the distance exceeds the
    larger sample by at most ``K h^2 / 8 <= margin``, as on the dense grid. ``K`` is ``|a|`` plus,
    near arcs, ``|v|^2 / rho`` (:func:`piece_concavity`). The spans cost the profile's pieces, not
    the cycle's duration (a 4,572 s engraving has a few hundred).

    Args:
        position: the exact profile (``NumpyPiecewise``); accel: ``(P,)`` its ``|a|`` bounds per
            piece [mm/s^2]; tp: the checked path; starts, pulses: ``(M,)`` each block's pulse start
            and length [s]; Td: total delay [s]; tol: ``(M,)`` tolerances [mm]; check_period [s];
            period, margin: :func:`sample_period`'s."""
    k = int(round(check_period / period))
    if k <= 1 or margin <= 0.0:
        return None
    breaks = np.asarray(position.breaks)
    t0 = float(breaks[0])
    n = int(np.ceil((float(breaks[-1]) - t0) / period)) + 1  # the grid of path_deviations
    concave = piece_concavity(position, accel, tp, starts, pulses, Td, tol)
    P = concave.size
    lo = np.clip(np.searchsorted(breaks, breaks[:-1] - check_period, side="right") - 1, 0, P - 1)
    hi = np.clip(np.searchsorted(breaks, breaks[1:] + check_period, side="left") - 1, 0, P - 1)
    near = range_max(concave, np.minimum(lo, hi), hi + 1)
    with np.errstate(divide="ignore"):
        stride = np.clip(np.floor(np.sqrt(8.0 * margin / near) / period), 1, k).astype(np.int64)
    # piece i holds the grid indices [ceil(b_i), ceil(b_i+1) - 1] (in periods from t0): a partition
    edge = np.minimum(np.ceil((breaks - t0) / period).astype(np.int64), n)
    first, last = edge[:-1], edge[1:] - 1
    keep = (stride > 1) & (last >= first)
    return first[keep], last[keep], stride[keep]


def piece_concavity(position, accel: np.ndarray, tp: ToolPath, starts: np.ndarray, pulses: np.ndarray, Td: float,
                    tol: np.ndarray) -> np.ndarray:
    """``(P,)`` bounds [mm/s^2] on ``-d''`` over each piece of ``position``, ``d`` the distance from
    the output to the path ``tp`` (module docstring): ``|a|`` (``accel``), plus ``|v|^2 / rho``
    where an arc block lies within the input the piece averages (its blocks' pulses meeting
    ``[start - T_d, end]``, and one block either side: a sample's three blocks). ``rho = R - (1 + 2
    SAMPLE_MARGIN) tol``, the least over those arcs; an arc with ``rho <= 0`` adds nothing: from its
    concave side the distance is at most ``R``, within the tolerance and the margin."""
    if not tp.is_arc.any():
        return accel
    M = tp.n_blocks
    breaks = np.asarray(position.breaks)
    rho = tp.radii - (1.0 + 2.0 * SAMPLE_MARGIN) * tol
    rho = np.where(rho > 0.0, rho, np.inf)
    ends = np.maximum.accumulate(starts + pulses)
    lo = np.clip(np.searchsorted(ends, breaks[:-1] - Td, side="left") - 1, 0, M - 1)
    hi = np.clip(np.searchsorted(starts, breaks[1:], side="right"), 0, M - 1)
    least = -range_max(-rho, np.minimum(lo, hi), hi + 1)
    speed = derivative_bound(position, 1)
    return accel + speed**2 / least
