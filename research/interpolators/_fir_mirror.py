"""Mirror pre-compensation of a FIR plan: the filters' input moved so that their output keeps the
programmed path (beyond Sencer 2015: Prevost 2012's mirror applied to the interpolator itself).

Why: on a curve the FIR chain averages the path, and the average of a curve lies inside it. On a
circle of radius ``R`` at feed ``F`` the output is a circle of radius ``R prod sinc(F T_i / 2R)``
(eq 8), an inward error of about ``F^2 var / (2 R)`` (``var`` the kernel's variance); ``plan_fir``
holds it within the tolerance by the feed, which is what keeps a FIR plan on a CAM file of smooth
chords well below the feeds a time-optimal plan reaches under the same limits (``sqrt(A R)``).
The error is a known function of the input, so it can be compensated instead of waited out: with
the plan's timing held (every block's pulse start and length, eq 5 and 11), the output is linear in
the input's vertices (each block's velocity pulse is its chord over its pulse length), and moving
each vertex by the mirror of its error brings the output back onto the path (Prevost 2012 eq 4,
``x_ref <- x_ref + (x_CAM - x_sim)``, here with ``x_sim`` the exact filtered profile).

What this module does:

1. **Timing.** Once the input is compensated, the output runs on the programmed path, so its feed
   is bounded by what bounds any motion on that path: the limits on its curvature, as in a
   time-optimal plan (``_fir_mirror_feeds.curvature_caps``). Two timings are searched, each at a
   relaxed tolerance ``g_k eps_k`` per block (``g_k >= 1``) and at the blocks' curvature caps times
   factors the search lowers, and the faster verified plan is kept. Both are planned with
   ``corner_speed="turn"``: the search's feeds step from block to block, and eq 13/14 read as the
   velocity step dwells at every step (``_fir_overlap``, "Unequal feeds"); on bench_cam's 10^4-chord
   CAM file those dwells on 1-5 degree turns held 0.53 s of the plan's 44.73 s, and the file plans
   in 43.67 s without them.

   a. ``plan_fir``'s eq 13/14 plan (``refine=False``: no look-ahead, no checks of its own), also
      capped where the filters' shrink of the curve would exceed ``g eps`` (eq 8 to second order,
      ``_fir_mirror_feeds.shrink_caps``): the mirror then compensates an error of at most that;
   b. ``plan_fir``'s look-ahead plan, whose window feeds hold the whole windowed error within
      ``g eps``. It is slower where the mirror converges (bench_cam's first 300 CAM chords at eps
      50 um: 1.4653 s against 1.3877 s) and faster where its residual is a larger share of eps
      (the quick file at eps 10 um: 30.59 s against 45.12 s). It starts from (a)'s plan and stops
      as soon as its timing alone cannot beat it.

2. **Mirror passes** (:func:`compensate`): ``passes`` passes move the vertices of the planned
   blocks (its pulse table's chords). Each vertex takes the mirror of its contour error: the vector
   from the output's point nearest the vertex (searched over the window centred on it) to the
   vertex, less its component along the path's tangent there. The point at the corner instant
   instead lagged behind the vertex where the feed changes, and its mirror moved the vertex along
   the curve; on the first 100 chords of bench_cam's CAM file that input broke the jerk limit by
   4.3x after five passes, the nearest point's by 1.5x. Fixed: the path's two ends and exact stops
   (the output rests on them).

   **Arcs** are searched as chords (``_fir_mirror_paths.chorded``: sagitta ``CHORD_SHARE`` of the
   tolerance) and checked as the programmed arcs. Each arc block was once scaled about its own
   centre (eq 8's shrink is radial), which only an arc between two lines can be: two arcs that
   meet cannot both scale about their centres and still meet. On chains of tangent arcs (CAM
   arc fitting) nothing verified and the plain plan came back: a 54-block program of 40 such arcs
   (R 5-40 mm) at bench_cam's setting kept ``plan_fir``'s 10.2124 s after 8.4 s of search, and
   4.6292 s as chords; over eleven programs with arcs (``benchmarks/fir_mirror.py``) the cycles
   summed 33.71 -> 19.60 s (benchmarks/README.md).

   **Fillets** (``_fir_mirror_paths.cornered``): an arc, or a run of chords, shorter than the
   filters' reach at its feed that rounds the corner of two longer blocks is not followed as a
   curve at all: the window averages it with the blocks either side, yet ``plan_fir`` slows it to
   its eq 8 feed (or its chords' window feeds) as if it were a long curve. A fillet of R 1 mm
   between two 50 mm lines at bench_cam's setting: 0.7283 s, against 0.6552 s for the sharp corner
   without it. Where the program has fillets the search runs a second time (the faster verified
   plan is kept) with each planned as the corner ``V`` of the lines either side and checked as
   programmed: eq 13/14 rounds ``V`` at ``|V - P| + (2 h - 1) eps`` (``P`` the fillet's point
   nearest ``V``; ``planned_tolerance``), ``h`` bisected per fillet on which side of ``P`` the
   output passes (``bisect_rounding``); the mirror passes leave the fillet's planned vertices where
   they are (moving ``V`` towards ``P`` by the mirror of its error broke the lines beside it). The
   fillet: 0.6298 s; a closed 60 x 40 mm rectangle with R 1 mm fillets 1.6384 -> 1.2492 s (as 1 um
   G1 chords 1.6774 -> 1.2492 s); an offset pocket of 8 such rings (R 1-0.3 mm, 2 mm stepovers)
   10.8623 -> 8.3186 s, under the envelope's limits 11.0126 -> 9.0319 s. A fillet of R 2 mm or
   more sits too far inside its corner (0.83 mm at R 2) for one rounding to follow it: such an
   arc is planned as the polygon of its tangents with the fewest corners within ``CORNER_OFFSET``
   tolerances of it (more after a spent search): a fillet of R 5 mm 0.7863 -> 0.6384 s (two
   corners), the rectangle with R 5 mm fillets 1.8579 -> 1.2837 s. A fillet turning more than
   ``CORNER_TURN`` (120 deg; one corner never verified beyond it) gets at least ``turn /
   CORNER_TURN`` corners: a slot of R 1 mm half circles 0.9784 -> 0.7973 s.

3. **Checks and search.** The exact profile of the moved input is checked against the
   *programmed* path as ``plan_fir`` checks its own (vertex distances at every corner, the
   trajectory sampled), but more densely: the mirror holds the output's distance near eps all
   along a curve, so its peaks fall between samples; the samples lie ``check_period / k`` apart,
   further where the profile bends less, and keep eps less what can hide between them
   (``_fir_mirror_check``; only which corners and blocks break eps is sought, not by how much).
   And against ``limits`` on its exact peaks. A limit
   violation lowers the feeds of the blocks whose input makes the profile at its instant
   (``_fir_mirror_feeds.limit_factors``; at a jerk peak of a cubic profile, only those whose term
   has the peak's sign, until the peak has stayed as high for :data:`STUCK_ROUNDS` rounds: the
   signed lowering can miss what makes a peak, where the moved input's direction is not the
   path's). A tolerance violation lowers the feeds of the blocks whose window holds
   it by ``TOLERANCE_STEP`` (the mirror's residual falls with the feed where it does not with
   ``g``), from the feed each block reached once it has been lowered :data:`LOWERED_ROUNDS`
   rounds in a row with the violation still there (a short block's feed is its window's, often
   far below the cap the steps act on); where the corner nearest it was the nearest to one in
   the round before as well, it halves that corner's relaxation towards 1 (``g <- 1 + (g - 1) / 2``, to 1 below
   :data:`_LAST_STEP`; at a sharp corner eq 13/14 then dwells), and once that is at 1 its
   vertices stop being moved. Halving at the first violation moved the violation on: the halved
   corner's blocks slow against their neighbours, whose corner broke next, and round by round a
   low relaxation spread along the path (bench_cam's file from block 9830 as a program: the
   violations moved on by one to five blocks a round for five rounds, leaving ``g`` 2-3 over 20
   blocks). Halving at the second violation instead: the 10^4-chord file 43.6683 -> 43.6014 s,
   the quick file's eps ladder summed 94.00 -> 93.47 s (at 10 um 29.33 -> 29.62 s, slower).
   A *sharp* corner, one that dwells even at the first round's relaxed tolerance (eq 13/14 at
   ``relax eps``), is different: its error is eq 13/14's at its relaxed tolerance, which the
   relaxation sets and the feeds barely move. Its relaxation is halved at its first violation and
   its window's feeds are kept (once it is at 1, as any other). The test part of four lines and a
   G2 arc (``data/programs/part_line_arc.ngc``, 90 deg corners on 40-70 mm lines) lowered its long
   lines by 3 % a round while its corners' relaxation came down every second round, and its first
   timing passed ``plan_fir``'s before it verified: 2.1319 s, the plain plan; now 1.9386 s. On
   bench_cam's cases: the eps ladder summed 93.47 -> 92.64 s, the 10^4-chord file 43.6014 ->
   43.5978 s, the first 300 / 1,000 chords +0.2 %; eleven programs with arcs 19.60 -> 19.18 s; 25
   fuzz programs 11 faster, 1 slower by 0.015 %. Then the next round re-plans, at most ``rounds``
   rounds per timing.
4. **Raise phase** (with limits). Steps down overshoot: a block lowered for a peak that its
   neighbours' lowering then removed stays low (bench_cam's first 100 CAM chords: about 40 blocks
   left at 0.93-0.99 of their caps where nothing in their spans reached a limit). Once a plan
   verifies, every block whose output span keeps below the limits is raised by its headroom
   (``_fir_mirror_feeds.span_ratios``, ``raise_factors``), and the search re-plans. A raise that
   breaks a limit or the tolerance takes the raised blocks whose span holds the violation back to
   the last verified feeds and halves their largest raise (one failed raise freezing every block in
   its span instead: the first 1,000 chords 0.8 % slower, the quick file 0.4 %); a violation no
   raised block's span holds is searched as in step 3. The phase ends when nothing can be raised
   by more than ``RAISE_LEAST``, a re-plan is not faster than the best verified plan, or the
   rounds run out. Only verified plans faster than the best are kept. The
   second timing's search stops once its timing alone is no faster than the best (step 1), which
   its later rounds, with feeds and relaxations only lowered, would not be either where
   ``plan_fir``'s cycle falls with both.

The plan returned is the faster of this and ``plan_fir``'s own at the tolerance, so it is never
slower than the plain plan and always verified. What the machine's interpolator is fed is the
moved polyline (:attr:`MirrorPlan.input_vertices`); the filters then run it unchanged.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np
from scipy.spatial import cKDTree

from research._device import device_array
from research.errors import ParameterError
from research.interpolators._fir_profile import ProfileInputs, profile
from research.interpolators._fir_mirror_paths import (FILLET_RETRIES, SHORT_LEAST, Fillets, bisect_rounding, chorded,
                                                      cornered, planned_tolerance)
from research.interpolators._fir_mirror_feeds import (RAISE_STEP, TOLERANCE_STEP, curvature_caps, jerk_push,
                                                      limit_factors, raise_factors, shrink_caps, span_ratios,
                                                      triangle_sum, vertex_curvature)
from research.interpolators._fir_mirror_check import violations
from research.interpolators._fir_verify import nearest_instants
from research.interpolators.fir import (CHECK_PERIOD, FIRPlan, _as_toolpath, _check_inputs, joined_plan, paused_parts,
                                       plan_fir)
from research.limits import AxisLimits
from research.paths.toolpath import ToolPath
from research.piecewise import NumpyPiecewise

#: tolerance factor of the first round's timing and mirror passes per round, swept with
#: ``benchmarks/fir_mirror.py --sweep`` (relax 2-64 x passes 1-8 on bench_cam's quick CAM file,
#: limits = the envelope, the search of 2026-12-05 third: 0.3923x ``plan_fir``'s cycle at 32 / 5,
#: 0.3890x at 16 / 5, 0.3929x at 64 / 5, 0.4420x at 8 / 5, 0.7307x at 2 / 5): flat from 16 to 64;
#: 32 is where the feed steps were swept (16 with them: the first 1,000 chords 1.091x the OCP, but
#: eps 150 / 200 um 8.3752 / 8.3840 s, a rise; 32: 1.099x and 8.3840 / 8.3840 s)
RELAX, PASSES = 32.0, 5
#: half-width of the triangle that smooths each pass's steps along the path, as a share of the
#: shortest delay times the input speed (module docstring, step 2). Swept (benchmarks/README.md):
#: 0, 0.1, 0.15, 0.25, 0.35, 0.5, 1 on the first 100 and 300 chords of bench_cam's CAM file, its
#: quick file and the micro-chord program (16 um chords) rounded to 0.1 and 2.54 um, limits = the
#: envelope; 0.15-0.35 is flat, 0 never verifies the rounded program
SMOOTH = 0.25
_LAST_STEP = 1.25  # a relaxation below this goes to 1 on the next violation (one round, not many)
#: rounds in a row a jerk peak may stay as high under the signed lowering (step 3) before it
#: lowers every block in its reach. Swept (benchmarks/README.md) at 1-5 on the first 100 / 300 /
#: 1,000 chords, the quick file at eps 10 / 20 / 50 / 100 um, the micro-chord program, the 10^4-chord
#: file, and the fuzz run's program of seed 25 (stuck at 1.05x the jerk limit for 40 rounds, the
#: plain plan returned): 4 is the least count that leaves every bench_cam case as it was (1-3
#: moved them by -0.4 to +1.1 %) and plans seed 25 at 10.5706 s against 12.2763 s
STUCK_ROUNDS = 4
#: rounds in a row a block's feed may be lowered for a tolerance violation that stays (step 3)
#: before it is lowered from the feed it reached instead of from its cap. Swept 2 / 4 / **8** / 16
#: (with no such lowering: 30.0733 / 668.7790 / 627.5498 s, tight contours 2 of 6 returned plain,
#: the 1,897-block program 290.5828 s): fir_mirror.py's arc programs 30.0889 / 30.1165 / 30.0733 /
#: 30.0733 s, the 120 filleted fuzz contours 668.6264 / 668.7133 / 668.7790 / 668.7790 s, the 100
#: random programs 625.1398 / 622.1265 / 619.4909 / 619.6872 s, six filleted contours at eps 2.54 um
#: and F 423 mm/s 29.0355 / 28.4383 / 27.8905 / 29.1255 s, a real 394-block program at eps 2.54 um
#: 38.8451 / 37.8541 / 37.7488 / 37.7360 s (53.1065 s plain) and its 1,897 blocks - / 210.0793 /
#: 209.1836 / 290.5828 s (at 16 its 41 rounds run out first)
LOWERED_ROUNDS = 8
RAISE_LEAST = 1e-3  # the raise phase ends when no block can be raised by more than this share


def default_rounds(relax: float) -> int:
    """Re-plans allowed: twice those that take one corner from ``relax`` to 1 by the search's
    halvings (to :data:`_LAST_STEP`, then 1) and stop moving its vertices, since a violation moves
    on to the neighbours of the blocks it changed, plus those that halve a feed by
    ``TOLERANCE_STEP`` steps (relax 32: 18 + 23 = 41 rounds at a step of 0.03), for each of the two
    timings. The search stops earlier once a timing cannot beat the best plan, or nothing is left
    to raise; with the raise phase (step 4) bench_cam's CAM files took 25-47 rounds in all, its
    quick file's eps ladder (10-200 um) 43-59, the 10^4-chord file 46 (the first timing's 41 the
    budget's: its last raise was cut off, worth about 0.1 %)."""
    halvings = 0 if relax <= _LAST_STEP else math.ceil(math.log2((relax - 1.0) / (_LAST_STEP - 1.0)))
    return 2 * (halvings + 2) + math.ceil(math.log(0.5) / math.log(1.0 - TOLERANCE_STEP))


@dataclass(frozen=True)
class MirrorPlan:
    """A FIR plan whose filters' input is moved so that their output keeps the programmed path.

    Attributes:
        plan: the :class:`FIRPlan` (its timing, vertices and corner instants; its profile the
            filtered moved input, verified against the programmed path:
            :attr:`FIRPlan.path_deviation` is the largest sampled distance [mm]). Where the
            program has arcs and the plan is compensated, its blocks are the arcs' chords
            (``chorded``; the programmed vertices among their vertices), or for a fillet the
            pieces of the lines to its corner (``cornered``), whose vertex there is the fillet's
            point nearest that corner: every vertex is a point of the program, and
            :attr:`FIRPlan.corner_errors` its verified distance.
        input_vertices: ``(B + 1, d)`` the path the filters average [mm]: the vertices of the
            planned blocks (arcs as chords or fillets as corners, straight runs merged, lines
            cut into ramp pieces where ``plan_fir`` did), moved; the programmed vertices where
            nothing was compensated.
        relaxation: ``(M,)`` factor ``g_k >= 1`` on each programmed block's tolerance at which the
            timing was planned (an arc's: the least over its chords; a fillet planned as a corner
            is rounded by ``planned_tolerance`` instead; 1 everywhere when the plain
            plan was kept).
        feed_factors: ``(M,)`` each block's feed in the timing over its commanded feed (the
            curvature caps times the search's factors; an arc's: the least over its chords; 1
            everywhere when the plain plan was kept).
        compensated: False when ``plan_fir``'s own plan was kept (it was as fast, or no round
            verified).
        rounds: re-plans made.
        plain_cycle_time: ``plan_fir``'s cycle time at the tolerance [s], for comparison.
    """

    plan: FIRPlan
    input_vertices: np.ndarray
    relaxation: np.ndarray
    feed_factors: np.ndarray
    compensated: bool
    rounds: int
    plain_cycle_time: float

    @property
    def cycle_time(self) -> float:
        """Total motion time [s] (:attr:`FIRPlan.cycle_time`)."""
        return float(self.plan.cycle_time)


def plan_fir_mirror(path, feed, delays, tolerance, *, limits: AxisLimits | None = None, relax: float = RELAX,
                    passes: int = PASSES, rounds: int | None = None, check_period: float = CHECK_PERIOD,
                    pauses=None, progress=None) -> MirrorPlan:
    """A FIR plan with its input pre-compensated by mirror passes (module docstring).

    Args:
        path, feed, delays, tolerance, limits, check_period, pauses: as :func:`plan_fir` (concrete
            values: this search decides on them and is not differentiable).
        relax: tolerance factor ``>= 1`` the first round plans its timing at.
        passes: mirror passes per round, ``>= 0`` (0: relaxed timing, nothing moved: verifies only
            where the relaxed plan already keeps the tolerance).
        rounds: re-plans at most, ``>= 1``; None: :func:`default_rounds` of ``relax``.
        progress: called after every re-plan with the cycle time [s] of the best plan so far (a
            progress bar's hook: the search may take minutes on long programs at tight
            tolerances), or None.

    Returns:
        :class:`MirrorPlan`; its plan keeps ``tolerance`` on the programmed path (vertices and
        sampled trajectory, as ``plan_fir`` verifies) and ``limits`` on its exact peaks, and its cycle
        time is at most ``plan_fir``'s.

    Raises:
        ParameterError: a bad ``relax``, ``passes`` or ``rounds`` (naming which), or what
            :func:`plan_fir` raises.

    Example:
        >>> import numpy as np
        >>> from research.paths import Polyline
        >>> a = np.linspace(0.0, np.pi, 200)
        >>> arc = Polyline(np.stack([10 * np.cos(a), 10 * np.sin(a)], axis=1))
        >>> m = plan_fir_mirror(arc, 200.0, [0.06, 0.03], 0.05)
        >>> bool(m.cycle_time <= m.plain_cycle_time)
        True
    """
    if not (np.isfinite(relax) and relax >= 1.0):
        raise ParameterError(f"relax must be a finite factor >= 1 on the tolerance, got {relax!r}")
    if isinstance(passes, bool) or not isinstance(passes, (int, np.integer)) or passes < 0:
        raise ParameterError(f"passes must be an integer >= 0 (mirror passes per round), got {passes!r}")
    if rounds is None:
        rounds = default_rounds(float(relax))
    if isinstance(rounds, bool) or not isinstance(rounds, (int, np.integer)) or rounds < 1:
        raise ParameterError(f"rounds must be an integer >= 1 (re-plans at most), got {rounds!r}")
    tp = _as_toolpath(path)
    M = tp.n_blocks
    _check_inputs(delays, feed, tolerance, M, limits, tp.dim)
    cut = paused_parts(tp, feed, tolerance, pauses, lambda part, f, t: plan_fir_mirror(
        part, f, delays, t, limits=limits, relax=relax, passes=passes, rounds=rounds, check_period=check_period,
        progress=progress))
    if cut is not None:
        pauses, ranges, parts = cut
        return MirrorPlan(joined_plan(tp, pauses, ranges, [p.plan for p in parts]),
                          np.concatenate([parts[0].input_vertices] + [p.input_vertices[1:] for p in parts[1:]]),
                          np.concatenate([p.relaxation for p in parts]), np.concatenate([p.feed_factors for p in parts]),
                          any(p.compensated for p in parts),
                          sum(p.rounds for p in parts),
                          sum(p.plain_cycle_time for p in parts) + float(np.nansum(pauses)))
    tol = np.broadcast_to(np.asarray(tolerance, dtype=np.float64), (M,))
    feed = np.broadcast_to(np.asarray(feed, dtype=np.float64), (M,))
    delays = np.asarray(delays, dtype=np.float64).reshape(-1)
    Td = float(np.sum(delays))
    plain = plan_fir(tp, feed, delays, tol, limits=limits, check_period=check_period)
    T_plain = float(plain.cycle_time)
    best = MirrorPlan(plain, _input_vertices(plain), np.ones(M), np.ones(M), False, 0, T_plain)
    # the search plans chords where the program has arcs, and checks the arcs themselves (chorded);
    # where it has fillets shorter than the filters' reach, also those as corners (cornered); after
    # a search that verified nothing better, again with one more corner on each fillet whose
    # rounding ran out of bisection steps (beyond CORNERS_MAX it stays as programmed)
    total, owner_best = 0, None
    extra = np.zeros(M, dtype=int)  # searches each programmed block's fillet spent (cornered)
    for attempt in range(2 + FILLET_RETRIES):
        variant = (chorded(tp, tol) + (None,)) if attempt == 0 else cornered(tp, tol, feed, Td, extra)
        if variant is None:
            break
        planned, checked, owner, fillets = variant
        f, t = feed[owner], tol[owner]
        B = planned.n_blocks
        corners = np.zeros(max(B - 1, 0), dtype=bool)
        if B > 1:  # eq 13/14 dwells there at the relaxed tolerance: a corner, not a curve (no curvature cap)
            h = None if fillets is None else np.ones(fillets.first.size)
            eq13 = plan_fir(planned, f, delays, planned_tolerance(t, np.full(B, relax), fillets, h), refine=False,
                            corner_speed="turn")
            corners = np.asarray(eq13.overlaps) < Td * (1.0 - 1e-12)
        kappa = vertex_curvature(planned, f, corners, delays)
        caps = curvature_caps(planned, f, kappa, delays, limits)
        better = False
        spent = np.zeros(0 if fillets is None else fillets.first.size, dtype=bool)
        for refine in (False, True):  # eq 13/14 at the caps, then plan_fir's look-ahead (module docstring)
            found, r, out = _search(planned, checked, f, delays, t, limits, relax, passes, rounds, check_period,
                                    refine, kappa, caps, best, corners, fillets, progress)
            if found is not best:
                best, owner_best, better = found, (owner if planned is not tp else None), True
            if progress is not None:
                progress(float(best.plan.cycle_time))
            spent |= out
            total += r
        if fillets is not None and (better or not spent.any()):
            break
        if fillets is not None:
            extra[np.unique(fillets.owners[spent])] += 1
    if best.compensated and owner_best is not None:  # per programmed block: the least over its chords
        # each programmed block's first planned block
        own_first = np.concatenate([[0], np.flatnonzero(np.diff(owner_best)) + 1])
        best = dataclasses.replace(best, relaxation=np.minimum.reduceat(best.relaxation, own_first),
                                   feed_factors=np.minimum.reduceat(best.feed_factors, own_first))
    return dataclasses.replace(best, rounds=total)


def _search(tp: ToolPath, checked: ToolPath, feed: np.ndarray, delays: np.ndarray, tol: np.ndarray, limits: AxisLimits | None,
            relax: float, passes: int, rounds: int, check_period: float, refine: bool, kappa: np.ndarray,
            caps: np.ndarray, best: MirrorPlan, corners: np.ndarray,
            fillets: Fillets | None = None, progress=None) -> tuple[MirrorPlan, int, np.ndarray]:
    """One timing's search (module docstring, steps 1-3): ``(the faster of best and what it
    verified, rounds made, (n,) the fillets whose bisection ran out with violations left)``.
    ``tp``: the planned path (arcs as chords, fillets as corners), ``checked``: the path its plans
    are checked against (the programmed arcs' pieces, :func:`chorded`); ``refine``: the timing is
    ``plan_fir``'s look-ahead plan, else its eq 13/14 plan capped by :func:`shrink_caps` as well; ``kappa`` ``(M - 1, d)`` the vertices' curvature [1/mm], ``caps`` ``(M,)`` the blocks'
    curvature caps [mm/s]; ``corners`` ``(M - 1,)`` the sharp corners (step 3); ``fillets``: the
    fillets ``tp`` has as corners (``cornered``; their tolerance ``planned_tolerance``'s, bisected
    where a violation is theirs), or None; ``progress``: :func:`plan_fir_mirror`'s."""
    M = tp.n_blocks
    g = np.full(M, float(relax))
    scale = np.ones(M)  # the search's factors on the caps
    frozen = np.zeros(M, dtype=bool)  # programmed blocks whose planned vertices are not moved
    tangents = tp.tangents()[0]
    verified = None  # the search's factors of the last verified plan (raise phase)
    struck = np.zeros(M, dtype=bool)  # the blocks of the corners nearest a tolerance violation last round
    lowered = np.zeros(M, dtype=int)  # rounds in a row each block's feed was lowered for the tolerance
    step = np.full(M, RAISE_STEP)  # each block's largest raise a round, halved where a raise broke something
    last_limits = (np.zeros(0), np.zeros(0), np.zeros(0, dtype=int))  # the last round's limit violations
    n_fillets = 0 if fillets is None else fillets.first.size
    h, lo, hi = np.ones(n_fillets), np.zeros(n_fillets), np.ones(n_fillets)  # their roundings (planned_tolerance)
    spent = np.zeros(n_fillets, dtype=bool)
    r = 0
    while r < rounds:
        if progress is not None and r:
            progress(float(best.plan.cycle_time))
        r += 1
        relaxed_tol = planned_tolerance(tol, g, fillets, h)
        top = caps if refine else np.minimum(caps, shrink_caps(kappa, np.minimum(relaxed_tol[:-1], relaxed_tol[1:]),
                                                                delays))
        plan = plan_fir(tp, top * scale, delays, relaxed_tol, refine=refine, check_period=check_period,
                        corner_speed="turn")
        if float(plan.cycle_time) >= float(best.plan.cycle_time):
            break  # this timing cannot beat the plan at hand, moved or not
        moved, vertices = compensate(plan, passes, frozen, None if fillets is None else fillets.pinned)
        found = violations(moved, checked, tol, limits, check_period)
        if found.tolerance.size == 0 and found.limits.size == 0:
            # its corners are the checked path's vertices (a fillet's point nearest its planned corner,
            # not that corner, which lies off the program), at the errors just verified
            best = MirrorPlan(dataclasses.replace(moved, path_deviation=found.deviation,
                                                  vertices=device_array(checked.vertices)), vertices, g.copy(),
                              top * scale / feed, True, r, best.plain_cycle_time)
            if limits is None:
                break
            # raise phase: every block whose span keeps below the limits, up to its cap
            verified = scale.copy()
            up = raise_factors(span_ratios(np.asarray(moved.start_times), np.asarray(moved.pulse_times), found.peaks,
                                           delays), step)
            up = np.minimum(up, 1.0 / scale)
            if np.max(up) < 1.0 + RAISE_LEAST:
                break
            scale = scale * up
            continue
        if verified is not None:
            # a raise broke something: the raised blocks whose span holds it go back to the last
            # verified feeds, their raise halved; a violation no raised block's span holds is searched as before
            back = _blocks_near(moved, np.concatenate([found.limits, found.tolerance])) & (scale > verified)
            if back.any():
                scale[back] = verified[back]
                step[back] *= 0.5
                continue
        push = None if found.limits.size == 0 else jerk_push(moved.position.numpy_evaluator(), found.limits,
                                                             found.ratios, limits, delays, tangents)
        held = _persisting(found.limits, found.ratios, last_limits, float(np.min(delays)))
        if push is not None:
            # a jerk peak that the signed lowering left as high as it was for STUCK_ROUNDS rounds
            # lowers every block in reach
            push = (np.where((held >= STUCK_ROUNDS)[:, None], 0.0, push[0]), push[1])
        last_limits = (found.limits, found.ratios, held)
        scale *= limit_factors(np.asarray(moved.start_times), np.asarray(moved.pulse_times), found.limits,
                               found.ratios, delays, push)
        late = found.tolerance
        if late.size and n_fillets:  # a violation by a fillet still bisected: its rounding moves instead
            which = fillets.corner_of[_nearest_corner(moved, late)]
            mine = (which >= 0) & (hi[which] - lo[which] > SHORT_LEAST)
            spent[which[(which >= 0) & ~mine]] = True
            if mine.any():
                bisect_rounding(moved.position.numpy_evaluator(), np.asarray(moved.corner_times), moved.delays, fillets,
                                np.unique(which[mine]), h, lo, hi)
                late = late[~mine]
        if late.size:
            if M > 1:  # the nearest corner's eq 13/14 tolerance back towards eps, the second round in a row
                # (a sharp corner's at once)
                at = _nearest_corner(moved, late)
                near = np.zeros(M, dtype=bool)
                near[at] = near[at + 1] = True
                sharp = np.zeros(M, dtype=bool)
                # a sharp corner (one that dwells even at the first round's relaxed tolerance) still
                # relaxed: its error is eq 13/14's at that tolerance, which its relaxation sets and
                # the feeds do not: relaxed less at once, its window's feeds kept
                hit = corners[at] & (np.maximum(g[at], g[at + 1]) > 1.0)
                sharp[at[hit]] = sharp[at[hit] + 1] = True
                blocks, struck = (near & struck) | sharp, near
                relaxed = blocks & (g > 1.0)
                g[relaxed] = np.where(g[relaxed] < _LAST_STEP, 1.0, 1.0 + 0.5 * (g[relaxed] - 1.0))
                frozen |= blocks & ~relaxed  # at the tolerance already: stop moving its vertices
                lower = late[~hit]
            else:
                lower = late
            slow = _blocks_near(moved, lower)
            held_low = slow & (lowered >= LOWERED_ROUNDS)  # lowered that many rounds in a row, still violated
            # those are lowered from the feed they reached, not from their cap: a short block's feed
            # is its window's (plan_fir's look-ahead), often far below the cap, where steps of the
            # cap change nothing for many rounds (an arc's 0.05 mm chords at 4 mm/s under a
            # 423 mm/s cap, eps 2.54 um: no plan verified in 48 rounds)
            reached = np.asarray(moved.feeds)[held_low] / np.maximum(top[held_low], 1e-300)
            scale[held_low] = np.minimum(scale[held_low], reached)
            scale[slow] *= 1.0 - TOLERANCE_STEP
            lowered = np.where(slow, lowered + 1, 0)
        else:
            struck[:] = False
            lowered[:] = 0
    return best, r, spent


def compensate(plan: FIRPlan, passes: int, frozen: np.ndarray, pinned=None) -> tuple[FIRPlan, np.ndarray]:
    """``passes`` mirror passes on ``plan``'s input, its timing held (module docstring, step 2).

    Args:
        plan: a concrete plan of a path of lines (its profile a ``ProfileInputs``; the search plans
            arcs as chords, :func:`chorded`).
        passes: mirror passes (0: the plan's own input).
        frozen: ``(M,)`` programmed blocks whose planned vertices are not moved.
        pinned: None, or ``(n, d)`` points [mm] (the fillets' corners and ends, :func:`cornered`):
            planned vertices there are not moved.

    Returns:
        ``(plan with the moved input's profile, its input vertices (B + 1, d) [mm])``.
    """
    inputs = plan.profile
    table = inputs.pieces.table
    if table.arc_pieces.size:
        raise ParameterError("compensate moves the vertices of lines; plan arcs as chords (chorded)")
    B = table.n_blocks
    Td = float(np.sum(inputs.delays))
    target = _input_vertices(plan)
    normal = _normal_projectors(target)
    moved = target.copy()
    line = ~table.gap & (table.block < B)
    fixed = smooth = None
    for k in range(passes + 1):
        geo = table.geo.copy()
        geo[line, 0, :] = np.diff(moved, axis=0)[table.block[line]]
        starts, ends, breaks, coeffs, centre = profile(inputs.start, geo, table.block, table.gap, inputs.fraction,
                                                       inputs.piece_tv, inputs.gaps, inputs.delays, table.joins)
        if k == passes or B < 2:
            break
        if fixed is None:  # the timing is held: the planned pulses start and end where they did here
            fixed = _fixed_vertices(inputs, plan, frozen, ends[: B - 1]) | _at(target, pinned)
            smooth = _smoothing(target, fixed, ends[:B] - starts[:B], float(np.min(inputs.delays)))
        pos = NumpyPiecewise(breaks, coeffs)
        error = target[1:-1] - pos(nearest_instants(pos, target[1:-1], centre[: B - 1], 0.5 * Td))
        moved[1:-1] += smooth(np.einsum("kij,kj->ki", normal, error))  # its part across the path, smoothed
    moved_inputs = ProfileInputs(dataclasses.replace(table, geo=geo), inputs.fraction, inputs.piece_tv, inputs.gaps,
                                 inputs.delays, inputs.start, np.asarray(inputs.span))
    return dataclasses.replace(plan, profile=moved_inputs), moved


def _at(vertices: np.ndarray, points) -> np.ndarray:
    """``(B + 1,)`` True for the ``vertices`` [mm] at one of ``points`` ``(n, d)`` (None: none), within
    1e-9 of the path's extent (the vertices are read back from the pulse table by sums)."""
    if points is None or not len(points):
        return np.zeros(vertices.shape[0], dtype=bool)
    dist, _ = cKDTree(points).query(vertices)
    return dist <= 1e-9 * (1.0 + float(np.max(np.abs(vertices))))


def _smoothing(target: np.ndarray, fixed: np.ndarray, pulses: np.ndarray, shortest: float):
    """The smoothing of a pass's steps (module docstring, step 2): a function of the steps
    ``(B - 1, d)`` at the interior planned vertices ``target[1:-1]`` [mm] that averages them along
    the path with triangle weights of half-width ``SMOOTH * shortest * v`` (``v`` the larger input
    speed of the vertex's two blocks, chord over pulse ``pulses`` ``(B,)`` [s]; ``shortest`` the
    shortest delay [s]), over the vertices not ``fixed`` ``(B + 1,)``, and leaves those at 0."""
    chords = np.linalg.norm(np.diff(target, axis=0), axis=1)
    along = np.cumsum(chords)[:-1]  # arc length at each interior vertex [mm]
    speed = chords / np.maximum(pulses, 1e-300)
    width = np.maximum(SMOOTH * shortest * np.maximum(speed[:-1], speed[1:]), 1e-12)
    still = fixed[1:-1]
    weight = triangle_sum(along, (~still).astype(np.float64)[:, None], width)

    def smooth(step: np.ndarray) -> np.ndarray:
        out = np.where(weight > 0, triangle_sum(along, np.where(still[:, None], 0.0, step), width)
                       / np.maximum(weight, 1e-300), 0.0)
        out[still] = 0.0
        return out

    return smooth


def _nearest_corner(plan: FIRPlan, times: np.ndarray) -> np.ndarray:
    """``(N,)`` the corner (``0 .. M - 2``) whose instant (``plan.corner_times``) is nearest each of
    ``times`` [s]."""
    centre = np.asarray(plan.corner_times)
    j = np.clip(np.searchsorted(centre, times), 1, max(centre.size - 1, 1))
    before = np.abs(centre[j - 1] - times) <= np.abs(centre[np.minimum(j, centre.size - 1)] - times)
    return np.where(before, j - 1, np.minimum(j, centre.size - 1))


def _input_vertices(plan: FIRPlan) -> np.ndarray:
    """``(B + 1, d)`` vertices [mm] of the blocks ``plan``'s pulse table holds: its start plus the
    running sum of every piece's displacement (``geo`` holds ``dP/du`` in powers of the piece's
    local block fraction ``u' in [0, share]``: the piece moves ``sum_m geo_m share^(m+1) / (m+1)``)."""
    inputs = plan.profile
    table = inputs.pieces.table
    B = table.n_blocks
    motion = ~table.gap & (table.block < B)
    m = np.arange(table.geo.shape[1])
    weight = table.fraction[:, None] ** (m + 1) / (m + 1)
    disp = np.zeros((B, table.geo.shape[2]))
    np.add.at(disp, table.block[motion], np.einsum("pmd,pm->pd", table.geo[motion], weight[motion]))
    return np.asarray(inputs.start, dtype=np.float64) + np.concatenate([np.zeros((1, disp.shape[1])),
                                                                        np.cumsum(disp, axis=0)])


def _fixed_vertices(inputs: ProfileInputs, plan: FIRPlan, frozen: np.ndarray, ends: np.ndarray) -> np.ndarray:
    """``(B + 1,)`` planned vertices that stay where they are: the two ends, exact stops (gap
    ``T_d``: the output rests on the vertex) and the vertices on the programmed blocks ``frozen``
    ``(M,)`` or next to them. A planned vertex is where its block's pulse ends (``ends`` ``(B - 1,)``
    [s]): on the programmed block whose pulse started last before then (:func:`_programmed_blocks`),
    or at that block's end."""
    B = ends.size + 1
    fixed = np.zeros(B + 1, dtype=bool)
    fixed[[0, B]] = True
    Td = float(np.sum(inputs.delays))
    gaps = np.asarray(inputs.gaps)[: B - 1]
    fixed[1:B][gaps >= Td * (1.0 - 1e-12)] = True
    if frozen.any():
        block = _programmed_blocks(plan, ends)
        near = frozen.copy()
        near[:-1] |= frozen[1:]
        near[1:] |= frozen[:-1]
        fixed[1:B] |= near[block]
    return fixed


def _programmed_blocks(plan: FIRPlan, times: np.ndarray) -> np.ndarray:
    """The programmed block whose pulse started last at or before each of ``times`` [s]
    (``plan.start_times``; the first block before its start): where a planned block's pulse
    instant lies on the program, its timing being the plan's."""
    starts = np.asarray(plan.start_times)
    return np.clip(np.searchsorted(starts, times, side="right") - 1, 0, starts.size - 1)


def _normal_projectors(vertices: np.ndarray) -> np.ndarray:
    """``(B - 1, d, d)`` projectors across the path at the interior vertices: ``I - tau tau^T`` with
    ``tau`` the unit bisector of the two chords' directions (the identity at a reversal, where the
    tangent is undefined)."""
    chords = np.diff(vertices, axis=0)
    u = chords / np.maximum(np.linalg.norm(chords, axis=1, keepdims=True), 1e-300)
    tau = u[:-1] + u[1:]
    n = np.linalg.norm(tau, axis=1, keepdims=True)
    tau = np.where(n > 1e-9, tau / np.maximum(n, 1e-300), 0.0)
    d = vertices.shape[1]
    return np.eye(d)[None] - tau[:, :, None] * tau[:, None, :]


def _persisting(times: np.ndarray, ratios: np.ndarray, last, within: float) -> np.ndarray:
    """``(N,)`` rounds in a row that the violations at ``times`` [s] with ``ratios`` have been held
    as high: one more than a violation of the last round's (``last``: its times, sorted, ratios and
    counts) within ``within`` [s] and not above ``ratios`` by more than 0.1 %, else 0."""
    before, was, count = last
    out = np.zeros(times.size, dtype=int)
    if not before.size:
        return out
    j = np.searchsorted(before, times)
    for k in (np.clip(j - 1, 0, before.size - 1), np.clip(j, 0, before.size - 1)):
        same = (np.abs(before[k] - times) <= within) & (ratios >= was[k] * (1.0 - 1e-3))
        out = np.where(same, np.maximum(out, count[k] + 1), out)
    return out


def _blocks_near(plan: FIRPlan, times: np.ndarray) -> np.ndarray:
    """``(M,)`` programmed blocks whose output span (pulse start to ``T_d`` after its end: every
    instant its input is inside the window) holds one of ``times`` [s]. Swept against spans widened
    by ``T_d / 2`` and ``T_d`` on each side (bench_cam's quick file, relax 8, 5 passes): 0.507x
    ``plan_fir``'s cycle against 0.543x and 0.564x; a wider reach relaxes more blocks that were
    never at fault."""
    starts = np.asarray(plan.start_times)
    Td = float(np.sum(np.asarray(plan.delays)))
    ends = starts + np.asarray(plan.pulse_times) + Td
    M = starts.size
    lo = np.searchsorted(ends, times, side="left")
    hi = np.searchsorted(starts, times, side="right")
    mark = np.zeros(M + 1, dtype=np.int64)
    np.add.at(mark, np.minimum(lo, M), 1)
    np.add.at(mark, np.minimum(np.maximum(hi, lo), M), -1)
    return np.cumsum(mark)[:M] > 0
