"""Per-axis kinematic limits shared by interpolators, optimal control and metrics.

Units: mm/s, mm/s^2, mm/s^3 (per axis, in the order of the path's axes).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from research.errors import ParameterError


@dataclass(frozen=True)
class AxisLimits:
    """Velocity, acceleration and jerk bounds ``|q'| <= v``, ``|q''| <= a``, ``|q'''| <= j`` per axis.

    Args:
        velocity: ``(A,)`` [mm/s] (a scalar is broadcast when ``n_axes`` is given).
        acceleration: ``(A,)`` [mm/s^2].
        jerk: ``(A,)`` [mm/s^3]; ``inf`` for no jerk limit.

    Example:
        >>> lim = AxisLimits.uniform(2, velocity=250.0, acceleration=2000.0, jerk=3000.0)
        >>> lim.along([0.6, 0.8]).tolist()   # tangential limits along a unit direction
        [312.5, 2500.0, 3750.0]
    """

    velocity: np.ndarray
    acceleration: np.ndarray
    jerk: np.ndarray

    def __post_init__(self):
        arrays = [np.atleast_1d(np.asarray(x, dtype=np.float64)) for x in (self.velocity, self.acceleration, self.jerk)]
        n = max(a.size for a in arrays)
        for name, a in zip(("velocity", "acceleration", "jerk"), arrays):
            if a.ndim != 1 or a.size not in (1, n):
                raise ParameterError(f"AxisLimits.{name} must have one value per axis ({n}), got shape {a.shape}")
            if np.any(np.isnan(a)) or np.any(a <= 0):
                raise ParameterError(f"AxisLimits.{name} must be > 0 (inf allowed), got {a.tolist()}")
        for name, a in zip(("velocity", "acceleration", "jerk"), arrays):
            a = np.broadcast_to(a, (n,)).copy()
            a.setflags(write=False)
            object.__setattr__(self, name, a)

    @staticmethod
    def uniform(n_axes: int, velocity: float, acceleration: float, jerk: float = np.inf) -> "AxisLimits":
        """The same limits on every axis."""
        return AxisLimits(np.full(n_axes, velocity), np.full(n_axes, acceleration), np.full(n_axes, jerk))

    @staticmethod
    def fir_envelope(n_axes: int, feed: float, delays) -> "AxisLimits":
        """Nominal envelope of a two-filter FIR interpolator: ``v = F``, ``a = F / T1``,
        ``j = F / (T1 T2)`` (Sencer 2015 §2.1; ``T1 >= T2``; one filter: no jerk limit)."""
        d = np.sort(np.atleast_1d(np.asarray(delays, dtype=np.float64)))[::-1]
        jerk = feed / (d[0] * d[1]) if d.size > 1 else np.inf
        return AxisLimits.uniform(n_axes, feed, feed / d[0], jerk)

    @property
    def n_axes(self) -> int:
        return self.velocity.size

    def along(self, direction) -> np.ndarray:
        """Tangential ``[v, a, j]`` limits for straight motion along ``direction`` (unit vector):
        the tightest ``limit_i / |u_i|`` over the axes that move."""
        u = np.abs(np.asarray(direction, dtype=np.float64))
        if u.shape != (self.n_axes,):
            raise ParameterError(f"direction must have {self.n_axes} components, got shape {u.shape}")
        with np.errstate(divide="ignore"):
            return np.array([np.min(lim / u) for lim in (self.velocity, self.acceleration, self.jerk)])

    def ratios(self, v, a, j) -> dict[str, np.ndarray]:
        """Per-axis ``peak / limit`` for given peak values, e.g. ``{"velocity": [0.98, 1.01], ...}``
        (above 1: the limit is exceeded; 0 under an infinite limit, whatever the peak: the jerk of
        one FIR filter's motion is unbounded and its envelope sets no jerk limit)."""
        out = {}
        for name, peak, lim in (("velocity", v, self.velocity), ("acceleration", a, self.acceleration), ("jerk", j, self.jerk)):
            peak = np.asarray(peak, dtype=np.float64)
            with np.errstate(invalid="ignore"):  # inf / inf: an unbounded peak under no limit
                out[name] = np.where(np.isinf(lim) & ~np.isnan(peak), 0.0, peak / lim)
        return out
