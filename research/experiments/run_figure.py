"""Figure of one run (``python -m research run``): path, a sharp corner, feed, axis kinematics.

In the layout of Sencer 2015 Fig 6a-b: the commanded and interpolated path with a zoom on the
sharp corner of largest error (the first such), the feed along time, and the axis acceleration and jerk of the first interpolator.
With several interpolators every one is drawn in the path, corner and feed panels.
"""

from __future__ import annotations

import numpy as np
from matplotlib.patches import Circle

from research.experiments.plot_style import AXIS_COLOURS, STYLE, figure
from research.paths import Polyline


#: Above this many plotted samples a legend goes to a fixed corner: matplotlib's ``loc="best"``
#: tests every candidate place against every point (its documentation: "can be slow for plots with
#: large amounts of data"); measured 9.7 s of a 260,000-sample run's figure.
BEST_LEGEND_MAX_SAMPLES = 20_000


def _envelope(t: np.ndarray, y: np.ndarray, bins: int) -> tuple[np.ndarray, np.ndarray]:
    """A time series reduced for drawing: of each of ``bins`` consecutive stretches of equal sample
    count, its first, last, smallest and largest samples, in time order (the M4 reduction of Jugel
    et al., VLDB 2014). Drawn ``bins`` stretches across, it is the full series' picture (every
    stretch spans the same pixel column's extremes and joins its neighbours as the full line does);
    at most ``4 bins`` samples. Series of up to ``4 bins`` samples are returned as they are."""
    n = t.size
    if n <= 4 * bins:
        return t, y
    w = -(-n // bins)  # samples per stretch (the last one shorter)
    padded = np.concatenate([y, np.full(bins * w - n, y[-1])]).reshape(bins, w)
    base = np.arange(bins) * w
    keep = np.concatenate([base, np.minimum(base + w - 1, n - 1), base + padded.argmin(axis=1),
                           base + padded.argmax(axis=1)])
    keep = np.unique(np.minimum(keep, n - 1))
    return t[keep], y[keep]


def _near(q: np.ndarray, centre: np.ndarray, r: float) -> np.ndarray:
    """The samples of ``q`` ``(N, d)`` within the box ``centre +- r`` in its first two axes, with one
    neighbour each side of every run of them (the lines leave the box as drawn in full), runs
    apart separated by a row of NaN (no line drawn between them)."""
    inside = np.all(np.abs(q[:, :2] - centre[:2]) <= r, axis=1)
    inside[:-1] |= inside[1:]
    inside[1:] |= inside[:-1].copy()
    idx = np.flatnonzero(inside)
    if not idx.size:
        return q[:0]
    gap = np.flatnonzero(np.diff(idx) > 1) + 1
    parts = np.split(idx, gap)
    nan = np.full((1, q.shape[1]), np.nan)
    return np.concatenate([x for p in parts for x in (q[p], nan)][:-1])


def plot_run(path: Polyline, runs: list, title: str = ""):
    """Return a matplotlib figure of the run (not saved).

    Args:
        path: the commanded polyline [mm].
        runs: ``(label, plan or None, Trajectory, MotionMetrics)`` per interpolator (the first gets the
            kinematics panel; ``plan``: the :class:`~research.interpolators.FIRPlan` of an FIR run).
        title: figure title.
    """
    fig, ax = figure(2, 2, figsize=(10, 7))
    # time series drawn by their M4 envelope over one stretch per pixel column of the saved figure
    bins = int(np.ceil(fig.get_figwidth() * STYLE["savefig.dpi"]))
    label0, plan0, traj0, metrics0 = runs[0]
    samples = sum(np.asarray(traj.t).size for _, _, traj, _ in runs) + path.points.shape[0]
    best = "best" if samples <= BEST_LEGEND_MAX_SAMPLES else "upper right"
    several = len(runs) > 1
    a = ax[0, 0]
    y = (lambda p: p[:, 1]) if path.dim > 1 else (lambda p: 0 * p[:, 0])
    a.plot(path.points[:, 0], y(path.points), "k--", lw=0.8, label="G01 path")
    for i, (label, _, traj, _) in enumerate(runs):
        q = np.asarray(traj.q)
        a.plot(q[:, 0], y(q), f"C{i}", label=label if several else f"{label} trajectory")
    a.set(xlabel=f"{path.axes[0]} [mm]", ylabel=f"{path.axes[1] if path.dim > 1 else ''} [mm]", title="tool path")
    a.set_aspect("equal", adjustable="datalim")
    a.legend(loc=best)
    a = ax[0, 1]
    if path.n_segments > 1 and path.dim > 1:
        # a sharp corner (turning by at least half the sharpest turn: a lead-in's straight junction or
        # an arc's chord vertex shows nothing of the cornering), the first of largest error of the first run
        turns = np.asarray(path.turning_angles)
        errors = np.where(turns >= 0.5 * float(np.max(turns)), np.asarray(metrics0.corner_errors, dtype=float), -1.0)
        k = int(np.argmax(errors))
        c = path.corners[k]
        r = max(4 * max(float(m.corner_errors[k]) for *_, m in runs), 1e-3)
        a.plot(path.points[:, 0], path.points[:, 1], "k--", lw=0.8, label="G01 path")
        for i, (label, _, traj, m) in enumerate(runs):
            q = _near(np.asarray(traj.q), c, 2 * r)  # the samples in (and around) the zoom
            a.plot(q[:, 0], q[:, 1], f"C{i}.-", ms=2, label=f"{label}: {float(m.corner_errors[k]) * 1e3:.1f} um")
            a.add_patch(Circle(c[:2], float(m.corner_errors[k]), fill=False, ls=":", color=f"C{i}"))
        same = plan0 is not None and np.asarray(plan0.overlaps).size == turns.size  # the plan's corners are these
        overlap = f", T_k = {float(plan0.overlaps[k]) * 1e3:.1f} ms" if same else ""
        a.set(xlim=(c[0] - r, c[0] + r), ylim=(c[1] - r, c[1] + r), xlabel=f"{path.axes[0]} [mm]",
              ylabel=f"{path.axes[1]} [mm]", title=f"sharp corner, {np.degrees(turns[k]):.0f} deg (dotted: "
                                                    f"corner error, Ts = {traj0.sample_period * 1e3:g} ms){overlap}")
        a.set_aspect("equal")
        a.legend(loc=best, title="corner error")
    else:
        a.axis("off")
    a = ax[1, 0]
    for i, (label, _, traj, m) in enumerate(runs):
        a.plot(*_envelope(np.asarray(traj.t), np.asarray(traj.feed), bins), f"C{i}" if several else "k",
               label=f"{label}: {m.cycle_time:.4f} s" if several else "feed |v|")
    t0 = np.asarray(traj0.t)
    if not several:
        for k, name in enumerate(traj0.axes):
            a.plot(*_envelope(t0, np.asarray(traj0.v)[:, k], bins), color=AXIS_COLOURS.get(name), lw=0.8, label=f"v_{name}")
    a.set(xlabel="time [s]", ylabel="velocity [mm/s]",
          title="feed (legend: cycle time)" if several else f"feed and axis velocity; cycle time {metrics0.cycle_time:.4f} s")
    a.legend(loc=best)
    a = ax[1, 1]
    for k, name in enumerate(traj0.axes):
        a.plot(*_envelope(t0, np.asarray(traj0.a)[:, k], bins), color=AXIS_COLOURS.get(name), label=f"a_{name}")
    a.set(xlabel="time [s]", ylabel="acceleration [mm/s^2]", title=f"{label0}: axis acceleration (solid), jerk (dotted)")
    b = a.twinx()
    for k, name in enumerate(traj0.axes):
        b.plot(*_envelope(t0, np.asarray(traj0.j)[:, k], bins), color=AXIS_COLOURS.get(name), lw=0.5, ls=":")
    b.set_ylabel("jerk [mm/s^3] (dotted)")
    b.grid(False)
    a.legend(loc=best)
    if title:
        fig.suptitle(title, fontsize=8)
    return fig
