"""Axis motion from a time law along a 5-axis path (eq 3.27), dense limit checks, which limit binds
where (thesis Fig 3.10 style), and the axis limits reflected on the feed (eq 3.42, 3.50, 3.54)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from research.limits import AxisLimits
from research.paths.kinematics5 import TableTiltingAC
from research.paths.pose_spline import PoseSpline
from research.optimal._arrays import frozen

AXES = ("x", "y", "z", "a", "c")
KINDS = ("velocity", "acceleration", "jerk")


def axis_motion(path: PoseSpline, machine: TableTiltingAC, s, sd, sdd, sddd):
    """Axis position, velocity, acceleration and jerk from the path states (eq 3.27):

        q' = Q_s s',  q'' = Q_ss s'^2 + Q_s s'',  q''' = Q_sss s'^3 + 3 Q_ss s' s'' + Q_s s'''.

    Args:
        s, sd, sdd, sddd: ``(N,)`` arc length [mm] and its time derivatives [mm/s^k].
    Returns:
        ``(q, v, a, j)``, each ``(N, 5)`` [mm, rad and per s^k].
    """
    d = path.axis_derivatives(machine, s)
    sd, sdd, sddd = (np.asarray(x, dtype=np.float64)[:, None] for x in (sd, sdd, sddd))
    v = d.Q_s * sd
    a = d.Q_ss * sd**2 + d.Q_s * sdd
    j = d.Q_sss * sd**3 + 3 * d.Q_ss * sd * sdd + d.Q_s * sddd
    return d.Q, v, a, j


@dataclass(frozen=True)
class LimitCheck:
    """Peaks over a dense sample of the motion, as ratios to the limits (1.0 = at the limit).

    Attributes:
        velocity_ratio, acceleration_ratio, jerk_ratio: ``(5,)`` per axis ``x, y, z, a, c``.
        feed_ratio: peak path feed / feed cap (``nan`` without a cap).
        samples: number of points checked.
    """

    velocity_ratio: np.ndarray
    acceleration_ratio: np.ndarray
    jerk_ratio: np.ndarray
    feed_ratio: float
    samples: int

    @property
    def worst_ratio(self) -> float:
        vals = [*self.velocity_ratio, *self.acceleration_ratio, *self.jerk_ratio]
        if np.isfinite(self.feed_ratio):
            vals.append(self.feed_ratio)
        return float(max(vals))

    def worst(self) -> tuple[str, str, float]:
        """``(axis, kind, ratio)`` of the largest axis ratio."""
        r = np.vstack([self.velocity_ratio, self.acceleration_ratio, self.jerk_ratio])
        k, i = np.unravel_index(np.argmax(r), r.shape)
        return AXES[i], KINDS[k], float(r[k, i])


def limit_ratios(v, a, j, limits: AxisLimits) -> np.ndarray:
    """``(N, 3, 5)`` ``|q^(k)| / limit`` per sample, kind and axis."""
    return np.stack([np.abs(v) / limits.velocity, np.abs(a) / limits.acceleration, np.abs(j) / limits.jerk], axis=1)


def check(v, a, j, sd, limits: AxisLimits, feed: float | None) -> LimitCheck:
    r = limit_ratios(v, a, j, limits).max(axis=0)
    fr = float(np.max(sd) / feed) if feed else float("nan")
    return LimitCheck(frozen(r[0]), frozen(r[1]), frozen(r[2]), fr, int(np.shape(v)[0]))


@dataclass(frozen=True)
class Binding:
    """A stretch of path where one axis limit (or the feed cap) is active (Fig 3.10 style).

    Attributes:
        axis: ``"x" .. "c"``, or ``"feed"`` for the programmed feed cap.
        kind: ``"velocity"``, ``"acceleration"``, ``"jerk"`` (``"velocity"`` for the feed cap).
        s_start, s_end: the stretch [mm]; peak: largest ratio there.
    """

    axis: str
    kind: str
    s_start: float
    s_end: float
    peak: float


def binding_intervals(s, ratios: np.ndarray, feed_ratio: np.ndarray | None, threshold: float = 0.98,
                      min_gap: float = 1.0) -> tuple[Binding, ...]:
    """Stretches where ``ratio >= threshold``, merged across gaps shorter than ``min_gap`` mm.

    Args:
        s: ``(N,)`` increasing arc lengths [mm]; ratios: ``(N, 3, 5)`` from :func:`limit_ratios`;
        feed_ratio: ``(N,)`` feed / cap or ``None``.
    """
    s = np.asarray(s)
    series = [(AXES[i], KINDS[k], ratios[:, k, i]) for k in range(3) for i in range(5)]
    if feed_ratio is not None:
        series.append(("feed", "velocity", np.asarray(feed_ratio)))
    out = []
    for axis, kind, r in series:
        idx = np.flatnonzero(r >= threshold)
        if idx.size == 0:
            continue
        groups = np.split(idx, np.flatnonzero(np.diff(s[idx]) > min_gap) + 1)
        out += [Binding(axis, kind, float(s[g[0]]), float(s[g[-1]]), float(r[g].max())) for g in groups]
    return tuple(sorted(out, key=lambda b: (b.s_start, b.axis)))


def axis_feed_limits(path: PoseSpline, limits: AxisLimits, s, machine: TableTiltingAC | None = None) -> dict[str, np.ndarray]:
    """Each axis' limits reflected on the tangential feed (thesis Fig 3.10), ``(N, 5)`` [mm/s]:

    - ``velocity``: ``v_i / |Q_s,i|`` (eq 3.42);
    - ``acceleration``: ``sqrt(a_i / |Q_ss,i|)``, the feed at zero path acceleration (eq 3.50);
    - ``jerk``: ``cbrt(j_i / |Q_sss,i|)``, at zero path acceleration and jerk (eq 3.54).

    ``inf`` where the partial derivative vanishes. The envelope ``min`` over axes and kinds is an
    upper bound on any feasible feed, not a feasible feed itself (thesis §3.6).
    """
    d = path.axis_derivatives(machine or TableTiltingAC(), s)
    with np.errstate(divide="ignore"):
        return {
            "velocity": limits.velocity / np.abs(d.Q_s),
            "acceleration": np.sqrt(limits.acceleration / np.abs(d.Q_ss)),
            "jerk": np.cbrt(limits.jerk / np.abs(d.Q_sss)),
        }
