"""Per-axis velocity, acceleration and jerk of FIR-overlap cornering: exact peaks and their repair.

Beyond Sencer 2015: plain overlap superposes the slow-down of one block and the speed-up of the
next, so an axis whose velocity reverses sees up to twice its nominal acceleration and jerk. The
limit-holding variant (``plan_fir(..., limits=...)``) repairs a planned FIR profile post hoc, in two
phases, on exact peaks (the profile is piecewise polynomial: peaks at break points and where the
next derivative vanishes, ``_fir_piece_peaks``):

Nothing changes where the planned profile keeps the limits (a plan that holds them is returned as
planned). Where a corner's window breaks one:

1. **Blocks alone.** With every corner an exact stop (``T_k = 0``) no two blocks' filtered outputs
   overlap, so a block's own peaks depend on its own pulse only: the exact-stop profile of just
   the blocks being checked gives them (:func:`alone_block_ratios`), but for the line blocks that
   a closed-form bound on those peaks proves safe (``_fir_alone_bound``: a staircase pulse of top
   level ``S`` peaks at most at ``S |u|``, ``S |u| / T_1`` and ``S |u| / (T_1 T_2)``, twice that
   where an up-step and a down-step lie between ``T_1 - T_2`` and ``T_1 + T_2`` apart). A block
   that a violating window covers (:func:`blocks_in_windows`) and that breaks a limit even alone is
   slowed: its feed is bisected between the closed-form safe feed (:func:`feed_caps`,
   :func:`arc_limit_caps`; a block of ``T_v >= T_1 + T_2`` peaks at ``F |u_i|``, ``F |u_i| / T_1``,
   ``F |u_i| / (T_1 T_2)``, Sencer 2015 §2.1) and its planned feed (:func:`hold_block_limits`).
   Short blocks inside a continuous motion often peak lower than alone (no start and stop of their
   own), so blocks are never slowed up front.
2. **Corners.** Any time at which two blocks' outputs overlap lies inside the window
   ``[end of block k, start of block k+1 + T_d]`` of a corner with ``T_k > 0``, and every other
   instant lies in one block's own span (checked every round), so with every block safe alone only
   overlapping corners can break a limit. A corner whose window does has its overlap
   bisected (:class:`CornerBisection`) between 0 (two safe blocks) and its planned value.

Convergence bound: a call of phase 1 builds at most ``2 + SECANT_STEPS + BISECTION_STEPS + HALVINGS``
exact-stop profiles, of the blocks it checks (then of those it bisects), and costs one round; it runs only in
rounds that find a block not checked before, so at most ``M`` times (once on the benchmark paths);
within such a round the slow-down is followed along the chain (``_fir_limit_spread``: the blocks
whose corner windows the slowed blocks' feed steps break are checked in the same round, at most
``M`` steps in all), so a chain of blocks slowed one after another costs one round, not ``N / 2``.
Phase 2 takes at most ``BISECTION_STEPS + 2`` rounds for the bisections, then exact-stop rounds for
corners still above a limit, each of which adds at least one exact stop (the profile away from a
corner set to ``T_k = 0`` is unchanged up to a shift), so at most ``M - 1`` more (0-1 on the
benchmark paths): ``BISECTION_STEPS + 2M + 1`` rounds in all. Each bisected corner gives away at
most ``2^-BISECTION_STEPS`` of its overlap. Should exact stops still break a limit (a block checked
alone in an earlier window, seen again in another), ``plan_fir`` slows every block those windows
cover by ``0.98 / ratio`` a round, within its hard round bound (``ConvergenceError`` beyond it).

Cost: a round after a corner bisection step alone whose limits still break is not checked
against the tolerance (the plan that is returned always is; see ``plan_fir``), and a bisecting
corner bounds its candidate's cycle time by its bracket's upper end
(:attr:`CornerBisection.bound_scale`), so the branch and bound drops a candidate as soon as that
bound passes the best verified plan; the closed-form capped candidates join the same queue once
any candidate needs a limit repair, with one candidate of the whole path at its feeds scaled to
what its start and end ramps allow (:func:`end_ramp_scale`): on chains of short chords far below
the envelope, phase 1 takes blocks to their safe feeds alone, which a block inside one continuous
motion never needed (a 1 deg chord circle at 0.1x: 20.13 s against 12.66 s at that scale). On a seeded 400-segment CAM-like path under the FIR envelope
this took planning from 2.6-4.3 s to 0.56-0.96 s at the same cycle time (benchmarks/README.md);
phase 1's profiles of only the blocks it checks took ``hold_block_limits`` from 26-29 % of a
limit-holding plan of the quick CAM file to 5-6 %, and the bound, which proves all 2,246 blocks
of its first checks safe, to 2-3 %. A round's corner-window and own-span ratios are recomputed
only where the profile's input changed since the candidate's last round (``_fir_round_peaks``).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from research.errors import ConvergenceError, ParameterError
from research.interpolators._fir_alone_bound import alone_bounds
from research.interpolators._fir_piece_peaks import PiecePeaks
from research.interpolators._fir_profile import profile
from research.limits import AxisLimits
from research.piecewise import NumpyPiecewise

#: bisection steps on a corner's overlap or a block's feed: the overlap (feed) given away is at most
#: ``2^-10`` of the planned one (0.23 ms of overlap at the paper's T_d = 237 ms)
BISECTION_STEPS = 10
#: halvings of a block's feed tried after the bisection if its lower bracket was not safe after all
HALVINGS = 8
#: relative excess over a limit taken as rounding. The peaks here are exact up to rounding
#: (Horner on local coefficients, ~1e-15 relative; eigenvalue roots only move a peak to second
#: order); limits measured on a sampled profile (``metrics.peak_axis_values``: one-sided values at
#: breaks +- 1e-12 t_end, golden-section refinement) agree with them to about 1e-11, and
#: ``metrics.within_limits`` accepts 1e-6. 1e-9 lies between the two: a plan measured within a
#: limit is not repaired, and a repaired plan passes the 1e-6 check.
LIMIT_RTOL = 1e-9


def feed_caps(lengths: np.ndarray, directions: np.ndarray, delays: np.ndarray, limits: AxisLimits) -> np.ndarray:
    """Largest feed [mm/s] per block for which the block alone keeps every axis limit.

    Args:
        lengths: ``(M,)`` block lengths [mm]; directions: ``(M, d)`` unit vectors.
        delays: FIR delays [s]; limits: per-axis limits.
    """
    d = np.sort(np.asarray(delays, dtype=np.float64))[::-1]
    if d.size < 2 and np.any(np.isfinite(limits.jerk)):
        raise ParameterError("a jerk limit needs at least two FIR filters: one filter gives unbounded jerk")
    if d.size > 3:
        raise ParameterError("limit-holding FIR cornering supports up to three filters (exact peaks)")
    u = np.abs(np.asarray(directions, dtype=np.float64))
    with np.errstate(divide="ignore", invalid="ignore"):
        va = np.min(np.where(u > 0, np.minimum(limits.velocity, limits.acceleration * d[0])[None, :] / u, np.inf), axis=1)
        if d.size < 2:
            return va
        long_block = np.min(np.where(u > 0, limits.jerk[None, :] * d[0] * d[1] / u, np.inf), axis=1)
        # a block shorter than T1 + T2 in time doubles its jerk; F <= L / (T1 + T2) keeps it long
        short_block = np.maximum(0.5 * long_block, np.minimum(long_block, np.asarray(lengths) / (d[0] + d[1])))
        jerk_cap = np.where(np.asarray(lengths) / long_block >= d[0] + d[1], long_block, short_block)
    return np.minimum(va, jerk_cap)


def steps_within_limits(tp, feeds: np.ndarray, t_in: np.ndarray, t_out: np.ndarray, delays: np.ndarray,
                        limits: AxisLimits) -> bool:
    """Whether every velocity step of the path at the feeds ``feeds`` keeps the limits taken alone
    through the FIR chain: each block's start and stop as the edges of a long block
    (:func:`feed_caps` of an infinitely long block, :func:`arc_limit_caps` on arcs) and each
    corner's step at full overlap ``dV = F_k+1 u_in,k+1 - F_k u_out,k``, which peaks at
    ``|dV_i| / T_1`` and ``|dV_i| / (T_1 T_2)`` (Sencer 2015 §2.1). A cheap prediction that the
    plan without limits keeps them (``plan_fir`` then checks its exact peaks): steps closer than
    ``T_d`` add or cancel, so it is no proof either way.

    Args:
        tp: the path (``ToolPath``); feeds: ``(M,)`` commanded feeds [mm/s];
        t_in, t_out: ``(M, d)`` block tangents at start and end; delays: FIR delays [s].
    """
    if np.any(feeds > _ramp_caps(tp.is_arc, tp.radii, t_in, delays, limits) * (1.0 + LIMIT_RTOL)):
        return False
    step = np.abs(feeds[1:, None] * t_in[1:] - feeds[:-1, None] * t_out[:-1])
    return bool(np.all(step <= isolated_step(delays, limits) * (1.0 + LIMIT_RTOL)))


def isolated_step(delays: np.ndarray, limits: AxisLimits) -> np.ndarray:
    """``(A,)`` largest velocity step [mm/s] per axis that keeps the limits alone through the FIR
    chain: ``min(A_i T_1, J_i T_1 T_2)`` (a step ``dV`` peaks at ``|dV_i| / T_1`` and
    ``|dV_i| / (T_1 T_2)``, Sencer 2015 §2.1; no jerk bound with one filter)."""
    d = np.sort(np.asarray(delays, dtype=np.float64))[::-1]
    jerk = limits.jerk * d[0] * d[1] if d.size > 1 else np.full(limits.n_axes, np.inf)
    return np.minimum(limits.acceleration * d[0], jerk)


def _ramp_caps(is_arc: np.ndarray, radii: np.ndarray, directions: np.ndarray, delays: np.ndarray,
               limits: AxisLimits) -> np.ndarray:
    """Largest feed [mm/s] per block whose start and stop, as the edges of a long block, keep the
    limits: :func:`feed_caps` of an infinitely long line along ``directions``, :func:`arc_limit_caps`
    on arcs."""
    return np.where(is_arc, arc_limit_caps(radii, delays, limits),
                    feed_caps(np.full(is_arc.size, np.inf), directions, delays, limits))


def profile_peak_ratio(position, limits: AxisLimits) -> float:
    """The largest ``peak / limit`` of a whole profile (``PiecewisePolynomial`` or its NumPy
    evaluator) over orders and axes, on its exact peaks (``_fir_piece_peaks.PiecePeaks``); it
    keeps the limits where this is at most ``1 + LIMIT_RTOL``."""
    breaks = np.asarray(position.breaks, dtype=np.float64)
    return float(PiecePeaks(position, limits).over(breaks[:1], breaks[-1:])[0])


def end_ramp_scale(tp, feeds: np.ndarray, t_in: np.ndarray, t_out: np.ndarray, delays: np.ndarray,
                   limits: AxisLimits) -> float:
    """Largest factor ``<= 1`` on every feed under which the path's start from rest and its stop
    at the end keep the limits as the edges of a long block: a velocity step ``F u`` through the
    FIR chain peaks at ``F |u_i|``, ``F |u_i| / T_1`` and ``F |u_i| / (T_1 T_2)`` (Sencer 2015 §2.1;
    :func:`feed_caps` of an infinitely long block), and an arc at its end by :func:`arc_limit_caps`.
    Every plan of the path makes these two steps; where the first and last blocks are long, a
    uniform scaling of the feeds by more than this breaks a limit at them (a short end block that
    turns into the next one can peak lower: the factor is a candidate's, not a bound).

    Args:
        tp: the path (``ToolPath``); feeds: ``(M,)`` feeds of its blocks [mm/s];
        t_in, t_out: ``(M, d)`` block tangents at start and end; delays: FIR delays [s].

    Returns:
        The factor, in ``(0, 1]``.
    """
    ends = np.array([0, tp.n_blocks - 1])
    caps = _ramp_caps(tp.is_arc[ends], tp.radii[ends], np.stack([t_in[0], t_out[-1]]), delays, limits)
    return float(min(1.0, np.min(caps / feeds[ends])))


def arc_limit_caps(radii: np.ndarray, delays: np.ndarray, limits: AxisLimits) -> np.ndarray:
    """Largest feed [mm/s] per arc block (``inf`` radius: no cap) for which the arc alone keeps
    every axis limit, bounding each derivative by its steady part plus its transient part:
    ``F <= v``, ``F / T_1 + F^2 / R <= a``, ``F / (T_1 T_2) + F^2 / (R T_2) + F^3 / R^2 <= j``
    (the start and stop pulse edges of a line, plus the centripetal acceleration ``F^2 / R`` and
    its rotation ``F^3 / R^2`` switched on through the shortest filter). Conservative: the
    smallest limit over the axes is used, since an arc's tangent sweeps its plane."""
    d = np.sort(np.asarray(delays, dtype=np.float64))[::-1]
    radii = np.asarray(radii, dtype=np.float64)
    arc = np.isfinite(radii)
    out = np.full(radii.shape, np.inf)
    r = radii[arc]  # the arcs alone: a plan of lines asks for every block (the bisection is elementwise)
    v, a, j = float(np.min(limits.velocity)), float(np.min(limits.acceleration)), float(np.min(limits.jerk))
    T1, T2 = d[0], (d[1] if d.size > 1 else d[0])

    def excess(F):
        acc = F / T1 + F**2 / r - a
        jerk = F / (T1 * T2) + F**2 / (r * T2) + F**3 / r**2 - j if np.isfinite(j) else -np.ones_like(F)
        return np.maximum(acc, jerk)

    lo, hi = np.zeros_like(r), np.full(r.shape, v)
    ok = excess(hi) <= 0
    lo = np.where(ok, hi, lo)
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        good = excess(mid) <= 0
        lo, hi = np.where(ok | ~good, lo, mid), np.where(ok | good, hi, mid)
    out[arc] = lo
    return out


def block_peak_ratios(peaks: PiecePeaks, starts: np.ndarray, pulse_times: np.ndarray, total_delay: float) -> np.ndarray:
    """``(M,)`` largest ``peak / limit`` over each block's filtered span ``[start, end + T_d]`` [s]
    (of a plan whose corners are exact stops: each block's own peaks), from its profile's ``peaks``.
    A span ends at the next block's start at the latest: with exact stops the two coincide up to
    rounding, and a span's end rounded past that start would take the next block's first piece."""
    starts = np.asarray(starts, dtype=np.float64)
    ends = np.minimum(starts + np.asarray(pulse_times) + total_delay, np.append(starts[1:], np.inf))
    return peaks.over(starts, ends)


#: a block whose closed-form bound (:func:`_fir_alone_bound.alone_bounds`) is at most this is not
#: built by :func:`alone_block_ratios`: its exact ratio lies within rounding (~1e-13) of at most the
#: bound, below ``1 + LIMIT_RTOL``, so no check would find it above a limit
PROVEN = 1.0 + 1e-12
#: with blocks left out, :func:`alone_block_ratios` builds every block asked for after all when a
#: block built comes within this of ``1 + LIMIT_RTOL`` (or above): its ratio at the other time
#: offset differs by rounding (~1e-13), so decisions away from the threshold are those of the full build
THRESHOLD_GUARD = 1e-11


def alone_block_ratios(table, blocks: np.ndarray, fraction: np.ndarray, piece_factor: np.ndarray, lengths: np.ndarray,
                       feeds: np.ndarray, start: np.ndarray, delays: np.ndarray, limits: AxisLimits, *,
                       prove: bool = True, decisions: bool = False) -> np.ndarray:
    """``(M,)`` largest ``peak / limit`` of each block ``blocks`` alone (phase 1), 0 for the others.

    With every corner an exact stop no two blocks' filtered outputs overlap, so a block's own peaks
    depend on its own pulse only: the exact-stop profile is built of the blocks asked for alone, in
    path order, each followed by its gap piece of ``T_d`` (but the path's last block, which has
    none), by the planner's own filter (``_fir_profile.profile``), and read over their spans
    (:func:`block_peak_ratios`). Its cost is that of those blocks' pieces, not the path's. Asked
    for every block, it is the whole path's exact-stop profile, the same arrays; asked for fewer,
    a block's pieces lie at another time offset (the blocks asked for before it, not all), which
    moves its peaks by rounding only.

    With ``prove``, a line block whose closed-form bound (:func:`_fir_alone_bound.alone_bounds`)
    is at most :data:`PROVEN` is not built and gets that bound; unless a block built comes within
    :data:`THRESHOLD_GUARD` of ``1 + LIMIT_RTOL``, then every block asked for is built (so every
    ratio is the exact one of the build without ``prove``). Either way each comparison with
    ``1 + LIMIT_RTOL`` comes out as without ``prove``: a block left out is below it, and a block
    built is not moved across it by the other time offset (nor by the last piece of the block
    before it, should that end past its start by rounding: the piece is within that block's own
    bound or ratio). With ``decisions`` as well (the caller reads only those comparisons, not the
    ratios above the limit), the blocks asked for are all built only when a block built comes
    within :data:`THRESHOLD_GUARD` of ``1 + LIMIT_RTOL`` on either side: a ratio further above it
    is then the build's own, within rounding of the exact one (a bisection's probes above a
    block's limit no longer build every block asked for twice).

    Args:
        table: the path's ``_fir_blocks.PulseTable``; ``blocks``: ``(M,)`` bool, the blocks asked for.
        fraction, piece_factor: ``(P,)`` share of its block and feed factor of every piece
            (``PulseTable.pieces`` at the plan's feed factors).
        lengths, feeds: block lengths [mm] and commanded feeds [mm/s], indexed by a piece's block
            (``(M_pad + 1,)``, as ``_fir_profile.timing``).
        start: ``(d,)`` start point [mm]; delays: ``(n,)`` filter delays [s]; limits: the per-axis limits.
        prove: leave out the blocks proven safe in closed form (above).
        decisions: only the comparisons with ``1 + LIMIT_RTOL`` are read (above).
    """
    blocks = np.asarray(blocks, dtype=bool)
    if prove:
        bound = alone_bounds(table, blocks, fraction, piece_factor, lengths, feeds, delays, limits)
        proven = blocks & (bound <= PROVEN)
        if proven.any():
            rest = blocks & ~proven
            out = _built_ratios(table, rest, fraction, piece_factor, lengths, feeds, start, delays, limits)
            near = out[rest] > 1.0 + LIMIT_RTOL - THRESHOLD_GUARD
            if decisions:
                near &= out[rest] < 1.0 + LIMIT_RTOL + THRESHOLD_GUARD
            if not np.any(near):
                out[proven] = bound[proven]
                return out
    return _built_ratios(table, blocks, fraction, piece_factor, lengths, feeds, start, delays, limits)


def _built_ratios(table, blocks, fraction, piece_factor, lengths, feeds, start, delays, limits) -> np.ndarray:
    """:func:`alone_block_ratios` without ``prove``: the exact-stop profile of the blocks ``blocks``."""
    M = table.n_blocks
    out = np.zeros(M)
    ks = np.flatnonzero(blocks)
    if ks.size == 0:
        return out
    idx, sub = table.block_pieces(ks)  # block k's motion pieces, then its gap piece (all but the path's last block)
    blk = table.block[idx]
    piece_tv = lengths[blk] / (feeds[blk] * piece_factor[idx])  # eq 5, the operations of _fir_profile.timing
    total_delay = float(np.sum(delays))
    gaps = np.where(ks < M - 1, total_delay, 0.0)  # exact stops: T_d - 0 after each block but the last
    starts, ends, breaks, coeffs, _ = profile(start, table.geo[idx], sub, table.gap[idx], fraction[idx], piece_tv,
                                              gaps, delays)
    peaks = PiecePeaks(NumpyPiecewise(breaks, coeffs), limits)
    out[ks] = block_peak_ratios(peaks, starts, ends - starts, total_delay)
    return out


def corner_limit_ratios(peaks: PiecePeaks, starts: np.ndarray, pulse_times: np.ndarray, total_delay: float) -> np.ndarray:
    """``(M - 1,)`` largest ``peak / limit`` in each corner's window ``[end of block k,
    start of block k+1 + T_d]`` [s]: every instant at which blocks ``k`` and ``k + 1`` overlap
    (``peaks``: the profile's :class:`PiecePeaks`)."""
    starts = np.asarray(starts, dtype=np.float64)
    if starts.size < 2:
        return np.zeros(0)
    ends = starts + np.asarray(pulse_times)
    return peaks.over(ends[:-1], starts[1:] + total_delay)


def own_span_ratios(peaks: PiecePeaks, starts: np.ndarray, pulse_times: np.ndarray, total_delay: float) -> np.ndarray:
    """``(M,)`` largest ``peak / limit`` in the part of each block's filtered span that no corner window
    covers, ``[start_k + T_d, end_k]`` (``[start_1, end_1]`` for the first block, ``[start_M + T_d,
    end_M + T_d]`` for the last, the whole span for a single block) [s]; 0 where that part is empty.

    Only block ``k``'s own pulse is filtered there (block ``k - 1``'s output has ended, block ``k + 1``'s
    has not begun), so these are the block-alone peaks that the corner windows do not see: a block
    slowed in pieces (look-ahead staircase) can break a limit inside its own span. ``peaks``: the
    profile's :class:`PiecePeaks`."""
    starts = np.asarray(starts, dtype=np.float64)
    ends = starts + np.asarray(pulse_times, dtype=np.float64)
    lo, hi = starts + total_delay, ends.copy()
    lo[0] = starts[0]
    hi[-1] = ends[-1] + total_delay
    out = np.zeros(starts.size)
    some = hi > lo
    if some.any():
        out[some] = peaks.over(lo[some], hi[some])
    return out


def hold_block_limits(alone_ratios: Callable[[np.ndarray, np.ndarray], np.ndarray], safe: np.ndarray,
                      which: np.ndarray) -> np.ndarray:
    """Feed multipliers ``g`` ``(M,)``, ``0 < g <= 1``, under which the blocks ``which`` alone keep the limits.

    Args:
        alone_ratios: ``(g, blocks, decisions) -> (M,)`` peak ratios of the blocks ``blocks``
            (``(M,)`` bool) alone, with every corner an exact stop and block feeds multiplied by
            ``g`` (:func:`alone_block_ratios`; blocks are independent, the others' entries
            unread; ``decisions``: only the comparisons with ``1 + LIMIT_RTOL`` are read). It is
            asked for ``which`` (ratios), then for the blocks still being searched (decisions).
        safe: ``(M,)`` multipliers known safe in closed form (:func:`feed_caps` / planned feed).
        which: ``(M,)`` bool, the blocks to check (the others keep 1).

    Returns:
        1 where a block keeps the limits alone or is not checked; otherwise the largest multiplier found safe on
        the grid of :data:`BISECTION_STEPS` bisections between ``safe`` and 1, next to one that is
        not (:func:`_largest_safe`; then up to :data:`HALVINGS` halvings should the bracket's
        lower end not be safe after all).

    Raises:
        ConvergenceError: a block still breaks a limit after the halvings.
    """
    which = np.asarray(which, dtype=bool)
    ratio = alone_ratios(np.ones(safe.size), which, False)
    bad = which & (ratio > 1.0 + LIMIT_RTOL)
    if not bad.any():
        return np.ones(safe.size)
    # the closed-form cap, or the velocity ratio's linear scaling where the cap claims no need
    lo = np.where(bad, np.where(safe < 1.0, safe, 1.0 / np.where(bad, ratio, 1.0)), 1.0)
    lo = _largest_safe(alone_ratios, bad, lo, ratio)
    still = bad
    for _ in range(HALVINGS + 1):
        ratio = alone_ratios(lo, still, True)  # a block found safe at its lower end keeps it
        still = still & (ratio > 1.0 + LIMIT_RTOL)
        if not still.any():
            return lo
        lo = np.where(still, 0.5 * lo, lo)
    raise ConvergenceError(f"limit-holding FIR: {int(still.sum())} blocks break a limit alone even at "
                           f"{float(np.min(lo[still])):.3g} of their feed", residual=float(ratio.max() - 1.0),
                           steps=BISECTION_STEPS + HALVINGS)


#: secant-guided probes of :func:`_largest_safe` per block before it bisects
SECANT_STEPS = 4


def _grid_point(lo: np.ndarray, j: np.ndarray) -> np.ndarray:
    """The multiplier the bisection of ``[lo, 1]`` in :data:`BISECTION_STEPS` steps tries at grid
    index ``j`` (``(M,)`` integers in ``[0, 2^BISECTION_STEPS]``; 0 is ``lo``, the top 1), computed
    by the same operations as the bisection on its way to that point (so the same floats): the
    midpoint of each step's bracket, the bracket following the bits of ``j`` from the top."""
    n = BISECTION_STEPS
    a, b = lo.copy(), np.ones(lo.size)
    out = np.where(j <= 0, lo, 1.0)
    done = (j <= 0) | (j >= 1 << n)
    for k in range(n - 1, -1, -1):  # step n - k of the bisection: its midpoint is index j with lowest bit k
        mid = 0.5 * (a + b)
        here = ~done & (j & ((1 << (k + 1)) - 1) == 1 << k)
        out = np.where(here, mid, out)
        done |= here
        up = (j >> k) & 1 == 1
        a, b = np.where(up, mid, a), np.where(up, b, mid)
    return out


def _largest_safe(alone_ratios, bad: np.ndarray, lo: np.ndarray, ratio: np.ndarray) -> np.ndarray:
    """The multipliers :data:`BISECTION_STEPS` bisections of ``[lo, 1]`` give the blocks ``bad``
    (``(M,)`` bool; the largest point of the bisection's grid found within the limits, ``lo``
    where none is), found in fewer profile builds where peaks grow with the feed.

    The bisection's points form a grid of ``2^BISECTION_STEPS`` steps on ``[lo, 1]``
    (:func:`_grid_point`, the same floats); where a block's ratio does not fall as its feed grows,
    the bisection ends at the largest grid point within the limits whose next one is not, and so
    does any search that brackets that point between two neighbouring grid points. This one
    brackets each block by grid indices (``lo`` taken within the limits and 1 above them, as the
    bisection does) and probes first where a power law of the feed puts the limit: a block's peaks
    grow as a power of its feed (jerk ``g F |u| / (T_1 T_2)`` for a pulse longer than ``T_2``,
    Sencer 2015 §2.1; a shorter one's acceleration not at all), so the zero of ``log(ratio / (1 +
    LIMIT_RTOL))`` on the line through the bracket's ends in ``log g`` (slope 1, the linear law,
    while the lower end is unmeasured), on the grid point below it after an upper end moved (or
    none yet) and above it after a lower end moved: two builds for a block that follows a power
    law, instead of :data:`BISECTION_STEPS`. After :data:`SECANT_STEPS` probes it bisects the
    bracket's indices; so at most ``SECANT_STEPS + BISECTION_STEPS`` builds, each of the blocks
    still bracketed wider than one grid step. (The probes depend on the ratios' values, which
    another time offset moves by rounding, but the result only on which grid points are within
    the limits.) Where a block's ratio falls somewhere as its feed grows (a pulse whose pieces'
    lengths meet the delays: peaks of its rise and fall cancel), both end at a grid point within
    the limits whose next one is not, not always the same: on the 150 programs of
    ``benchmarks/fir_limits_stress.py``, 6 plans came out faster than with the bisection (to
    0.72x), none slower, 144 the same (there the secant from the ratio at ``g = 1`` reached safe
    stretches above an unsafe one that the bisection had given up; on synthetic ratios with one
    narrow dip below the limit, the bisection's midpoint-first order lands in the dip more often).

    Args:
        alone_ratios: ``(g, blocks, decisions) -> (M,)`` peak ratios of the blocks ``blocks`` alone
            at feed multipliers ``g`` (:func:`hold_block_limits`; asked for decisions only).
        bad: ``(M,)`` bool, the blocks above a limit at multiplier 1; lo: ``(M,)`` their lower
            ends (not measured: ``hold_block_limits`` checks the result); ratio: ``(M,)`` their
            ratios at multiplier 1 (``> 1 + LIMIT_RTOL`` on ``bad``).
    """
    one, top = 1.0 + LIMIT_RTOL, 1 << BISECTION_STEPS
    j_lo, j_hi = np.zeros(lo.size, dtype=np.int64), np.full(lo.size, top, dtype=np.int64)
    g_lo, g_hi = lo.copy(), np.ones(lo.size)
    with np.errstate(divide="ignore", invalid="ignore"):
        f_hi = np.where(bad, np.log(ratio / one), 0.0)
    f_lo = np.full(lo.size, np.nan)  # unmeasured
    last = np.ones(lo.size, dtype=np.int64)  # the end the last probe moved: -1 lower, 1 upper
    active = bad.copy()
    for step in range(SECANT_STEPS + BISECTION_STEPS):
        if not active.any():
            break
        if step < SECANT_STEPS:
            with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
                x_lo, x_hi = np.log(g_lo), np.log(g_hi)
                slope = np.where(np.isnan(f_lo), 1.0, (f_hi - f_lo) / (x_hi - x_lo))
                u = (np.exp(x_hi - f_hi / slope) - lo) / (1.0 - lo) * top  # the estimate's grid index
                j = np.where(last > 0, np.floor(u), np.ceil(u))
            j = np.where((slope > 0.0) & np.isfinite(j), j, 0.5 * (j_lo + j_hi))
            j = np.clip(j, j_lo + 1, j_hi - 1).astype(np.int64)
        else:
            j = (j_lo + j_hi) // 2
        j = np.where(active, j, 0)
        g = np.ones(lo.size)
        g[active] = _grid_point(lo[active], j[active])
        r = alone_ratios(g, active, True)
        ok = r <= one
        with np.errstate(divide="ignore"):
            f = np.log(r / one)
        up, down = active & ok, active & ~ok
        j_lo, g_lo, f_lo = np.where(up, j, j_lo), np.where(up, g, g_lo), np.where(up, f, f_lo)
        j_hi, g_hi, f_hi = np.where(down, j, j_hi), np.where(down, g, g_hi), np.where(down, f, f_hi)
        last = np.where(active, np.where(ok, -1, 1), last)
        active &= j_hi - j_lo > 1
    return np.where(bad, g_lo, lo)


class CornerBisection:
    """Overlap multipliers of the corners that break a limit, found by bisection round by round.

    A corner above a limit in round ``r <= BISECTION_STEPS`` starts a bisection of its multiplier on
    ``[0, current]``; each round moves its bracket (above a limit: upper end, else lower end); after
    :data:`BISECTION_STEPS` steps it takes the lower end (the largest multiplier seen within the
    limits). A corner above a limit after its bisection, or first above one after round
    :data:`BISECTION_STEPS`, becomes an exact stop (multiplier 0). See the module docstring for the
    bound on rounds.

    Attributes:
        scale: ``(C,)`` overlap multipliers in ``[0, 1]``.
    """

    def __init__(self, n_corners: int):
        self.scale = np.ones(n_corners)
        self._lo, self._hi = np.zeros(n_corners), np.ones(n_corners)
        self._steps = np.zeros(n_corners, dtype=np.int64)
        self._state = np.zeros(n_corners, dtype=np.int64)  # 0 untouched, 1 bisecting, 2 settled
        self._round = 0

    @property
    def bound_scale(self) -> np.ndarray:
        """``(C,)`` upper bounds on the final multipliers: a bisecting corner ends at most at its
        bracket's upper end, which only falls; any other multiplier only falls (to 0 at most). The
        overlaps they give bound the repaired plan's cycle time from below."""
        return np.where(self._state == 1, self._hi, self.scale)

    def update(self, ratios: np.ndarray) -> bool:
        """Take this round's corner ratios (:func:`corner_limit_ratios`); returns True while the
        multipliers changed and the plan must be rebuilt and checked again.

        Raises:
            ConvergenceError: corners break a limit and none can change (all exact stops), which
                phase 1 rules out up to rounding."""
        self._round += 1
        bad = np.asarray(ratios) > 1.0 + LIMIT_RTOL
        changed = np.zeros(self.scale.size, dtype=bool)
        # settled corners (exact stops included) above a limit again: exact stop
        again = bad & (self._state == 2) & (self.scale > 0)
        self.scale[again], changed[again] = 0.0, True
        bis = self._state == 1
        self._hi = np.where(bis & bad, self.scale, self._hi)
        self._lo = np.where(bis & ~bad, self.scale, self._lo)
        self._steps[bis] += 1
        done = bis & (self._steps >= BISECTION_STEPS)
        self.scale = np.where(done, self._lo, np.where(bis, 0.5 * (self._lo + self._hi), self.scale))
        self._state[done] = 2
        changed |= bis
        new = bad & (self._state == 0)
        if self._round <= BISECTION_STEPS:
            self._lo[new], self._hi[new] = 0.0, self.scale[new]
            self.scale[new] *= 0.5
            self._state[new] = 1
        else:
            self.scale[new] = 0.0
            self._state[new] = 2
        changed |= new
        if bad.any() and not changed.any():  # only exact stops above a limit: a block alone breaks it
            raise ConvergenceError(f"limit-holding FIR: corners {np.flatnonzero(bad)[:5].tolist()} break a limit "
                                   "as exact stops", residual=float(np.max(ratios) - 1.0), steps=self._round)
        return bool(changed.any())


def blocks_in_windows(flags: np.ndarray, starts: np.ndarray, pulse_times: np.ndarray, total_delay: float) -> np.ndarray:
    """``(M,)`` True for the blocks whose filtered span ``[start, end + T_d]`` meets the window of a
    flagged corner (``flags`` ``(M - 1,)``, windows as in :func:`corner_limit_ratios`)."""
    M = np.asarray(starts).size
    out = np.zeros(M + 1, dtype=np.int64)
    c = np.flatnonzero(flags)
    if c.size:
        first, last = _window_blocks(c, starts, pulse_times, total_delay)
        np.add.at(out, first, 1)
        np.add.at(out, last, -1)
    return np.cumsum(out)[:M] > 0


def _window_blocks(corners: np.ndarray, starts, pulse_times, total_delay: float) -> tuple[np.ndarray, np.ndarray]:
    """``(first, last)``: the blocks ``first .. last - 1`` whose filtered span ``[start, end + T_d]``
    meets the window ``[end_c, start_(c+1) + T_d]`` of each of ``corners`` (indices)."""
    starts = np.asarray(starts, dtype=np.float64)
    ends = starts + np.asarray(pulse_times)
    first = np.searchsorted(ends + total_delay, ends[corners], side="right")
    last = np.searchsorted(starts, starts[corners + 1] + total_delay, side="left")
    return first, last


def window_slow_down(corners: np.ndarray, scale: np.ndarray, starts: np.ndarray, pulse_times: np.ndarray,
                     total_delay: float) -> np.ndarray:
    """``(M,)`` feed multipliers: each block whose filtered span meets the window of one of
    ``corners`` (indices, windows as in :func:`blocks_in_windows`) takes the least ``scale`` ``(C,)``
    of those corners (1 where none reaches it)."""
    g = np.ones(np.asarray(starts).size)
    c = np.asarray(corners, dtype=np.int64)
    if c.size:
        first, last = _window_blocks(c, starts, pulse_times, total_delay)
        count = np.maximum(last - first, 0)
        blocks = np.repeat(first - np.cumsum(count) + count, count) + np.arange(int(count.sum()))
        np.minimum.at(g, blocks, np.repeat(np.asarray(scale, dtype=np.float64), count))
    return g


def futile_stops(v_in: np.ndarray, v_out: np.ndarray, step: np.ndarray) -> np.ndarray:
    """``(C,)`` True where bisecting a corner's overlap towards an exact stop is predicted to be no
    remedy for its peaks. Through the FIR chain an isolated velocity step ``dV`` peaks at
    ``|dV_i| / T_1`` and ``|dV_i| / (T_1 T_2)`` on axis ``i`` (Sencer 2015 §2.1; the largest step the
    axes keep is ``step`` ``(d,)``, ``_fir_limit_spread.FeedSteps.step``). At full overlap the corner
    is one step ``v_out - v_in``, at an exact stop two, ``-v_in`` and ``v_out`` (``(C, d)`` [mm/s],
    each block's piece facing the corner). Where no axis's overlapped step, over the step it keeps,
    exceeds the largest of the stop's (no axis reverses: ``|v_out,i - v_in,i| <= max(|v_in,i|,
    |v_out,i|)``), or the stop's steps break a limit by themselves, the stop lowers nothing; in
    between, the decel of one block and the accel of the next part as the overlap falls and their
    peaks add (measured: the chord corners of bench_cam's quick file under 0.2x its envelope, 1.02-1.08
    of a limit at full overlap and up to 2.0 at half; 118 of them ended as exact stops). A prediction
    from isolated steps: ``plan_fir`` plans such corners both ways and keeps the faster plan."""
    with np.errstate(divide="ignore", invalid="ignore"):
        over = np.max(np.nan_to_num(np.abs(v_out - v_in) / step), axis=1)
        stop = np.max(np.nan_to_num(np.maximum(np.abs(v_in), np.abs(v_out)) / step), axis=1)
    return (over <= stop) | (stop > 1.0 + LIMIT_RTOL)
