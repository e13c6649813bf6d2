"""Figure of one FIR-cornering run (``python -m research run``): path, feed, axis kinematics.

In the layout of Sencer 2015 Fig 6a-b: the commanded and interpolated path with a zoom on the
first corner, the feed along time, and the axis acceleration and jerk.
"""

from __future__ import annotations

import numpy as np
from matplotlib.patches import Circle

from research.figures._style import AXIS_COLOURS, figure
from research.interpolators import FIRPlan
from research.metrics import MotionMetrics
from research.paths import Polyline
from research.trajectory import Trajectory


def plot_fir_run(path: Polyline, plan: FIRPlan, traj: Trajectory, metrics: MotionMetrics, title: str = ""):
    """Return a matplotlib figure of the run (not saved)."""
    fig, ax = figure(2, 2, figsize=(10, 7))
    q, t = np.asarray(traj.q), np.asarray(traj.t)
    a = ax[0, 0]
    a.plot(path.points[:, 0], path.points[:, 1] if path.dim > 1 else 0 * path.points[:, 0], "k--", lw=0.8, label="G01 path")
    a.plot(q[:, 0], q[:, 1] if path.dim > 1 else 0 * q[:, 0], "C0", label="FIR trajectory")
    a.set(xlabel=f"{path.axes[0]} [mm]", ylabel=f"{path.axes[1] if path.dim > 1 else ''} [mm]", title="tool path")
    a.set_aspect("equal", adjustable="datalim")
    a.legend(loc="best")
    a = ax[0, 1]
    if path.n_segments > 1:
        c = path.corners[0]
        r = max(4 * metrics.corner_errors[0], 1e-3)
        a.plot(path.points[:, 0], path.points[:, 1], "k--", lw=0.8, label="G01 path")
        a.plot(q[:, 0], q[:, 1], "C0.-", ms=2, label=f"samples, Ts = {traj.sample_period * 1e3:g} ms")
        a.add_patch(Circle(c[:2], metrics.corner_errors[0], fill=False, ls=":", color="C3", label="corner error"))
        a.set(xlim=(c[0] - r, c[0] + r), ylim=(c[1] - r, c[1] + r), xlabel=f"{path.axes[0]} [mm]", ylabel=f"{path.axes[1]} [mm]",
              title=f"first corner: error {metrics.corner_errors[0] * 1e3:.1f} um, T_k = {float(plan.overlaps[0]) * 1e3:.1f} ms")
        a.set_aspect("equal")
        a.legend(loc="best")
    else:
        a.axis("off")
    a = ax[1, 0]
    a.plot(t, traj.feed, "k", label="feed |v|")
    for k, name in enumerate(traj.axes):
        a.plot(t, np.asarray(traj.v)[:, k], color=AXIS_COLOURS.get(name), lw=0.8, label=f"v_{name}")
    a.set(xlabel="time [s]", ylabel="velocity [mm/s]", title=f"feed and axis velocity; cycle time {metrics.cycle_time:.4f} s")
    a.legend(loc="best")
    a = ax[1, 1]
    for k, name in enumerate(traj.axes):
        a.plot(t, np.asarray(traj.a)[:, k], color=AXIS_COLOURS.get(name), label=f"a_{name}")
    a.set(xlabel="time [s]", ylabel="acceleration [mm/s^2]", title="axis acceleration")
    b = a.twinx()
    for k, name in enumerate(traj.axes):
        b.plot(t, np.asarray(traj.j)[:, k], color=AXIS_COLOURS.get(name), lw=0.5, ls=":")
    b.set_ylabel("jerk [mm/s^3] (dotted)")
    b.grid(False)
    a.legend(loc="best")
    if title:
        fig.suptitle(title, fontsize=8)
    return fig
