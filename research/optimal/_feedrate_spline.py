"""The feed profile of Sencer 2009 thesis §3.3: a cubic B-spline in arc length (eq 3.31-3.38), and
the time law ``s(t)`` it defines, with jerk-limited rest ramps at both ends.

Feed ``f(s) = sum_i N_i,3(s) f_i`` on a clamped uniform knot vector (eq 3.34-3.35: ``n`` control
points, ``n - 3`` spans of ``Delta s = L / (n - 3)``). Its time derivatives follow eq 3.29/3.38:
``s' = f``, ``s'' = f f_s``, ``s''' = f (f_s^2 + f f_ss)``.

Rest ends. A feed profile that is polynomial in ``s`` cannot leave ``s = 0`` from rest in finite
time: with ``f(0) = 0``, ``f ~ f_s(0) s`` and ``t = int ds / f`` diverges (a jerk-limited start has
``f ~ s^(2/3)``). The thesis' eq 3.35 sets ``f_0 = f_init = 0``, which only works with a discrete
time sum. Here the first and last ``s_r`` mm are a time-domain ramp of constant path jerk from rest
(:class:`RestRamp`; the stop is its mirror image), and the spline lives on ``[s_r, S - s_r]`` with
its two end control points fixed so that feed and path acceleration match the ramp at the joints.
Position, velocity and acceleration are continuous there; the jerk jumps (it is bounded on both
sides). The ramp feed is chosen as high as the axis limits allow near the ends (``feedrate.py``),
so that the spline never has to accelerate from a crawl, where ``int ds / f`` is most sensitive to a
shape that a polynomial in ``s`` cannot follow; the cost against the path-parametrized OCP is
measured in the tests.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass

import numpy as np
from scipy.interpolate import BSpline

from research.piecewise import PiecewisePolynomial

_GX, _GW = np.polynomial.legendre.leggauss(8)
_TIME_SUB = 8  # time-table sub-intervals per knot span


def clamped_knots(n: int, s0: float, s1: float) -> np.ndarray:
    """Knot vector of eq 3.34-3.35 in arc length: ``[s0]*4, s0 + Delta s, ..., [s1]*4`` with
    ``Delta s = (s1 - s0) / (n - 3)`` [mm]; ``n >= 4`` control points."""
    inner = s0 + (s1 - s0) * np.arange(1, n - 3) / (n - 3)
    return np.concatenate([[s0] * 4, inner, [s1] * 4])


def basis(knots: np.ndarray, s, nu: int = 0) -> np.ndarray:
    """``d^nu N_i,3 / ds^nu`` at ``s`` (eq 3.32, 3.37 through scipy), dense ``(len(s), n)``; ``s`` is
    clipped to the spline's domain (rounding at the ends)."""
    n = knots.size - 4
    s = np.clip(np.asarray(s, dtype=np.float64), knots[3], knots[-4])
    spline = BSpline(knots, np.eye(n), 3, extrapolate=False)
    return np.asarray(spline.derivative(nu)(s) if nu else spline(s))


def span_points(knots: np.ndarray, spans: np.ndarray, per_span) -> np.ndarray:
    """``per_span[j] + 1`` equally spaced points (ends included) on each knot span ``j`` in
    ``spans``, without duplicates [mm]."""
    h = knots[4] - knots[3]
    per = np.asarray(per_span)
    if per.ndim == 0:
        per = np.full(np.max(spans) + 1, per)
    pts = [knots[3] + h * (j + np.arange(per[j] + 1) / per[j]) for j in spans]
    return np.unique(np.concatenate(pts))


def gauss_nodes(knots: np.ndarray, spans: np.ndarray, order: int = 3) -> tuple[np.ndarray, np.ndarray]:
    """Gauss-Legendre nodes and weights on the given knot spans (for ``T = int ds / f``)."""
    x, w = np.polynomial.legendre.leggauss(order)
    h = knots[4] - knots[3]
    left = knots[3] + h * np.asarray(spans, dtype=np.float64)
    return (left[:, None] + 0.5 * h * (x[None, :] + 1)).ravel(), np.tile(0.5 * h * w, len(spans))


@dataclass(frozen=True)
class RestRamp:
    """Jerk-limited start from rest to the ramp feed ``f_r`` [mm/s] with path jerk ``J_r`` [mm/s^3].

    ``accelerating=False``: S-curve, jerk ``+J_r`` then ``-J_r``, zero path acceleration at the joint
    (duration ``2 sqrt(f_r / J_r)``, length ``f_r sqrt(f_r / J_r)``). ``accelerating=True``: jerk
    ``+J_r`` only, ``s = J_r t^3 / 6`` up to ``t_r = sqrt(2 f_r / J_r)`` (length ``J_r t_r^3 / 6``); the
    joint has path acceleration ``J_r t_r``, i.e. ``f_s = 2 / t_r``. The second is what a time-optimal
    start does, so the spline takes over while still accelerating.
    """

    feed: float
    jerk: float
    accelerating: bool = True

    @property
    def duration(self) -> float:
        """Ramp time [s]."""
        k = 2.0 if self.accelerating else 1.0
        return float(np.sqrt(k * self.feed / self.jerk)) * (1.0 if self.accelerating else 2.0)

    @property
    def length(self) -> float:
        """Ramp length ``s_r`` [mm]."""
        return float(self.profile().evaluate_numpy(np.array([self.duration]), 0)[0, 0])

    def end_controls(self, knots: np.ndarray) -> tuple[float, float]:
        """``(f_0, f_1)`` of a clamped cubic feed spline (``f_s = 3 (f_1 - f_0) / Delta s`` at its
        start) that joins the ramp with continuous feed and path acceleration."""
        slope = 2.0 / self.duration if self.accelerating else 0.0
        return self.feed, self.feed + slope * (knots[4] - knots[3]) / 3

    def profile(self) -> PiecewisePolynomial:
        J = self.jerk
        if self.accelerating:
            return PiecewisePolynomial(np.array([0.0, self.duration]), np.array([[[0.0], [0.0], [0.0], [J / 6]]]))
        T = self.duration / 2
        v1, a1, s1 = J * T * T / 2, J * T, J * T**3 / 6
        coeffs = np.array([[0.0, 0.0, 0.0, J / 6], [s1, v1, a1 / 2, -J / 6]])[:, :, None]
        return PiecewisePolynomial(np.array([0.0, T, 2 * T]), coeffs)


@dataclass(frozen=True)
class FeedTimeLaw:
    """``s(t)`` of a rest-to-rest motion: start ramp, ``s' = f(s)`` on the spline, stop ramp.

    Attributes:
        spline: the feed B-spline ``f(s)`` on ``[s_r, S - s_r]`` [mm/s].
        start, stop: the rest ramps (the stop ramp is run backwards in time from the path end).
        length: ``S`` [mm].
    """

    spline: BSpline
    start: RestRamp
    stop: RestRamp
    length: float

    def _table(self) -> tuple[np.ndarray, np.ndarray]:
        """Breaks in ``s`` and the time at each (from the start of the spline part)."""
        k = np.unique(self.spline.t)
        b = np.unique(np.concatenate([np.linspace(a, c, _TIME_SUB + 1) for a, c in itertools.pairwise(k)]))
        h = np.diff(b)
        nodes = b[:-1, None] + 0.5 * h[:, None] * (_GX[None, :] + 1)
        dt = 0.5 * h * ((1.0 / self.spline(nodes)) @ _GW)
        return b, np.concatenate([[0.0], np.cumsum(dt)])

    @property
    def spline_duration(self) -> float:
        return float(self._cached()[1][-1])

    @property
    def duration(self) -> float:
        """Cycle time ``T_Sigma`` [s]: two ramps and ``int ds / f`` over the spline (Gauss)."""
        return self.start.duration + self.stop.duration + self.spline_duration

    def _cached(self):
        if not hasattr(self, "_tab"):
            object.__setattr__(self, "_tab", self._table())
        return self._tab

    def _time_of(self, s: np.ndarray) -> np.ndarray:
        b, tt = self._cached()
        i = np.clip(np.searchsorted(b, s, side="right") - 1, 0, b.size - 2)
        h = s - b[i]
        nodes = b[i, None] + 0.5 * h[:, None] * (_GX[None, :] + 1)
        return tt[i] + 0.5 * h * ((1.0 / self.spline(nodes)) @ _GW)

    def states(self, t) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """``(s, s', s'', s''')`` at times ``t`` [s] (clipped to ``[0, duration]``)."""
        t = np.clip(np.atleast_1d(np.asarray(t, dtype=np.float64)), 0.0, self.duration)
        out = [np.zeros_like(t) for _ in range(4)]
        Tr, Te, T = self.start.duration, self.stop.duration, self.duration
        first, last = self.start.profile(), self.stop.profile()
        start, stop = t <= Tr, t >= T - Te
        mid = ~(start | stop)
        for nu in range(4):
            out[nu][start] = first.evaluate_numpy(t[start], nu)[:, 0]
        # stop ramp run backwards: s(t) = S - r(T - t), s' = r'(T - t), s'' = -r''(T - t), s''' = r'''(T - t)
        if stop.any():
            tau = T - t[stop]
            out[0][stop] = self.length - last.evaluate_numpy(tau, 0)[:, 0]
            out[1][stop] = last.evaluate_numpy(tau, 1)[:, 0]
            out[2][stop] = -last.evaluate_numpy(tau, 2)[:, 0]
            out[3][stop] = last.evaluate_numpy(tau, 3)[:, 0]
        if mid.any():
            out[0][mid], *rest = self._spline_states(t[mid] - Tr)
            for nu in range(1, 4):
                out[nu][mid] = rest[nu - 1]
        return tuple(out)

    def _spline_states(self, tau: np.ndarray):
        """Invert ``t(s)`` on the spline part (table guess, Newton with ``dt/ds = 1/f``)."""
        b, tt = self._cached()
        s = np.interp(tau, tt, b)
        for _ in range(30):
            step = (self._time_of(s) - tau) * self.spline(s)
            s = np.clip(s - step, b[0], b[-1])
            if np.max(np.abs(step), initial=0.0) < 1e-12:
                break
        f, f1, f2 = (self.spline(s, nu) for nu in range(3))
        return s, f, f * f1, f * (f1 * f1 + f * f2)
