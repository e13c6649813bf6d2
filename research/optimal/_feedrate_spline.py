"""The feed profile of Sencer 2009 thesis §3.3: a cubic B-spline in arc length (eq 3.31-3.38), and
the time law ``s(t)`` it defines, with jerk-limited rest ramps at both ends.

Feed ``f(s) = sum_i N_i,3(s) f_i`` on a clamped uniform knot vector (eq 3.34-3.35: ``n`` control
points, ``n - 3`` spans of ``Delta s = L / (n - 3)``). Its time derivatives follow eq 3.29/3.38:
``s' = f``, ``s'' = f f_s``, ``s''' = f (f_s^2 + f f_ss)``.

Rest ends. A feed profile that is polynomial in ``s`` cannot leave ``s = 0`` from rest in finite
time: with ``f(0) = 0``, ``f ~ f_s(0) s`` and ``t = int ds / f`` diverges (a jerk-limited start has
``f ~ s^(2/3)``). The thesis' eq 3.35 sets ``f_0 = f_init = 0``, which only works with a discrete
time sum. Here the spline lives on ``[s_r, S - s_r]`` with ``f_0 = f_1 = f_b`` (and ``f_(n-2) =
f_(n-1) = f_b``), i.e. a small *rest feed* ``f_b`` with zero path acceleration (clamped ends), and
the first and last ``s_r`` mm are a time-domain ramp: constant jerk ``+J_r`` then ``-J_r`` from rest to
``f_b`` (``s_r = f_b sqrt(f_b / J_r)``, duration ``2 sqrt(f_b / J_r)``). Position, velocity and
acceleration are continuous at the joints; the jerk jumps (it is bounded on both sides).
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
    """``d^nu N_i,3 / ds^nu`` at ``s`` (eq 3.32, 3.37 through scipy), dense ``(len(s), n)``."""
    n = knots.size - 4
    return np.asarray(BSpline(knots, np.eye(n), 3, extrapolate=False).derivative(nu)(np.asarray(s, dtype=np.float64)) if nu
                      else BSpline(knots, np.eye(n), 3, extrapolate=False)(np.asarray(s, dtype=np.float64)))


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
    """Jerk-limited start from rest to the rest feed ``f_b`` [mm/s] with tangential jerk ``J_r``
    [mm/s^3]: ``s(t)`` piecewise cubic, zero acceleration at both ends."""

    feed: float
    jerk: float

    @property
    def half(self) -> float:
        return float(np.sqrt(self.feed / self.jerk))

    @property
    def duration(self) -> float:
        """``2 sqrt(f_b / J_r)`` [s]."""
        return 2 * self.half

    @property
    def length(self) -> float:
        """``f_b sqrt(f_b / J_r)`` [mm]."""
        return self.feed * self.half

    def profile(self) -> PiecewisePolynomial:
        T, J = self.half, self.jerk
        v1, a1, s1 = J * T * T / 2, J * T, J * T**3 / 6
        coeffs = np.array([[0.0, 0.0, 0.0, J / 6], [s1, v1, a1 / 2, -J / 6]])[:, :, None]
        return PiecewisePolynomial(np.array([0.0, T, 2 * T]), coeffs)


@dataclass(frozen=True)
class FeedTimeLaw:
    """``s(t)`` of a rest-to-rest motion: start ramp, ``s' = f(s)`` on the spline, stop ramp.

    Attributes:
        spline: the feed B-spline ``f(s)`` on ``[s_r, S - s_r]`` [mm/s].
        ramp: the rest ramps (the stop ramp is the start ramp reversed in time).
        length: ``S`` [mm].
    """

    spline: BSpline
    ramp: RestRamp
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
        return 2 * self.ramp.duration + self.spline_duration

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
        Tr, T = self.ramp.duration, self.duration
        ramp = self.ramp.profile()
        start, stop = t <= Tr, t >= T - Tr
        mid = ~(start | stop)
        for nu in range(4):
            out[nu][start] = ramp.evaluate_numpy(t[start], nu)[:, 0]
        # stop ramp: s(t) = S - r(T - t) => s' = r'(T - t), s'' = -r''(T - t), s''' = r'''(T - t)
        if stop.any():
            tau = T - t[stop]
            out[0][stop] = self.length - ramp.evaluate_numpy(tau, 0)[:, 0]
            out[1][stop] = ramp.evaluate_numpy(tau, 1)[:, 0]
            out[2][stop] = -ramp.evaluate_numpy(tau, 2)[:, 0]
            out[3][stop] = ramp.evaluate_numpy(tau, 3)[:, 0]
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
