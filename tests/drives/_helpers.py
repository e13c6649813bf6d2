"""Trajectory builders shared by the drive tests."""

import numpy as np

from research.trajectory import Trajectory


def make_trajectory(q, Ts, v=None, a=None, j=None, axes=None):
    """Trajectory from sampled columns; missing derivatives are zero."""
    q = np.asarray(q, dtype=float)
    if q.ndim == 1:
        q = q[:, None]
    z = np.zeros_like(q)
    cols = [z if x is None else np.asarray(x, dtype=float).reshape(q.shape) for x in (v, a, j)]
    t = np.arange(q.shape[0]) * Ts
    axes = axes or tuple("xyzac"[: q.shape[1]])
    return Trajectory(t, q, cols[0], cols[1], cols[2], np.float64(t[-1]), None, axes, Ts)


def polynomial_trajectory(coeffs, n, Ts, axes=("x",)):
    """x_r(t) = sum c_k t^k with exact v, a, j (one column per axis, same polynomial)."""
    t = np.arange(n) * Ts
    p = np.polynomial.Polynomial(coeffs)
    cols = [p(t), p.deriv(1)(t), p.deriv(2)(t), p.deriv(3)(t)]
    cols = [np.repeat(c[:, None], len(axes), axis=1) for c in cols]
    return Trajectory(t, *cols, np.float64(t[-1]), None, tuple(axes), Ts)


def sine_trajectory(amplitude, freq_hz, n, Ts, axes=("x",)):
    """x_r = A sin(2 pi f t) with exact derivatives."""
    t = np.arange(n) * Ts
    w = 2 * np.pi * freq_hz
    cols = [amplitude * np.sin(w * t), amplitude * w * np.cos(w * t), -amplitude * w**2 * np.sin(w * t),
            -amplitude * w**3 * np.cos(w * t)]
    cols = [np.repeat(c[:, None], len(axes), axis=1) for c in cols]
    return Trajectory(t, *cols, np.float64(t[-1]), None, tuple(axes), Ts)
