"""Sigmoid and exponential interpolators for modulated tool path (MTP) machining (DiMarco 2015).

The nominal motion of the part program is multiplied by blending functions that rise smoothly
from 0 to 1 (DiMarco, Ziegert, Vermillion, J. Manuf. Syst. 2015, §2):

* startup, linear component (eq 1-5): ``x_L = (m t + b) (1 - exp(-alpha t^3))``;
* startup, sinusoidal component (eq 6-7): ``A sin(w t) (1 - exp(-alpha t^2))``;
* MTP: their sum, the oscillation running along the feed direction.

The paper's text ends after eq 7; the rest is designed here in its spirit:

* Every change of nominal motion at ``t_k`` (new feed, or stop) adds the term
  ``(x_new - x_old)(t) S(t - t_k)`` with ``S(tau) = 1 - exp(-alpha tau^3)``: position, velocity and
  acceleration stay continuous because ``S = S' = S'' = 0`` at ``tau = 0``. The motion is
  ``x = sum_k c_k(t) S_k(t - t_k)``, each ``c_k`` a ramp, a hold or a sinusoid.
* A stop blends the moving nominal into a hold at the end point. Because ``exp(-alpha tau^3)``
  never reaches 0, a blend that starts when the nominal arrives would overshoot the end point by
  ``m (3 alpha)^(-1/3) e^(-1/3)``; the stop therefore starts ``delta`` earlier, with ``delta`` the
  smallest lead that keeps the overshoot below ``overshoot_tol`` (bisection). The move has ended
  (cycle time) when it stays within ``settle_tol`` of the end point.
* The exponential interpolator of Rymansaib, as the paper reviews it, is the same construction
  with a first-order exponent, ``S = 1 - exp(-alpha t)``. What each order gives at ``t = 0`` for
  ``x = (m t + b) S`` (Taylor expansion of ``S``; tested): order 1: ``v(0) = b alpha``,
  ``a(0) = 2 m alpha - b alpha^2``; order 2: ``v(0) = 0``, ``a(0) = 2 b alpha``, ``j(0) = 6 m alpha``;
  order 3: ``v(0) = a(0) = 0``, ``j(0) = 6 b alpha``. So the paper's "order ... chosen as 3 to
  maintain a zero value at t = 0 for acceleration" (§2.1) is needed only for an offset ``b != 0``:
  with ``b = 0`` order 2 already starts with ``a(0) = 0`` (but with a jerk step ``6 m alpha``),
  and order 3 with ``b = 0`` starts without a jerk step as well. ``order=1`` gives the exponential
  interpolator; the ramps here have ``b = 0``.
* ``alpha``: found by bisection on ``log alpha`` for the boundary between candidates whose peak
  |acceleration| (and |jerk| when a limit is given) stays within the limits on a dense grid and
  candidates that break them; a motion whose steady part already breaks a limit (``A w^2 > a_max``)
  cannot be fixed by any ``alpha`` and is refused. Maximality: for a plain move (``A = 0``) the
  startup peaks scale as ``m alpha^(1/3)`` (acceleration) and ``m alpha^(2/3)`` (jerk) (substitute
  ``u = alpha^(1/3) t`` in eq 3), so they grow strictly with ``alpha`` and the boundary is the
  largest feasible ``alpha`` up to the stop blend; with an oscillation the peaks are not monotone
  in ``alpha`` in general and the returned value is the bisection boundary only (the tests check
  that sampled larger values break a limit, not that none can pass). For a plain move the search
  starts from the decade of the closed form where that keeps the limits with room to stop, and
  each bisection's result is found on the bisection's own grid by secant-guided probes
  (:func:`bisection_on_grid`: the same alphas where the predicate holds below one alpha only):
  a 0.5 mm chord at 200 mm/s took 65 builds, now about 10. Peaks on the search's grid, which is
  not equally spaced, are refined by the exact value at the vertex of the parabola through the
  top three samples (:func:`grid_peak`).
* A blending baseline for the MTP comparison (:func:`mtp_blending_baseline`): the same 16 G01
  moves per period, linearly interpolated at their nominal feeds without stopping, then smoothed
  by acceleration/deceleration after interpolation (two moving averages, Chen and Lee 1998, the
  usual CNC practice the FIR interpolator of Sencer 2015 builds on), whose lengths are the
  shortest that keep the acceleration and jerk limits.

Branch conditions, counted in this code (the paper claims about 17 for a linear interpolator and
4 for the sigmoid): evaluating a sigmoid motion takes one test per term (``t >= t_k``, 4 terms for
an MTP move); the S-curve baseline (:mod:`research.interpolators.scurve`) takes 3 case tests to
plan a block and selects one of 7 jerk phases per sample. :data:`BRANCH_COUNTS` records them.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from research.errors import InfeasibleProblem, ParameterError
from research.interpolators._sigmoid_search import bisection_on_grid, decade_bracket, grid_peak
from research.trajectory import Trajectory

#: max |exp(-u^3) (12 u^2 - 9 u^5)|: peak startup acceleration is m alpha^(1/3) times this (eq 5, b = 0)
_EQ5_PEAK = 3.1003

#: Branch conditions per implementation, counted by hand in this package's code (see module doc).
BRANCH_COUNTS = {
    "sigmoid MTP move: evaluation (one t >= t_k test per blend term)": 4,
    "S-curve block: planning case tests (A reached, V reached, A reached when V is not)": 3,
    "S-curve block: jerk phases selected per sample": 7,
}


@dataclass(frozen=True)
class Ramp:
    """Nominal linear motion ``x = m t + b`` (eq 1) [mm, mm/s]."""

    m: float
    b: float = 0.0

    def derivatives(self, t: np.ndarray) -> list[np.ndarray]:
        return [self.m * t + self.b, np.full_like(t, self.m), np.zeros_like(t), np.zeros_like(t)]


@dataclass(frozen=True)
class Sine:
    """Nominal oscillation ``x = A sin(w t)`` (eq 6) [mm, rad/s]."""

    amplitude: float
    omega: float

    def __post_init__(self):
        if not (np.isfinite(self.amplitude) and self.amplitude != 0):
            raise ParameterError(f"oscillation amplitude A must be finite and non-zero mm, got {self.amplitude!r}")
        if not (np.isfinite(self.omega) and self.omega > 0):
            raise ParameterError(f"oscillation frequency w must be finite and > 0 rad/s, got {self.omega!r}")

    def derivatives(self, t: np.ndarray) -> list[np.ndarray]:
        s, c = np.sin(self.omega * t), np.cos(self.omega * t)
        A, w = self.amplitude, self.omega
        return [A * s, A * w * c, -A * w**2 * s, -A * w**3 * c]


@dataclass(frozen=True)
class Blend:
    """``S(tau) = 1 - exp(-alpha tau^order)`` for ``tau = t - start >= 0``, else 0 (eq 2, eq 7)."""

    alpha: float
    order: int = 3
    start: float = 0.0

    def __post_init__(self):
        if not (np.isfinite(self.alpha) and self.alpha > 0):
            raise ParameterError(f"blend time constant alpha must be finite and > 0, got {self.alpha!r}")

    def derivatives(self, t: np.ndarray, orders: int = 4) -> list[np.ndarray]:
        """``S, S', S'', S'''`` at ``t`` (exact; Faa di Bruno on ``exp(-g)``, ``g = alpha tau^p``): the
        first ``orders`` of them."""
        on = t >= self.start
        tau = np.where(on, t - self.start, 0.0)
        p = self.order
        g = [self.alpha * math.perm(p, i) * tau ** (p - i) if i <= p else np.zeros_like(tau) for i in range(orders)]
        E = np.exp(-g[0])
        out = [lambda: 1.0 - E, lambda: g[1] * E, lambda: (g[2] - g[1] ** 2) * E,
               lambda: (g[3] - 3 * g[1] * g[2] + g[1] ** 3) * E]
        return [np.where(on, x(), 0.0) for x in out[:orders]]


@dataclass(frozen=True)
class SigmoidMotion:
    """``x(t) = sum_k c_k(t) S_k(t)`` along a straight move: exact evaluation at any time.

    Attributes:
        terms: ``(component, blend)`` pairs; ``blend`` ``None`` means always on.
        duration: time at which the motion has settled [s].
        nominal: the part program's motion (for tracking error), same components without blends.
        order: exponent of the ramp blends (3 sigmoid, 1 exponential).
        stop_time: start of the stop blend [s].
    """

    terms: tuple
    duration: float
    nominal: tuple = field(default=())
    order: int = 3
    stop_time: float = 0.0

    def derivatives(self, t, orders: int = 4) -> np.ndarray:
        """Position and its first three derivatives at ``t``: shape ``(4,) + t.shape`` (the first
        ``orders`` of them: ``(orders,) + t.shape``, the position alone for a search on it)."""
        t = np.asarray(t, dtype=np.float64)
        total = np.zeros((orders,) + t.shape)
        for component, blend in self.terms:
            c = component.derivatives(t)
            if blend is None:
                total += np.stack(c[:orders])
                continue
            S = blend.derivatives(t, orders)
            for k in range(orders):  # Leibniz: (c S)^(k) = sum_i C(k, i) c^(i) S^(k - i)
                total[k] += sum(math.comb(k, i) * c[i] * S[k - i] for i in range(k + 1))
        return total

    def nominal_position(self, t) -> np.ndarray:
        """The part program's motion (ramp + oscillation, then hold) at ``t`` [mm]."""
        t = np.asarray(t, dtype=np.float64)
        return sum(component.derivatives(t)[0] for component in self.nominal) if self.nominal else np.zeros_like(t)


def velocity_transition(feed_old: float, feed_new: float, at: float, alpha: float, order: int = 3) -> tuple:
    """The blend term that moves a ramp of slope ``feed_old`` onto the ramp of slope ``feed_new``
    through the same point at time ``at`` [s]: ``(m_new - m_old)(t - at) S(t - at)``.

    Added to a motion's terms it keeps position, velocity and acceleration continuous at ``at``
    (``S = S' = S'' = 0`` there) and, as ``(x_new - x_old)(at) = 0``, jerk too when ``order = 3``.
    """
    dm = feed_new - feed_old
    return (Ramp(dm, -dm * at), Blend(alpha, order, at))


def mtp_motion(
    length: float,
    feed: float,
    amplitude: float = 0.0,
    frequency: float = 0.0,
    *,
    acceleration: float,
    jerk: float | None = None,
    order: int = 3,
    overshoot_tol: float = 1e-4,
    settle_tol: float = 1e-4,
) -> SigmoidMotion:
    """One MTP move along a line: ramp ``m t`` plus ``A sin(w t)``, from rest to rest.

    Args:
        length: move length ``L`` [mm], > 0.
        feed: nominal feed ``m`` [mm/s], > 0.
        amplitude: oscillation amplitude ``A`` [mm], >= 0 (0: plain move; > 0 needs ``frequency``).
        frequency: oscillation frequency [Hz] (``w = 2 pi f``).
        acceleration: limit ``a_max`` [mm/s^2]; ``jerk``: optional limit [mm/s^3].
        order: exponent of the startup blend (3: sigmoid, eq 2; 1: exponential interpolator).
        overshoot_tol: allowed overshoot past the end point [mm]; ``settle_tol``: band that ends
            the move [mm].

    Returns:
        The :class:`SigmoidMotion` at the bisection boundary of ``alpha`` between candidates that
        keep the limits and candidates that break them (the largest feasible ``alpha`` when
        ``A = 0``; module docstring).

    Raises:
        ParameterError: ``L``, ``m``, ``a_max`` not > 0, ``A < 0``, ``A > 0`` with frequency <= 0.
        InfeasibleProblem: no ``alpha`` meets the limits (e.g. ``A w^2 >= a_max``).
    """
    _check(length=length, feed=feed, acceleration=acceleration)
    if jerk is not None:
        _check(jerk=jerk)
    if not (np.isfinite(amplitude) and amplitude >= 0):
        raise ParameterError(f"MTP amplitude A must be >= 0 mm, got {amplitude!r}")
    if amplitude > 0 and not (np.isfinite(frequency) and frequency > 0):
        raise ParameterError(f"MTP frequency must be > 0 Hz when A > 0, got {frequency!r}")
    if order not in (1, 2, 3):
        raise ParameterError(f"blend order must be 1 (exponential), 2 or 3 (sigmoid), got {order!r}")
    omega = 2 * np.pi * frequency
    steady_a, steady_j = amplitude * omega**2, amplitude * omega**3
    if steady_a >= acceleration or (jerk is not None and steady_j >= jerk):
        raise InfeasibleProblem(
            f"the steady oscillation alone needs |a| = A w^2 = {steady_a:.4g} mm/s^2 and |j| = A w^3 = "
            f"{steady_j:.4g} mm/s^3, at or above the limits a_max = {acceleration:g}, j_max = {jerk}; "
            "no alpha can meet them: lower A or the frequency"
        )

    built, peaks = {}, {}

    def build(alpha):  # (the searches below ask some alphas twice)
        if alpha not in built:
            built[alpha] = _build(length, feed, amplitude, omega, alpha, order, overshoot_tol, settle_tol)
        return built[alpha]

    def has_room(alpha):  # the stop must not start before the move does
        return build(alpha).stop_time >= 0

    def peak_ratio(alpha):
        """``(within the limits, largest peak / limit)`` of the motion at ``alpha``."""
        if alpha not in peaks:
            motion = build(alpha)
            grid = _grid(motion, alpha, omega)
            _, _, a, j = motion.derivatives(grid)
            margin = 1.0 + 1e-6  # peaks between grid points: keep 1e-6 in hand
            pa = grid_peak(motion, grid, np.abs(a), 2)
            pj = None if jerk is None else grid_peak(motion, grid, np.abs(j), 3)
            ok = pa * margin <= acceleration and (jerk is None or pj * margin <= jerk)
            peaks[alpha] = ok, max(pa * margin / acceleration, 0.0 if jerk is None else pj * margin / jerk)
        return peaks[alpha]

    def within_limits(alpha):
        return peak_ratio(alpha)[0]

    # Larger alpha: faster blends, higher peaks; smaller alpha: longer blends, and below some
    # alpha_room the stop no longer fits in the move. Start near the closed form for a startup
    # ramp (peak |a| = 3.1003 m alpha^(1/3), eq 5 with b = 0), find alpha_room, then the largest
    # alpha within the limits by bisection on log(alpha). For a plain move (A = 0) the stop's
    # start and the peaks grow with alpha (module docstring), and each bisection's result is
    # found on its own grid by guided probes (:func:`bisection_on_grid`, the same alphas).
    lo = hi = (acceleration / (feed * _EQ5_PEAK)) ** 3
    plain = amplitude == 0.0
    bracket = decade_bracket(hi, has_room, within_limits) if plain else None
    if bracket is not None:
        lo, hi = bracket
    else:
        while not has_room(hi):
            lo, hi = hi, 10.0 * hi
        while has_room(lo) and lo > 1e-12 * hi:
            lo /= 10.0
        # lo: no room, hi: room (alpha_room to ~5 %)
        lo, hi = bisection_on_grid(lambda x: not has_room(x), lambda x: -build(x).stop_time, lo, hi, 15, plain)
        if not within_limits(hi):
            raise InfeasibleProblem(
                f"no alpha meets a_max = {acceleration:g}, j_max = {jerk} on this {length:g} mm move at "
                f"{feed:g} mm/s: blends slow enough for the limits do not fit in the move (lower the feed)"
            )
        lo, hi = hi, 10.0 * hi  # lo: feasible
        while within_limits(hi):
            lo, hi = hi, 10.0 * hi
    # alpha to a relative 1e-7
    lo, hi = bisection_on_grid(within_limits, lambda x: -math.log(peak_ratio(x)[1]), lo, hi, 25, plain)
    return build(lo)


def _build(L, m, A, omega, alpha, order, overshoot_tol, settle_tol) -> SigmoidMotion:
    """Startup blends, then a stop that starts ``delta`` before the nominal arrival."""
    start = [(Ramp(m), Blend(alpha, order))] + ([(Sine(A, omega), Blend(alpha, 2))] if A > 0 else [])
    arrival = L / m
    scale = alpha ** (-1 / order)  # time scale of a blend

    def with_stop(t_stop):
        stop = [(Ramp(-m, L), Blend(alpha, order, t_stop))]
        if A > 0:
            stop.append((Sine(-A, omega), Blend(alpha, order, t_stop)))
        return tuple(start + stop)

    def overshoot(t_stop):
        t = max(t_stop, 0.0) + np.linspace(0.0, 12.0 * scale + 4 * A / m, 601)
        return _peak(SigmoidMotion(with_stop(t_stop), 0.0).derivatives(t, orders=1)[0]) - L

    # latest stop start whose overshoot past L stays within tolerance
    late, early = arrival, arrival - 2.0 * A / m - 12.0 * scale
    if overshoot(late) <= overshoot_tol:
        early = late
    for _ in range(40):  # (bisection: the overshoot is 0 over the early part, flat for a secant)
        if late - early <= 1e-7 * scale:
            break
        mid = 0.5 * (late + early)
        late, early = (mid, early) if overshoot(mid) > overshoot_tol else (late, mid)
    t_stop = early
    # settled once |x - L| <= settle_tol for good: the factor exp(-alpha tau^p) bounds the rest
    envelope = m * (arrival - t_stop + 12 * scale) + A
    settle = t_stop + (math.log(max(envelope / settle_tol, 1.0 + 1e-12)) / alpha) ** (1 / order)
    nominal = (Ramp(m),) + ((Sine(A, omega),) if A > 0 else ())
    return SigmoidMotion(terms=with_stop(t_stop), duration=settle, nominal=nominal, order=order, stop_time=t_stop)


def _grid(motion: SigmoidMotion, alpha: float, omega: float) -> np.ndarray:
    """Dense grid over the whole move: 200 points per blend time scale and per oscillation period."""
    dt = alpha ** (-1 / motion.order) / 200
    if omega > 0:
        dt = min(dt, 2 * np.pi / omega / 200)
    n = int(min(motion.duration / dt, 2_000_000)) + 2
    # jerk jumps where a blend starts (third derivative of S is 6 alpha there): both sides of it
    # and peaks sit just after it: a geometric grid right behind every start
    starts = np.array([b.start for _, b in motion.terms if b is not None and 0 <= b.start <= motion.duration])
    eps = 1e-9 * max(motion.duration, 1.0)
    behind = (starts[:, None] + 200 * dt * np.geomspace(1e-6, 1.0, 120)[None, :]).ravel()
    grid = np.concatenate([np.linspace(0.0, motion.duration, n), starts, np.maximum(starts - eps, 0.0), behind])
    return np.unique(np.clip(grid, 0.0, motion.duration))


def _peak(y: np.ndarray) -> float:
    """Largest value of a smooth sampled signal, refined by a parabola through its top 3 samples."""
    i = int(np.argmax(y))
    if 0 < i < y.size - 1:
        a, b, c = y[i - 1], y[i], y[i + 1]
        curvature = a - 2 * b + c
        if curvature < 0:
            return float(b - (a - c) ** 2 / (8 * curvature))
    return float(y[i])


def sigmoid_trajectory(motion: SigmoidMotion, start, direction, sample_period: float = 1e-3, axes=None) -> Trajectory:
    """Sample a straight-line sigmoid motion on the axes: ``q = P0 + u s(t)``.

    Args:
        motion: arc-length motion from :func:`mtp_motion` [mm].
        start: ``P0`` [mm]; ``direction``: unit vector ``u`` (normalised here).
        sample_period: ``Ts`` [s]; ``axes``: names (default x, y, z cut to the dimension).
    """
    p0 = np.atleast_1d(np.asarray(start, dtype=np.float64))
    u = np.atleast_1d(np.asarray(direction, dtype=np.float64))
    norm = np.linalg.norm(u)
    if u.shape != p0.shape or not norm > 0:
        raise ParameterError(f"direction must be a non-zero vector like start {p0.shape}, got {u.tolist()}")
    u = u / norm
    n = int(np.ceil(motion.duration / sample_period - 1e-9)) + 1
    t = np.arange(n) * sample_period
    d = motion.derivatives(t)
    q, v, a, j = (p0 * (k == 0) + d[k][:, None] * u for k in range(4))
    axes = tuple(axes) if axes else ("x", "y", "z")[: p0.size]
    return Trajectory(t, q, v, a, j, np.float64(motion.duration), None, axes, float(sample_period))


def _check(**values) -> None:
    for name, value in values.items():
        if not (np.isfinite(value) and value > 0):
            raise ParameterError(f"{name} must be finite and > 0, got {value!r}")


def mtp_linear_baseline(
    length: float, feed: float, amplitude: float, frequency: float, *, acceleration: float, jerk: float,
    moves_per_period: int = 16, sample_period: float = 1e-3,
) -> tuple[Trajectory, np.ndarray]:
    """Current practice (DiMarco 2015 §1): the MTP motion approximated by short linear moves, each
    run by the jerk-limited linear interpolator (S-curve, exact stop) at its own nominal feed.

    Args:
        length, feed, amplitude, frequency: the MTP move as in :func:`mtp_motion` [mm, mm/s, mm, Hz].
        acceleration, jerk: the interpolator's limits [mm/s^2, mm/s^3].
        moves_per_period: linear moves per oscillation period (the whole move is one move if A = 0).
        sample_period: ``Ts`` [s].

    Returns:
        ``(trajectory of the arc length s (axis "s"), nominal times of the move end points [s])``.
    """
    from research.interpolators.scurve import scurve_interpolate
    from research.limits import AxisLimits
    from research.paths.polyline import Polyline

    _check(length=length, feed=feed, acceleration=acceleration, jerk=jerk)
    if amplitude > 0:
        _check(frequency=frequency)
    times, s = _mtp_moves(length, feed, amplitude, frequency, moves_per_period)
    keep = np.concatenate([[True], np.abs(np.diff(s)) > 1e-9])  # drop moves of no length
    times, s = times[keep], s[keep]
    path = Polyline(s[:, None], axes=("s",))
    feeds = np.abs(np.diff(s)) / np.diff(times)
    limits = AxisLimits.uniform(1, np.inf, acceleration, jerk)
    return scurve_interpolate(path, feeds, limits, sample_period), times


def _mtp_moves(length, feed, amplitude, frequency, moves_per_period):
    """End times [s] and positions [mm] of the G01 moves approximating the MTP motion (§1)."""
    if amplitude > 0:
        n = max(int(np.ceil(length / feed * frequency * moves_per_period)), 1)
        times = np.linspace(0.0, length / feed, n + 1)
        s = feed * times + amplitude * np.sin(2 * np.pi * frequency * times)
        s[-1] = length
    else:
        times, s = np.array([0.0, length / feed]), np.array([0.0, length])
    return times, s


def _ma(x: np.ndarray, n: int) -> np.ndarray:
    """Causal ``n``-sample moving average of a signal at rest before its first sample."""
    c = np.cumsum(np.concatenate([np.zeros(n), x]))
    return (c[n:] - c[:-n]) / n


def mtp_blending_baseline(
    length: float, feed: float, amplitude: float, frequency: float, *, acceleration: float, jerk: float,
    moves_per_period: int = 16, sample_period: float = 1e-4,
) -> tuple[Trajectory, tuple[float, float]]:
    """A blending linear interpolator for the MTP move: the G01 moves of
    :func:`mtp_linear_baseline`, each at its nominal feed with no stop between them (the velocity
    steps from one move's feed to the next), smoothed by acceleration/deceleration after
    interpolation: two causal moving averages of lengths ``T1`` and ``T2`` on the velocity
    (Chen and Lee 1998). Beyond the paper (it compares only against the exact-stop interpolator).

    ``T1`` is the shortest multiple of ``sample_period`` keeping ``|a| <= acceleration`` (checked on
    the samples; ``|a| <= max |dv| / T1`` for isolated steps), ``T2`` the shortest keeping
    ``|j| <= jerk`` (``|j| <= (max a - min a) / T2``). The motion ends ``T1 + T2`` after the last
    move's nominal end.

    Args:
        length, feed, amplitude, frequency, acceleration, jerk, moves_per_period: as in
            :func:`mtp_linear_baseline` [mm, mm/s, mm, Hz, mm/s^2, mm/s^3].
        sample_period: grid of the moving averages ``Ts`` [s]; the move end times are rounded to it.

    Returns:
        ``(trajectory of the arc length s (axis "s"), (T1, T2) [s])``.

    Example:
        >>> tr, (T1, T2) = mtp_blending_baseline(10.0, 20.0, 0.2, 20.0, acceleration=5000.0, jerk=2e6)
        >>> bool(abs(float(tr.q[-1, 0]) - 10.0) < 1e-9), bool(float(tr.duration) < 0.6)
        (True, True)
    """
    _check(length=length, feed=feed, acceleration=acceleration, jerk=jerk, sample_period=sample_period)
    if amplitude > 0:
        _check(frequency=frequency)
    times, s = _mtp_moves(length, feed, amplitude, frequency, moves_per_period)
    Ts = float(sample_period)
    k = np.rint(times / Ts).astype(int)
    feeds = np.diff(s) / np.maximum(np.diff(k), 1) / Ts  # each move covers its length on the grid
    steps = np.abs(np.diff(np.concatenate([[0.0], feeds, [0.0]])))
    n1 = max(int(np.ceil(steps.max() / acceleration / Ts - 1e-9)), 1)

    def signals(n1, n2):
        n = k[-1] + n1 + n2 + 1
        vn = np.zeros(n)
        for i in range(feeds.size):
            vn[k[i]:k[i + 1]] = feeds[i]
        g = (vn - np.concatenate([np.zeros(n1), vn[:-n1]])) / (n1 * Ts)  # d/dt of the first average
        a = _ma(g, n2)
        j = (g - np.concatenate([np.zeros(n2), g[:-n2]])) / (n2 * Ts)
        v = _ma(_ma(vn, n1), n2)
        return vn, v, a, j, g

    while np.abs(signals(n1, 1)[4]).max() > acceleration * (1 + 1e-12):
        n1 += 1
    g = signals(n1, 1)[4]
    n2 = max(int(np.ceil((g.max() - g.min()) / jerk / Ts - 1e-9)), 1)
    _, v, a, j, _ = signals(n1, n2)
    # position: each velocity sample held for one period (the averages keep sum(v) Ts = L)
    q = np.concatenate([[0.0], np.cumsum(v[:-1]) * Ts])
    t = np.arange(v.size) * Ts
    traj = Trajectory(t, q[:, None], v[:, None], a[:, None], j[:, None], np.float64(t[-1]), None, ("s",), Ts)
    return traj, (n1 * Ts, n2 * Ts)
