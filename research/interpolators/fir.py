"""FIR-filter trajectory generation with tolerance-bounded corner overlap (Sencer 2015).

Data flow, one block ``k`` at a time (Sencer, Ishizaki, Shamoto, CIRP Annals 64, 2015):

1. Each G01 block becomes a rectangular axis-velocity pulse ``F_k u_k`` of length
   ``T_v,k = L_k / F_k`` (eq 5); an arc block the same pulse with a turning direction
   (``_fir_blocks``).
2. The pulse train goes through a chain of n moving-average filters with delays ``T_i``
   (eq 1-6), which makes velocity trapezoidal (n = 1), jerk-limited (n = 2), ...
3. Block ``k + 1`` starts ``T_d - T_k`` after block ``k``'s pulse ends: ``T_k = 0`` is an exact
   stop, ``T_k = T_d`` full overlap (eq 11). ``T_k`` comes from the cornering tolerance (eq 13/14,
   :func:`overlap_time`).
4. The filtered profile is piecewise polynomial, so it is built exactly (``PiecewisePolynomial``)
   and sampled at ``Ts``: no convolution, no rounding of ``T_i`` to the sample grid. Cycle time and
   corner errors are smooth in ``T_i`` and ``jax.grad`` goes through them.

CAM programs (beyond the paper, which assumes every block longer than the window ``T_d``):

* **Pauses** (``G4`` dwells, ``M0``/``M1`` stops; ``pauses=``): exact stops held for the dwell; the
  program is cut there and its parts planned alone (``_fir_pauses``).

* **Arcs** keep their feed below the eq 8 bound on the radial shrink of a filtered circle
  (``_fir_feed.arc_feed_caps``).
* **Look-ahead** (``refine=True``): corners that eq 13/14 rounds with a dwell keep it when that is
  cheaper than slowing down; every other vertex runs at full overlap with the largest feed whose
  windowed displacement ``|d_j(F)|`` (``_fir_feed``: all the direction changes inside the window,
  with their cancellation) stays within the tolerance; the block feeds are the minimum over the
  windows that cover them.
* **Verification and repair** (``_fir_settle``): the exact profile is checked at every vertex (distance from the
  vertex to the trajectory) and between vertices (distance from the trajectory, sampled every
  ``check_period``, to the programmed path; between two samples bounded from their distances to
  the blocks both see, and sampled more densely where that bound is above the tolerance: at most
  ``_fir_certify.BETWEEN_RTOL`` of it more there; bounded in every round that may return its plan,
  not in one whose vertex errors or limits already break), both up to the rounding of the profile (a fixed slack
  plus what the profile has accumulated by its end, ``_fir_verify.profile_rounding``, which grows
  with the program's duration). A violating dwell corner has its overlap shrunk by
  ``(eps / error)^(1/(n+1))`` (the small-overlap scaling of ``H2``), a violating full-overlap
  vertex slows the blocks of its window by ``sqrt(eps / error)`` (the error of a chain is
  quadratic in feed); after ``_fir_settle._SCALING_ROUNDS`` rounds a vertex still violating becomes an exact
  stop, which puts it on the trajectory whatever its neighbours do. Deviations inside an arc slow
  that arc. At most ``_fir_settle.MAX_ROUNDS`` rounds; the rounds needed are reported in
  :attr:`FIRPlan.rounds`. Candidates go through a branch and bound on lower bounds of their
  verified times; a round checks the vertex errors first, and the bound of their repairs alone
  (``_fir_repair``, a lower bound on the whole round's) can put a candidate behind the others
  before its path samples are taken; a competing candidate's first check starts with the vertex
  errors of its first blocks, on the profile of their input alone (the plan's own until that
  input ends). The rounds decide on concrete arrays (``_fir_profile``: the same timing
  and exact profile in NumPy/Numba, no JAX dispatch for one or two filters) and re-check only the vertex windows and path
  stretches whose profile a repair changed (``_fir_verify.RoundChecks``); the plan returned is
  built with JAX only when ``feed``, ``delays`` or ``tolerance`` is a tracer (its differentiable
  form, with the empty pieces that the concrete build drops).

One call is not monotone in ``eps`` (a looser tolerance can change the candidates and repairs
and come out slower); :func:`plan_fir_sweep` keeps, over a tolerance sweep, the fastest verified
plan of every tighter tolerance, which is (``_fir_candidates``).
"""

from __future__ import annotations

import warnings

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jax import Array

from research._device import device_array
from research.errors import ConvergenceError, ParameterError
from research.interpolators._fir_candidates import FIRSweep, envelope
from research.interpolators._fir_chain import check_delays
from research.interpolators._fir_feed import arc_feed_caps
from research.interpolators._fir_limits import LIMIT_RTOL, profile_peak_ratio, steps_within_limits
from research.interpolators import _fir_pauses
from research.interpolators._fir_settle import _primal, plan_blocks
from research.interpolators._fir_straight import (join_plan, merged_path, ramp_pieces, run_bounds, split_plan,
                                                  straight_runs)
from research.interpolators._fir_verify import (corner_distances, vertex_distances)
from research.limits import AxisLimits
from research.paths.gcode import checked_pauses
from research.paths.polyline import Polyline
from research.paths.toolpath import ToolPath
from research.piecewise import PiecewisePolynomial
from research.trajectory import Trajectory

CHECK_PERIOD = 1e-3  # default spacing [s] of the path-deviation check: the usual interpolation period
CORNER_SPEEDS = ("step", "turn")  # plan_fir's corner_speed values


class FIRPlan(eqx.Module):
    """The timing of every block and the exact filtered profile.

    Attributes:
        start_times: ``(M,)`` start of each block's velocity pulse [s].
        pulse_times: ``(M,)`` pulse lengths ``T_v,k = L_k / F_k`` [s] (eq 5).
        overlaps: ``(M - 1,)`` overlap ``T_k`` at each corner [s] (eq 11), ``0 <= T_k <= T_d``.
        feeds: ``(M,)`` planned feed per block [mm/s] (the commanded feed, or less where arcs,
            windows of short blocks or axis limits need it).
        delays: ``(n,)`` filter delays ``T_i`` [s].
        profile: the exact position profile [mm] (:attr:`position`) as a ``PiecewisePolynomial``, or
            the ``_fir_profile.ProfileInputs`` that build it on first use (a concrete plan: its
            timing and the path's pieces, a tenth or less of the profile's floats).
        corner_times: ``(M - 1,)`` time [s] at which the averaging window is centred on each
            corner's gap (the bisector point of eq 13/14).
        vertices: ``(M - 1, d)`` corner vertices [mm].
        path_deviation: largest distance [mm] from the checked trajectory samples to the path
            (NaN when the plan was not verified).
        rounds: verification rounds used (0 without refinement).
        axes: axis names.
    """

    start_times: Array
    pulse_times: Array
    overlaps: Array
    feeds: Array
    delays: Array
    profile: object
    corner_times: Array
    vertices: Array
    path_deviation: float = eqx.field(static=True)
    rounds: int = eqx.field(static=True)
    axes: tuple[str, ...] = eqx.field(static=True)

    @property
    def position(self) -> PiecewisePolynomial:
        """The exact position profile [mm] (built and kept on first use for a concrete plan)."""
        p = self.profile
        return p if isinstance(p, PiecewisePolynomial) else p.position()

    @property
    def cycle_time(self) -> Array:
        """Total motion time [s]: ``sum T_v + T_d + sum (T_d - T_k)``, plus the pauses of a paused plan."""
        p = self.profile
        return p.end - p.start if isinstance(p, PiecewisePolynomial) else p.span[1] - p.span[0]

    @property
    def corner_errors(self) -> Array:
        """``(M - 1,)`` distance [mm] from each corner vertex to the trajectory (exact profile,
        searched around :attr:`corner_times`; never optimistic). A concrete plan is searched by the
        planner's compiled kernel (``_fir_verify.vertex_distances``, each search run until it stops
        moving: at least as close as the planner's own check), a traced one by the JAX form
        (differentiable), which compiles once per profile size: planning many programs in one
        process and reading their corner errors cost 0.35 s and 5 MB of kept compilations a plan."""
        pos = self.position
        arrays = (pos.breaks, pos.coeffs, self.corner_times, self.delays, self.vertices)
        if any(isinstance(x, jax.core.Tracer) for x in arrays):
            return corner_distances(pos, self.vertices, self.corner_times, 0.5 * jnp.sum(self.delays))
        return device_array(vertex_distances(pos.numpy_evaluator(), np.asarray(self.vertices),
                                            np.asarray(self.corner_times), 0.5 * float(np.sum(self.delays)), 0.0))

    def trajectory(self, sample_period: float = 1e-3) -> Trajectory:
        """Sample the exact profile at the interpolation period ``Ts`` [s]."""
        if not (np.isfinite(sample_period) and sample_period > 0):
            raise ParameterError(f"sample_period must be finite and > 0 s, got {sample_period!r}")
        return Trajectory.from_piecewise(self.position, sample_period, self.axes)


def fir_interpolate(path, feed, delays, tolerance, sample_period: float = 1e-3, *, refine: bool = True) -> Trajectory:
    """FIR trajectory along ``path`` with every corner rounded within ``tolerance``.

    Args:
        path: :class:`Polyline` (G01 blocks) or :class:`ToolPath` (lines and arcs) [mm].
        feed: commanded feed ``F`` [mm/s], scalar or one per block.
        delays: FIR delays ``T_1 .. T_n`` [s] (any order; n >= 1).
        tolerance: cornering tolerance ``epsilon`` [mm], >= 0, scalar or one per block (a vertex
            takes the smaller of its two blocks'); 0 = exact stop at every corner.
        sample_period: interpolation period ``Ts`` [s].
        refine: look-ahead and verification (module docstring); ``False`` uses eq 13/14 alone.

    Returns:
        The sampled :class:`Trajectory`, with the exact profile attached.

    Example:
        >>> from research.paths import named_path
        >>> path = named_path("corner90")
        >>> tr = fir_interpolate(path, 250.0, [0.148, 0.089], 0.5)
        >>> bool(tr.duration >= float(path.arc_length[-1]) / 250.0 + 0.148 + 0.089)  # >= L/F + T_d (eq 11)
        True
    """
    return plan_fir(path, feed, delays, tolerance, refine=refine).trajectory(sample_period)


def plan_fir(path, feed, delays, tolerance, *, refine: bool = True, limits: AxisLimits | None = None,
             check_period: float = CHECK_PERIOD, pauses=None, corner_speed: str = "step") -> FIRPlan:
    """Feeds, overlap times, schedule and exact profile; see :func:`fir_interpolate` for the arguments.

    Args:
        limits: per-axis limits to hold as well (beyond the paper, see ``_fir_limits``): a block
            whose own exact peaks break them is slowed, and the overlap of any corner whose exact
            peaks break them is bisected, down to an exact stop if need be; a plan that holds them
            is returned unchanged. Where every velocity step of the path alone keeps them
            (``_fir_limits.steps_within_limits``, at the feeds the plan can run: arcs at their eq 8
            feed), the plan without limits is made first and returned as it is if its exact peaks
            keep them (the limit-holding search, 2-3x its planning time, is then not run); where
            that prediction fails, it is made after the search and returned if it keeps them and
            is faster, so the result is never slower than the plan without limits where that
            holds them; where it breaks them by a ratio ``r``, the same plan at its feeds over
            ``r`` is tried as well (at most :data:`SCALED_TRIES` times) while it can still be
            faster than the search's plan.
        check_period: spacing [s] of the trajectory samples whose distance to the path is checked
            (and bounded between them, ``_fir_certify``).
        pauses: ``(M + 1,)`` pause at each vertex [s] (index 0 the start, ``M`` the end; NaN: none),
            e.g. a G-code program's ``block_pauses`` (``G4 P`` dwells, ``M0``/``M1`` stops as 0 s):
            the motion stops there (``T_k = 0``) and holds the vertex that long (``_fir_pauses``);
            the cycle time includes the pauses. ``None``: no pauses.
        corner_speed: the speed change eq 13/14 rounds a corner between unequal feeds for
            (``_fir_overlap``, "Unequal feeds"; the same at equal feeds): ``"step"`` the velocity
            step ``|F+ u+ - F- u-|``; ``"turn"`` the smaller of it and the turn at the larger feed
            ``max(F-, F+) |u+ - u-|``, which leaves a straight feed step no corner (longer
            overlaps where the feeds step; ``plan_fir_mirror``'s timing). Both bound the corner's
            error. ``"step"`` is the default because this planner's eps ladder was measured with it:
            with ``"turn"`` 4 of 200 random programs rose along eps x 1-3 against 2
            (benchmarks/README.md).

    Differentiable with ``jax.grad`` / ``jax.jacfwd`` with respect to ``feed``, ``delays`` and
    ``tolerance``: the discrete choices (which corners dwell, which feeds a window lowers, which
    corners stop, whether straight runs merge and lines are cut into ramp steps) are made on the
    primal values and held fixed, so a traced call returns the traced form of the plan an untraced
    call returns (the same values). Held fixed as well: the feed factors the look-ahead and the
    limits set (relative to the commanded feed) and the ramp pieces' cut points, so under
    ``limits`` the derivative is that of the plan at fixed decisions, not of the limit-holding
    cycle time where a limit binds (there the planned feed does not follow the commanded one).
    Not under ``jax.jit`` with ``refine`` or ``limits``, which decide on concrete values.

    Raises:
        ParameterError: a bad feed, delay, tolerance or corner_speed (naming which), a tolerance of 0
            on an arc.
        ConvergenceError: the verification did not settle within ``_fir_settle.MAX_ROUNDS`` rounds.
    """
    tp = _as_toolpath(path)
    M = tp.n_blocks
    _check_inputs(delays, feed, tolerance, M, limits, tp.dim)
    if corner_speed not in CORNER_SPEEDS:
        raise ParameterError(f"corner_speed must be one of {CORNER_SPEEDS}, got {corner_speed!r}")
    turn = corner_speed == "turn"
    cut = paused_parts(tp, feed, tolerance, pauses, lambda part, f, t: plan_fir(
        part, f, delays, t, refine=refine, limits=limits, check_period=check_period, corner_speed=corner_speed))
    if cut is not None:
        return joined_plan(tp, *cut)
    traced = any(isinstance(x, jax.core.Tracer) for x in jax.tree_util.tree_leaves((delays, feed, tolerance)))
    xp = jnp if traced else np
    # the variants below are decided on primal values and built from the inputs as given, so a
    # traced call returns the traced form of the very plan an untraced call returns
    feeds_np = np.broadcast_to(np.asarray(_primal(feed), dtype=np.float64), (M,))
    tol_np = np.broadcast_to(np.asarray(_primal(tolerance), dtype=np.float64), (M,))
    delays_np = np.asarray(_primal(delays), dtype=np.float64).reshape(-1)
    if limits is not None:
        def without_limits(scale=1.0):
            """The plan without limits at ``scale`` times the feeds (primal values) and its largest
            exact peak over its limit."""
            p = plan_fir(tp, *((feeds_np * scale, delays_np, tol_np) if traced or scale != 1.0 else (feed, delays, tolerance)),
                         refine=refine, check_period=check_period, corner_speed=corner_speed)
            return p, profile_peak_ratio(p.position, limits)

        def returned(p, scale=1.0):  # the traced form of that plan, where the call is traced
            return plan_fir(tp, feed * scale, delays, tolerance, refine=refine, check_period=check_period,
                            corner_speed=corner_speed) if traced else p

        # every velocity step alone keeps the limits (the steps of the feeds the plan can run: an
        # arc no faster than its eq 8 feed): that plan is made first and returned if it keeps them
        steps_keep = steps_within_limits(tp, arc_feed_caps(tp.radii, delays_np, tol_np, feeds_np), *tp.tangents(),
                                         delays_np, limits)
        unlimited = without_limits() if steps_keep else None
        if unlimited is not None and unlimited[1] <= 1.0 + LIMIT_RTOL:
            return returned(unlimited[0])
    feeds_all = xp.broadcast_to(xp.asarray(feed, dtype=np.float64), (M,))
    tol_all = xp.broadcast_to(xp.asarray(tolerance, dtype=np.float64), (M,))
    run = straight_runs(tp, feeds_np, tol_np)  # runs of collinear line blocks planned as one block each (_fir_straight)
    if run is not None:
        first, _ = run_bounds(run)
        merged_tp = merged_path(tp, run)
        plan, pieces = _plan_blocks(merged_tp, _run_value(feeds_all, run, first), delays,
                                    _run_value(tol_all, run, first), refine, limits, check_period, traced, turn)
        merged = split_plan(plan, pieces[:2], pieces[2], tp, merged_tp, run, FIRPlan)
        if limits is None:
            return merged
    plans = [_plan_blocks(tp, feed, delays, tolerance, refine, limits, check_period, traced, turn)[0]]
    if limits is not None:
        # under limits the pieces of a line can be the steps of a staircase ramp
        # (_fir_limit_spread), which one block cannot take: the plans of the path as written,
        # with its straight runs as one block each, with its lines cut into ramp steps, and with
        # its arcs cut so as well are plans of this path alike; the fastest is returned (ties: in
        # that order). The arcs' ramps are a plan apart: in a chain of blocks in motion an arc
        # need not start from rest, and its ramp can cost more than it saves (3 of 150 stress
        # plans 4-6 % slower with one plan for both, benchmarks/README.md)
        if run is not None:
            plans.append(merged)
        for arcs in (False, True):
            cut = ramp_pieces(tp, run, feeds_np, delays_np, limits, arcs=arcs)
            if cut is None:
                continue
            pieces_tp, block, recipe = cut
            # a plan runs no piece faster than commanded and ends T_d after its input: a lower
            # bound on the cut plan's cycle, which the plans at hand may already meet (a chain
            # of chords that ramps through its own blocks: a circle in 4,000 chords)
            bound = float(np.sum(pieces_tp.lengths / recipe.of(feeds_np))) + float(np.sum(delays_np))
            if min(float(_primal(p.cycle_time)) for p in plans) > bound:
                try:
                    plan, _ = _plan_blocks(pieces_tp, recipe.of(feeds_all), delays, tol_all[block], refine, limits,
                                           check_period, traced, turn)
                except ConvergenceError as exc:  # another plan of the same path is at hand: this one is not
                    warnings.warn(f"plan_fir: the plan with its {'arcs' if arcs else 'lines'} cut into ramp steps "
                                  f"did not converge and is left out ({exc}); the fastest of the others is returned",
                                  RuntimeWarning, stacklevel=2)
                    continue
                plans.append(join_plan(plan, tp, block, FIRPlan))
        best = min(plans, key=lambda p: float(_primal(p.cycle_time)))
        T_best = float(_primal(best.cycle_time))
        # the step prediction is no proof either way (steps closer than T_d add or cancel): where it
        # failed, the plan without limits is made as well and kept where it holds them and is
        # faster. Where it breaks them by a ratio r, the same plan at its feeds over r (peaks grow
        # with the feed) is tried while that can still be faster (its cycle then about r times
        # the plan's), at most SCALED_TRIES times, each at the feeds over the last ratio
        plain, ratio = unlimited if unlimited is not None else without_limits()
        scale, candidate = 1.0, plain
        for _ in range(SCALED_TRIES + 1):
            if ratio <= 1.0 + LIMIT_RTOL:
                if float(candidate.cycle_time) < T_best:
                    return returned(candidate, scale)
                break
            if float(plain.cycle_time) * ratio * (1.0 / scale) >= T_best:
                break
            scale /= ratio
            candidate, ratio = without_limits(scale)
        return best
    return plans[0] if len(plans) == 1 else min(plans, key=lambda p: float(_primal(p.cycle_time)))


#: tries of the plan without limits at scaled feeds where it breaks the limits (``plan_fir``):
#: each at the feeds over the last exact peak ratio (peaks grow about as the feed); a bound on the
#: extra plans, not swept (on 150 random programs under 0.05-1x the envelope no try was faster than
#: the search, and planning rose 1.6 % per plan, median)
SCALED_TRIES = 3


def paused_parts(tp: ToolPath, feed, tolerance, pauses, plan_part):
    """A program cut at its pauses (``_fir_pauses``) and each part planned alone:
    ``(pauses, ranges, [plan_part(part, its feed, its tolerance), ...])`` with ``pauses`` checked
    ``(M + 1,)`` [s] and ``ranges`` the parts' block ranges; None when ``pauses`` holds no pause."""
    if pauses is None:
        return None
    M = tp.n_blocks
    pauses = checked_pauses(pauses, M)
    if np.all(np.isnan(pauses)):
        return None
    ranges = _fir_pauses.parts(pauses)
    return pauses, ranges, [plan_part(tp.part(a, b), _fir_pauses.per_block(feed, a, b, M),
                                      _fir_pauses.per_block(tolerance, a, b, M)) for a, b in ranges]


def joined_plan(tp: ToolPath, pauses: np.ndarray, ranges, plans) -> FIRPlan:
    """The :class:`FIRPlan` of the whole program from its parts' plans (:func:`paused_parts`). Its
    corners are the parts' own (a part planned on more blocks than programmed, as
    ``plan_fir_mirror``'s arcs as chords, brings its own vertices) with the vertex of each cut
    between them, in the order of ``_fir_pauses.join``'s corner instants."""
    starts, pulse, overlaps, feeds, position, centre, deviation, rounds = _fir_pauses.join(plans, ranges, pauses)
    vertices = [np.asarray(plans[0].vertices)]
    for plan, (first, _) in zip(plans[1:], ranges[1:]):
        vertices += [tp.ends[first - 1][None], np.asarray(plan.vertices)]
    return FIRPlan(starts, pulse, overlaps, feeds, plans[0].delays, position, centre,
                   device_array(np.concatenate(vertices).reshape(-1, tp.dim)), deviation, rounds, tp.axes)


def _run_value(x, run: np.ndarray, first: np.ndarray):
    """The value ``x`` ``(M,)`` of the first block of each run ``run`` ``(M,)`` (the blocks of a run
    share it). Traced, its derivative is spread evenly over the run's blocks (the run's mean minus
    its own primal), so that each block's commanded value gets its share of the merged block's
    sensitivity rather than the first block all of it."""
    if not isinstance(x, jax.core.Tracer):
        return x[first]
    n = int(run[-1]) + 1
    mean = jax.ops.segment_sum(x, jnp.asarray(run), num_segments=n) / np.bincount(run, minlength=n)
    return jax.lax.stop_gradient(x[first]) + (mean - jax.lax.stop_gradient(mean))


def _plan_blocks(tp: ToolPath, feed, delays, tolerance, refine: bool, limits, check_period: float,
                 traced: bool, turn: bool):
    """``(FIRPlan, (fraction, piece_tv, first_motion))`` of ``_fir_settle.plan_blocks`` (a path
    without pauses)."""
    fields, pieces = plan_blocks(tp, feed, delays, tolerance, refine, limits, check_period, traced, turn)
    return FIRPlan(*fields), pieces


def plan_fir_sweep(path, feed, delays, tolerances, *, limits: AxisLimits | None = None,
                   check_period: float = CHECK_PERIOD, pauses=None) -> FIRSweep:
    """Verified plans over a tolerance sweep whose cycle time never increases with the tolerance.

    Each tolerance is planned by :func:`plan_fir` (``refine=True``); the plan kept at
    ``tolerances[j]`` is the fastest of the verified plans of every ``tolerances[i] <=
    tolerances[j]`` (componentwise for per-block tolerances). A plan verified within a tolerance is
    within every larger one, so the cycle time is non-increasing along the sweep by construction
    (``_fir_candidates``), exactly, at the cost of planning each tolerance once.

    Args:
        path, feed, delays, limits, check_period, pauses: as :func:`plan_fir`.
        tolerances: ``K >= 1`` cornering tolerances [mm], each a scalar or one per block, any order.

    Returns:
        :class:`FIRSweep` with ``plans[j]``, ``planned_at[j]`` (the tolerance index it was planned
        at), ``cycle_times`` and ``own_cycle_times`` (each tolerance's own plan). Gradients with respect to ``tolerances[j]`` are those of the plan
        kept (zero when it was planned at a tighter tolerance).
    """
    tols = tuple(tolerances)
    if not tols:
        raise ParameterError("plan_fir_sweep needs at least one tolerance, got none")
    M = _as_toolpath(path).n_blocks
    plans = [plan_fir(path, feed, delays, t, limits=limits, check_period=check_period, pauses=pauses) for t in tols]
    vectors = [np.broadcast_to(np.asarray(_primal(t), dtype=np.float64), (M,)) for t in tols]
    own = tuple(float(_primal(p.cycle_time)) for p in plans)
    pick = envelope(vectors, own)
    return FIRSweep(tols, tuple(plans[i] for i in pick), pick, own)


def _as_toolpath(path) -> ToolPath:
    if isinstance(path, ToolPath):
        return path
    if isinstance(path, Polyline):
        cache = path._tree  # Polyline's private cache dict: one ToolPath per polyline
        if "toolpath" not in cache:
            cache["toolpath"] = ToolPath.from_polyline(path)
        return cache["toolpath"]
    raise ParameterError(f"path must be a Polyline or a ToolPath, got {type(path).__name__}")


def _check_inputs(delays, feed, tolerance, n_blocks: int, limits=None, dim: int | None = None) -> None:
    """Domain checks on the primal values (and, given ``limits``, one limit per axis of the path's
    ``dim`` axes)."""
    if limits is not None and limits.n_axes != dim:
        raise ParameterError(f"limits have {limits.n_axes} axes but the path has {dim}")
    delays, feed, tolerance = (_primal(x) for x in (delays, feed, tolerance))
    check_delays(delays)
    f = np.asarray(feed, dtype=np.float64)
    if f.ndim > 1 or (f.ndim == 1 and f.shape[0] != n_blocks):
        raise ParameterError(f"feed must be a scalar or one value per segment ({n_blocks}), got shape {f.shape}")
    bad = ~(np.isfinite(f) & (f > 0))
    if bad.any():
        where = "" if f.ndim == 0 else f" on segment {int(np.argmax(bad))}"
        raise ParameterError(f"feed F must be finite and > 0 mm/s{where}, got {np.ravel(f)[np.argmax(np.ravel(bad))]!r}")
    tol = np.asarray(tolerance, dtype=np.float64)
    if tol.ndim > 1 or (tol.ndim == 1 and tol.shape[0] != n_blocks) or not np.all(np.isfinite(tol) & (tol >= 0)):
        raise ParameterError(f"cornering tolerance epsilon must be a finite scalar >= 0 mm (or one per block, "
                             f"{n_blocks}), got {tolerance!r}")
