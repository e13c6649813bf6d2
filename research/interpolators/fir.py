"""FIR-filter trajectory generation with tolerance-bounded corner overlap (Sencer 2015).

Data flow, one G01 segment ``k`` at a time (Sencer, Ishizaki, Shamoto, CIRP Annals 64, 2015):

1. Each segment becomes a rectangular axis-velocity pulse ``F_k u_k`` of length
   ``T_v,k = L_k / F_k`` (eq 5).
2. The pulse train goes through a chain of n moving-average filters with delays ``T_i``
   (eq 1-6), which makes velocity trapezoidal (n = 1), jerk-limited (n = 2), ...
3. Segment ``k + 1`` starts ``T_d - T_k`` after segment ``k``'s pulse ends: ``T_k = 0`` is an exact
   stop, ``T_k = T_d`` full overlap (eq 11). ``T_k`` comes from the cornering tolerance (eq 13/14,
   :func:`overlap_time`).
4. The filtered profile is piecewise polynomial, so it is built exactly (``PiecewisePolynomial``)
   in O(segments * 2^n), and sampled at ``Ts`` in O(samples): no convolution, no rounding of
   ``T_i`` to the sample grid. Cycle time and corner errors are smooth in ``T_i`` and ``jax.grad``
   goes through them.

Short segments (beyond the paper, which assumes ``T_v > T_d``): when a segment is shorter than
the averaging window, the windows of neighbouring corners overlap and eq 13/14 no longer bound the
error. Rule used here ("verified overlap"): start from eq 13/14, compute every corner's exact
error on the actual profile (distance from the vertex to the trajectory, local search around the
bisector time), shrink each violating overlap by ``(eps / error)^(1/(n+1))`` (the small-overlap
scaling of ``H2``) for a few rounds, then set any corner still violating to an exact stop. An exact
stop puts the corner vertex on the trajectory whatever the neighbours do, so the loop ends, and
every corner holds its tolerance. Feed is never changed.
"""

from __future__ import annotations

from functools import partial

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jax import Array

from research.errors import ParameterError
from research.interpolators._fir_chain import check_delays
from research.interpolators._fir_limits import corner_peak_ratios, feed_caps
from research.interpolators._fir_overlap import overlap_time
from research.limits import AxisLimits
from research.paths.polyline import Polyline
from research.piecewise import PiecewisePolynomial, bucket_size
from research.trajectory import Trajectory

_SCALING_ROUNDS = 6  # refinement rounds that shrink overlaps before violators are set to exact stops
_LIMIT_ROUNDS = 16  # the same for corners that break axis limits
_GRID = 9  # grid points per corner window for the corner-error search
_NEWTON_STEPS = 4


class FIRPlan(eqx.Module):
    """The timing of every block and the exact filtered profile.

    Attributes:
        start_times: ``(M,)`` start of each segment's velocity pulse [s].
        pulse_times: ``(M,)`` pulse lengths ``T_v,k = L_k / F_k`` [s] (eq 5).
        overlaps: ``(M - 1,)`` overlap ``T_k`` at each corner [s] (eq 11), ``0 <= T_k <= T_d``.
        feeds: ``(M,)`` commanded feed per segment [mm/s].
        delays: ``(n,)`` filter delays ``T_i`` [s].
        position: exact position profile [mm].
        corner_times: ``(M - 1,)`` time [s] at which the averaging window is centred on each
            corner's gap (the bisector point of eq 13/14).
        vertices: ``(M - 1, d)`` corner vertices [mm].
        axes: axis names.
    """

    start_times: Array
    pulse_times: Array
    overlaps: Array
    feeds: Array
    delays: Array
    position: PiecewisePolynomial
    corner_times: Array
    vertices: Array
    axes: tuple[str, ...] = eqx.field(static=True)

    @property
    def cycle_time(self) -> Array:
        """Total motion time [s]: ``sum T_v + T_d + sum (T_d - T_k)``."""
        return self.position.end - self.position.start

    @property
    def corner_errors(self) -> Array:
        """``(M - 1,)`` distance [mm] from each corner vertex to the trajectory (exact profile,
        searched around :attr:`corner_times`; never optimistic)."""
        C = self.vertices.shape[0]
        pad = bucket_size(C) - C
        centre = jnp.concatenate([self.corner_times, jnp.zeros(pad)])
        vertices = jnp.concatenate([self.vertices, jnp.zeros((pad, self.vertices.shape[1]))])
        real = jnp.arange(C + pad) < C
        return _corner_errors(self.position, vertices, centre, 0.5 * jnp.sum(self.delays), real)[:C]

    def trajectory(self, sample_period: float = 1e-3) -> Trajectory:
        """Sample the exact profile at the interpolation period ``Ts`` [s]."""
        if not (np.isfinite(sample_period) and sample_period > 0):
            raise ParameterError(f"sample_period must be finite and > 0 s, got {sample_period!r}")
        return Trajectory.from_piecewise(self.position, sample_period, self.axes)


def fir_interpolate(
    path: Polyline, feed, delays, tolerance: float, sample_period: float = 1e-3, *, refine: bool = True
) -> Trajectory:
    """FIR trajectory along ``path`` with every corner rounded within ``tolerance``.

    Args:
        path: G01 tool path [mm].
        feed: commanded feed ``F`` [mm/s], scalar or one per segment.
        delays: FIR delays ``T_1 .. T_n`` [s] (any order; n >= 1).
        tolerance: cornering tolerance ``epsilon`` [mm], >= 0 (0 = exact stop at every corner).
        sample_period: interpolation period ``Ts`` [s].
        refine: apply the short-segment rule (module docstring); ``False`` uses eq 13/14 alone.

    Returns:
        The sampled :class:`Trajectory`, with the exact profile attached.

    Example:
        >>> from research.paths import named_path
        >>> tr = fir_interpolate(named_path("corner90"), 250.0, [0.148, 0.089], 0.5)
        >>> round(float(tr.duration), 4)
        0.7777
    """
    return plan_fir(path, feed, delays, tolerance, refine=refine).trajectory(sample_period)


def plan_fir(path: Polyline, feed, delays, tolerance, *, refine: bool = True, limits: AxisLimits | None = None) -> FIRPlan:
    """Overlap times, schedule and exact profile; see :func:`fir_interpolate` for the arguments.

    Args:
        limits: per-axis limits to hold as well (beyond the paper, see ``_fir_limits``): each
            block's feed is capped so that it keeps them alone, and the overlap of any corner whose
            exact peaks break them is shrunk, down to an exact stop if need be.

    Differentiable with ``jax.grad`` with respect to ``feed``, ``delays`` and ``tolerance`` (not
    under ``jax.jit`` when ``refine`` is on: the refinement loop stops on concrete values; not
    with ``limits``, whose peaks are found in NumPy).
    """
    if not isinstance(path, Polyline):
        raise ParameterError(f"path must be a Polyline, got {type(path).__name__}")
    _check_concrete(delays, feed, tolerance, path.n_segments)
    M = path.n_segments
    pad = bucket_size(M) - M  # similar paths share compiled code
    delays = jnp.asarray(delays, dtype=jnp.float64).reshape(-1)
    feeds = jnp.broadcast_to(jnp.asarray(feed, dtype=jnp.float64), (M,))
    if limits is not None:
        if limits.n_axes != path.dim:
            raise ParameterError(f"limits have {limits.n_axes} axes but the path has {path.dim}")
        feeds = jnp.minimum(feeds, feed_caps(path.lengths, path.directions, np.asarray(delays), limits))
    tolerance = jnp.asarray(tolerance, dtype=jnp.float64)
    # padding segments have zero length and full overlap: they add neither motion nor time
    points = jnp.concatenate([jnp.asarray(path.points), jnp.repeat(jnp.asarray(path.points[-1:]), pad, axis=0)])
    u = jnp.concatenate([jnp.asarray(path.directions), jnp.zeros((pad, path.dim))])
    feeds_p = jnp.concatenate([feeds, jnp.ones(pad)])
    pulse_times = jnp.concatenate([jnp.asarray(path.lengths), jnp.zeros(pad)]) / feeds_p
    real = jnp.arange(M + pad - 1) < M - 1

    vertices = points[1:-1]
    half_window = 0.5 * jnp.sum(delays)
    overlaps = _initial_overlaps(u, feeds_p, delays, tolerance, real)
    starts, position, centre = _build(points, u, feeds_p, pulse_times, delays, overlaps)
    if (refine or limits is not None) and M > 1:
        limit = tolerance * (1.0 + 1e-9) + 1e-9  # 1 pm absolute slack for rounding
        for round_ in range(_LIMIT_ROUNDS + M):
            errors = _corner_errors(position, vertices, centre, half_window, real) if refine else jnp.zeros(M + pad - 1)
            too_fast = _limit_violations(position, starts, pulse_times, delays, limits, M, pad)
            if not (bool(jnp.any(errors > limit)) or too_fast.any()):
                break
            overlaps = _refine_overlaps(overlaps, errors, tolerance, limit, delays.shape[0], round_ < _SCALING_ROUNDS)
            if too_fast.any():  # shrink by 15 % a round, then exact stops
                overlaps = jnp.where(too_fast, overlaps * (0.85 if round_ < _LIMIT_ROUNDS else 0.0), overlaps)
            starts, position, centre = _build(points, u, feeds_p, pulse_times, delays, overlaps)
    return FIRPlan(
        starts[:M], pulse_times[:M], overlaps[: M - 1], feeds, delays, position, centre[: M - 1],
        jnp.asarray(path.corners), path.axes,
    )


def _limit_violations(position, starts, pulse_times, delays, limits, M: int, pad: int) -> np.ndarray:
    """Corners (padded length) whose window ``[end of block k, start of block k+1 + T_d]`` holds a
    velocity, acceleration or jerk above ``limits``."""
    flags = np.zeros(M + pad - 1, dtype=bool)
    if limits is None:
        return flags
    s, e = np.asarray(starts)[:M], np.asarray(starts + pulse_times)[:M]
    ratios = corner_peak_ratios(position, e[:-1], s[1:] + float(jnp.sum(delays)), limits)
    flags[: M - 1] = ratios > 1.0 + 1e-9
    return flags


@jax.jit
def _initial_overlaps(u, feeds, delays, tolerance, real):
    """Eq 13/14 overlap per corner from ``|F+ u+ - F- u-|``; padding corners get full overlap."""
    speed_change = _safe_norm(feeds[1:, None] * u[1:] - feeds[:-1, None] * u[:-1])
    return jnp.where(real, overlap_time(tolerance, speed_change, delays), jnp.sum(delays))


@partial(jax.jit, static_argnums=(4, 5))
def _refine_overlaps(overlaps, errors, tolerance, limit, n_filters: int, scale: bool):
    """One round of the short-segment rule: shrink (or, late, zero) every violating overlap."""
    violated = errors > limit
    if not scale:
        return jnp.where(violated, 0.0, overlaps)
    ratio = tolerance / jnp.where(violated, errors, 1.0)
    shrink = jnp.clip(0.98 * ratio ** (1.0 / (n_filters + 1)), 0.0, 1.0)
    return jnp.where(violated, overlaps * shrink, overlaps)


@jax.jit
def _build(points, u, feeds, pulse_times, delays, overlaps):
    """Schedule the pulses and filter them exactly; also returns each corner's bisector time."""
    Td = jnp.sum(delays)
    gaps = Td - overlaps
    starts = jnp.concatenate([jnp.zeros(1), jnp.cumsum(pulse_times[:-1] + gaps)])
    ends = starts + pulse_times
    # break points s_0, s_0 + T_v0, s_1, ...; cummax removes 1-ulp inversions when a gap is 0
    breaks = jax.lax.cummax(jnp.stack([starts, ends], axis=1).reshape(-1))
    values = jnp.zeros((breaks.shape[0] - 1, u.shape[1])).at[0::2].set(feeds[:, None] * u)
    velocity = PiecewisePolynomial.from_steps(breaks, values)
    for i in range(delays.shape[0]):
        velocity = velocity.moving_average(delays[i])
    position = velocity.antiderivative(points[0])
    # the bisector point of corner k: averaging window centred on the gap after pulse k
    centre = ends[:-1] + 0.5 * gaps + 0.5 * Td
    return starts, position, centre


@jax.jit
def _corner_errors(position, vertices, centre, half_window, real):
    """:func:`corner_distances` on padded corners; 0 on the padding."""
    return jnp.where(real, corner_distances(position, vertices, centre, half_window), 0.0)


def corner_distances(position: PiecewisePolynomial, vertices: Array, centre: Array, half_window: Array) -> Array:
    """Distance from each vertex to the profile, searched in ``centre +- half_window`` [s].

    A grid of 9 points finds the basin; safeguarded Newton steps on ``|p(t) - V|^2`` (exact
    derivatives of the profile) refine it. Any point of the trajectory gives an upper bound on the
    true distance, so the result is never optimistic.
    """
    if vertices.shape[0] == 0:
        return jnp.zeros(0)
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
        curvature = jnp.sum(v * v, axis=1) + jnp.sum(e * a, axis=1)
        t_new = jnp.where(curvature > 0, t - slope / jnp.where(curvature > 0, curvature, 1.0), t)
        return jnp.clip(t_new, lo, hi)

    t = jax.lax.fori_loop(0, _NEWTON_STEPS, newton, t)
    squared = jnp.minimum(jnp.sum((position(t) - vertices) ** 2, axis=1), jnp.min(d2, axis=1))
    positive = squared > 0
    return jnp.where(positive, jnp.sqrt(jnp.where(positive, squared, 1.0)), 0.0)


def _safe_norm(x: Array) -> Array:
    """Euclidean norm along the last axis with a finite gradient at 0."""
    s = jnp.sum(x * x, axis=-1)
    positive = s > 0
    return jnp.where(positive, jnp.sqrt(jnp.where(positive, s, 1.0)), 0.0)


def _check_concrete(delays, feed, tolerance, n_segments: int) -> None:
    """Domain checks on concrete inputs (skipped for JAX tracers)."""
    if any(isinstance(x, jax.core.Tracer) for x in (delays, feed, tolerance)):
        return
    check_delays(delays)
    f = np.asarray(feed, dtype=np.float64)
    if f.ndim > 1 or (f.ndim == 1 and f.shape[0] != n_segments):
        raise ParameterError(f"feed must be a scalar or one value per segment ({n_segments}), got shape {f.shape}")
    bad = ~(np.isfinite(f) & (f > 0))
    if bad.any():
        where = "" if f.ndim == 0 else f" on segment {int(np.argmax(bad))}"
        raise ParameterError(f"feed F must be finite and > 0 mm/s{where}, got {np.ravel(f)[np.argmax(np.ravel(bad))]!r}")
    tol = np.asarray(tolerance, dtype=np.float64)
    if tol.ndim != 0 or not (np.isfinite(tol) and tol >= 0):
        raise ParameterError(f"cornering tolerance epsilon must be a finite scalar >= 0 mm, got {tolerance!r}")


def fir_by_convolution(plan: FIRPlan, path: Polyline, sample_period: float) -> tuple[np.ndarray, np.ndarray]:
    """Straightforward discrete implementation of the same schedule, as a reference.

    The unfiltered pulse train is sampled as exact cell averages over ``[i Ts, (i+1) Ts)``; each
    filter is an ``np.convolve`` with the ``m + 1`` taps ``[1/2, 1, ..., 1, 1/2] / m``,
    ``m = T_i / Ts`` (the moving average acting on cell averages: exact for cell-wise constant
    input, delay ``T_i / 2``); positions are the cumulative sum. Accurate to O(Ts^2) at the grid
    points when every ``T_i`` is a multiple of ``Ts``; costs O(samples * sum T_i / Ts).

    Returns:
        ``(t, q)``: grid times [s] and positions ``(N, d)`` [mm].
    """
    taps = np.asarray(plan.delays) / sample_period
    if not np.allclose(taps, np.round(taps), rtol=0, atol=1e-6):
        raise ParameterError(f"fir_by_convolution needs delays that are multiples of Ts = {sample_period} s")
    taps = np.round(taps).astype(int)
    starts = np.asarray(plan.start_times)
    ends = starts + np.asarray(plan.pulse_times)
    knots = np.stack([starts, ends], axis=1).reshape(-1)
    knot_pos = np.repeat(path.points, 2, axis=0)[1:-1]  # P0, P1, P1, P2, ..., PM
    n = int(np.ceil(ends[-1] / sample_period)) + 1
    grid = np.arange(n + 1) * sample_period
    unfiltered = np.column_stack([np.interp(grid, knots, knot_pos[:, k]) for k in range(path.dim)])
    velocity = np.diff(unfiltered, axis=0) / sample_period  # cell averages
    for m in taps:
        kernel = np.full(m + 1, 1.0 / m)
        kernel[[0, -1]] *= 0.5
        velocity = np.column_stack([np.convolve(velocity[:, k], kernel) for k in range(path.dim)])
    q = path.points[0] + np.vstack([np.zeros((1, path.dim)), np.cumsum(velocity, axis=0) * sample_period])
    return np.arange(q.shape[0]) * sample_period, q
