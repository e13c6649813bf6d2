"""Sencer 2015 Fig 4: accurate corner blending by G-line overlapping.

Two 2.5 mm G01 lines with a 90 deg corner at F = 50 mm/s through one FIR filter, T1 = 20 ms:
(a) the three cornering trajectories, (b) sharp cornering (T_k = 0: each block takes
T_v + T_1 = 70 ms), (c) full overlap (T_k = T_d: Y reverses at 2 F sin 45 / T1 = 3535 mm/s^2),
(d) half overlap (T_k = T_d / 2 = 10 ms).

Made from the config :data:`CONFIG` through the results store; :func:`plot` only reads the stored
result (the record and its arrays).
"""

from __future__ import annotations

from research.figures._style import AXIS_COLOURS, mosaic
from research.paths import named_path

NAME = "sencer2015_fig4_fir_cornering"
REPRODUCES = "Sencer 2015 Fig 4 (sharp, full-overlap and half-overlap cornering, eq 11-13)"
CONFIG = "experiments/figures/sencer2015_fig4_fir_cornering.toml"
CASES = (("sharp", "sharp, T_k = 0", "k"), ("full", "full overlap, T_k = T_d", "C0"), ("half", "half overlap, T_k = T_d / 2", "C2"))


def plot(record: dict, arrays: dict):
    """The figure (not saved) from a stored result of :data:`CONFIG`."""
    path = named_path(record["config"]["path"]["name"])
    fig, ax = mosaic([["a", "v0", "v1", "v2"], ["a", "a0", "a1", "a2"]], figsize=(14, 5.5))
    for col, (label, text, colour) in enumerate(CASES):
        d = record["details"][label]
        t, q, v, a = (arrays[f"{label}.{k}"] for k in ("t", "q", "v", "a"))
        ax["a"].plot(q[:, 0], q[:, 1], color=colour, label=f"{text}: eps = {d['corner_errors'][0] * 1e3:.0f} um")
        panel_v, panel_a = ax[f"v{col}"], ax[f"a{col}"]
        for k, name in enumerate(record["details"][label]["metrics"]["axes"]):
            panel_v.plot(t * 1e3, v[:, k], color=AXIS_COLOURS[name], label=f"v_{name}")
            panel_a.plot(t * 1e3, a[:, k], color=AXIS_COLOURS[name], label=f"a_{name}")
        panel_v.set(title=f"({'bcd'[col]}) {text}\nT_k = {d['overlap_times'][0] * 1e3:.1f} ms, cycle time "
                          f"{d['metrics']['cycle_time'] * 1e3:.1f} ms", ylabel="velocity [mm/s]")
        peak = d["metrics"]["peak_acceleration"]
        panel_a.set(xlabel="time [ms]", ylabel="acceleration [mm/s^2]",
                    title=f"peak |a_x|, |a_y| = {peak[0]:.0f}, {peak[1]:.0f} mm/s^2")
        panel_v.legend(loc="lower left")
        panel_a.legend(loc="lower left")
    a = ax["a"]
    a.plot(path.points[:, 0], path.points[:, 1], "k:", lw=0.8, label="G01 path")
    a.set(xlabel="x [mm]", ylabel="y [mm]", title="(a) cornering trajectory\nF = 50 mm/s, T1 = 20 ms, 2 x 2.5 mm")
    a.set_aspect("equal", adjustable="datalim")
    a.legend(loc="lower center", fontsize=6)
    return fig

