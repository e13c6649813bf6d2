"""NumPy evaluation and sampling of piecewise polynomials (no JAX compilation on the OCP path).

Same representation as :class:`research.piecewise.PiecewisePolynomial`: breaks ``b`` and ascending
local coefficients ``c[i, m, :]``, ``f(t) = sum_m c[i, m] (t - b[i])^m`` on ``[b[i], b[i+1])``, held
at its end value (derivatives zero) outside ``[b[0], b[-1]]``. The OCP solutions are sampled here
because the JAX sampler compiles once per array-size bucket, which costs more than a small solve.
"""

from __future__ import annotations

import math

import numpy as np

from research.piecewise import PiecewisePolynomial
from research.trajectory import Trajectory


def evaluate(breaks: np.ndarray, coeffs: np.ndarray, t, nu: int = 0) -> np.ndarray:
    """``nu``-th derivative at times ``t`` ``(n,)`` [s]; returns ``(n, A)``.

    Args:
        breaks: ``(K + 1,)`` non-decreasing [s].
        coeffs: ``(K, d + 1, A)`` ascending local coefficients.
        t: evaluation times [s].
        nu: derivative order (0: value).
    """
    breaks, coeffs = np.asarray(breaks, dtype=np.float64), np.asarray(coeffs, dtype=np.float64)
    t = np.atleast_1d(np.asarray(t, dtype=np.float64))
    K, deg = coeffs.shape[0], coeffs.shape[1] - 1
    tc = np.clip(t, breaks[0], breaks[-1])
    piece = np.clip(np.searchsorted(breaks, tc, side="right") - 1, 0, K - 1)
    tau = (tc - breaks[piece])[:, None]
    if nu > deg:
        return np.zeros((t.size, coeffs.shape[2]))
    value = coeffs[piece, deg, :] * math.perm(deg, nu)
    for m in range(deg - 1, nu - 1, -1):
        value = value * tau + coeffs[piece, m, :] * math.perm(m, nu)
    if nu > 0:
        value = np.where(((t >= breaks[0]) & (t <= breaks[-1]))[:, None], value, 0.0)
    return value


def sampled_trajectory(breaks: np.ndarray, coeffs: np.ndarray, sample_period: float, axes: tuple[str, ...]) -> Trajectory:
    """A :class:`Trajectory` on the grid ``0, Ts, ...`` up to the first sample at or after the end
    (the grid of :meth:`Trajectory.from_piecewise`), with the exact profile attached; ``breaks``
    must start at 0."""
    duration = float(breaks[-1] - breaks[0])
    n = int(np.ceil(duration / sample_period - 1e-9)) + 1
    t = np.arange(n) * sample_period
    q, v, a, j = (evaluate(breaks, coeffs, t, nu) for nu in range(4))
    exact = PiecewisePolynomial(np.asarray(breaks, dtype=np.float64), np.asarray(coeffs, dtype=np.float64))
    return Trajectory(t, q, v, a, j, np.float64(duration), exact, tuple(axes), float(sample_period))
