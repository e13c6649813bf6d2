"""Sencer 2015 Fig 4: accurate corner blending by G-line overlapping.

Two 2.5 mm G01 lines with a 90 deg corner at F = 50 mm/s through one FIR filter, T1 = 20 ms:
(a) the three cornering trajectories, (b) sharp cornering (T_k = 0: each block takes
T_v + T_1 = 70 ms), (c) full overlap (T_k = T_d: Y reverses at 2 F sin 45 / T1 = 3535 mm/s^2),
(d) half overlap (T_k = T_d / 2 = 10 ms).
"""

from __future__ import annotations

from pathlib import Path

import jax.numpy as jnp
import numpy as np

from research.figures._style import AXIS_COLOURS, mosaic, save
from research.interpolators import cornering_error, plan_fir
from research.paths import named_path

NAME = "sencer2015_fig4_fir_cornering"
REPRODUCES = "Sencer 2015 Fig 4 (sharp, full-overlap and half-overlap cornering, eq 11-13)"
FEED = 50.0  # mm/s
T1 = 0.020  # s


def cases():
    """``(label, tolerance [mm])`` giving T_k = 0, T_d and T_d / 2 through eq 13."""
    dF = jnp.array([2 * FEED * np.sin(np.pi / 4)])
    half = float(cornering_error(T1 / 2, dF, jnp.array([T1]))[0])
    return [("sharp, T_k = 0", 0.0), ("full overlap, T_k = T_d", 1.0), ("half overlap, T_k = T_d / 2", half)]


def make_figure(out_dir: Path, fast: bool = False) -> list[Path]:
    """Write the figure to ``out_dir``; returns the files written."""
    path = named_path("sencer2015_fig4")
    Ts = 1e-3 if fast else 1e-4
    fig, ax = mosaic([["a", "v0", "v1", "v2"], ["a", "a0", "a1", "a2"]], figsize=(14, 5.5))
    colours = ("k", "C0", "C2")
    for col, ((label, eps), colour) in enumerate(zip(cases(), colours)):
        plan = plan_fir(path, FEED, [T1], eps)
        traj = plan.trajectory(Ts)
        t, q, v, a = (np.asarray(x) for x in (traj.t, traj.q, traj.v, traj.a))
        ax["a"].plot(q[:, 0], q[:, 1], color=colour, label=f"{label}: eps = {float(plan.corner_errors[0]) * 1e3:.0f} um")
        panel_v, panel_a = ax[f"v{col}"], ax[f"a{col}"]
        for k, name in enumerate(traj.axes):
            panel_v.plot(t * 1e3, v[:, k], color=AXIS_COLOURS[name], label=f"v_{name}")
            panel_a.plot(t * 1e3, a[:, k], color=AXIS_COLOURS[name], label=f"a_{name}")
        panel_v.set(title=f"({'bcd'[col]}) {label}\ncycle time {float(plan.cycle_time) * 1e3:.1f} ms", ylabel="velocity [mm/s]")
        peak = np.abs(a).max(axis=0)
        panel_a.set(xlabel="time [ms]", ylabel="acceleration [mm/s^2]",
                    title=f"peak |a_x|, |a_y| = {peak[0]:.0f}, {peak[1]:.0f} mm/s^2")
        panel_v.legend(loc="lower left")
        panel_a.legend(loc="lower left")
    a = ax["a"]
    a.plot(path.points[:, 0], path.points[:, 1], "k:", lw=0.8, label="G01 path")
    a.set(xlabel="x [mm]", ylabel="y [mm]", title="(a) cornering trajectory\nF = 50 mm/s, T1 = 20 ms, 2 x 2.5 mm")
    a.set_aspect("equal", adjustable="datalim")
    a.legend(loc="lower center", fontsize=6)
    out = Path(out_dir) / f"{NAME}.png"
    save(fig, out)
    return [out]
