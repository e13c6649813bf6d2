"""Arc length of a parametric curve by composite Gauss-Legendre quadrature, and its inverse.

Shared by :class:`~research.paths.bspline.BSplinePath` and :class:`~research.paths.pose_spline.PoseSpline`:
the knot spans are cut into equal sub-intervals, the speed ``|C'(u)|`` is integrated on each, and
``s(u)`` between break points adds one more quadrature from the break below ``u``.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class ArcLength:
    """``s(u) = int_{u_0}^{u} speed(v) dv`` [mm] of one curve.

    Attributes:
        breaks: ``(B,)`` quadrature break points in the parameter.
        cumulative: ``(B,)`` arc length at each break [mm].
        nodes: ``(B - 1, n)`` Gauss nodes of every sub-interval (e.g. for geometry checks).
        speed: ``u -> |C'(u)|`` [mm per unit parameter], vectorized over ``u``.
        order: Gauss-Legendre nodes per sub-interval.
    """

    breaks: np.ndarray
    cumulative: np.ndarray
    nodes: np.ndarray
    speed: Callable[[np.ndarray], np.ndarray]
    order: int

    @staticmethod
    def build(knots: np.ndarray, speed: Callable[[np.ndarray], np.ndarray], order: int, subdivisions: int) -> ArcLength:
        """Quadrature on ``subdivisions`` equal sub-intervals of every span between the distinct
        ``knots`` (those inside the domain), ``order`` Gauss nodes each."""
        k = np.unique(knots)
        b = np.unique(np.concatenate([np.linspace(a, c, subdivisions + 1) for a, c in zip(k[:-1], k[1:])]))
        x, w = np.polynomial.legendre.leggauss(order)
        h = np.diff(b)
        nodes = b[:-1, None] + 0.5 * h[:, None] * (x[None, :] + 1.0)
        pieces = 0.5 * h * (speed(nodes.ravel()).reshape(nodes.shape) @ w)
        return ArcLength(b, np.concatenate([[0.0], np.cumsum(pieces)]), nodes, speed, order)

    @property
    def total(self) -> float:
        """Length of the whole curve [mm]."""
        return float(self.cumulative[-1])

    def __call__(self, u) -> np.ndarray:
        """``s(u)`` [mm] at parameters ``u`` (clipped to the domain), shape ``(len(u),)``."""
        b = self.breaks
        x, w = np.polynomial.legendre.leggauss(self.order)
        u = np.clip(np.atleast_1d(np.asarray(u, dtype=np.float64)), b[0], b[-1])
        i = np.clip(np.searchsorted(b, u, side="right") - 1, 0, b.size - 2)
        h = u - b[i]
        nodes = b[i, None] + 0.5 * h[:, None] * (x[None, :] + 1.0)
        return self.cumulative[i] + 0.5 * h * (self.speed(nodes.ravel()).reshape(nodes.shape) @ w)

    def inverse(self, s, max_iterations: int = 30) -> np.ndarray:
        """The parameter ``u`` at arc length ``s`` [mm] (clipped to ``[0, total]``): Newton on
        ``s(u) - s`` from linear interpolation of the table, kept inside the bracketing breaks;
        stops when the step is below ``1e-14`` of the domain's scale."""
        b, cum = self.breaks, self.cumulative
        s = np.clip(np.atleast_1d(np.asarray(s, dtype=np.float64)), 0.0, cum[-1])
        i = np.clip(np.searchsorted(cum, s, side="right") - 1, 0, b.size - 2)
        lo, hi = b[i], b[i + 1]
        u = lo + (s - cum[i]) / np.maximum(cum[i + 1] - cum[i], 1e-300) * (hi - lo)
        tol = 1e-14 * max(1.0, abs(float(b[0])), abs(float(b[-1])))
        for _ in range(max_iterations):
            u_new = np.clip(u - (self(u) - s) / np.maximum(self.speed(u), 1e-300), lo, hi)
            done = np.max(np.abs(u_new - u), initial=0.0) < tol
            u = u_new
            if done:
                break
        return u
