"""Optimality study (README "Optimality study"): FIR overlap (Sencer 2015, plain and holding the limits) against
the converged time-optimal OCP in the same 500 um tube, F = 250 mm/s, T = 148 / 89 ms. (a) cycle times per path
and limit convention (a: the FIR's own axis peaks; b: its nominal envelope), with the lower bound L_cut / F;
(b) the ratios to the OCP, the README table's values (declared in the config as model predictions) marked;
(c, d) the paths (tube corner detail) with the FIR and OCP motions under limits a.

Made from the config :data:`CONFIG` through the results store; :func:`plot` only reads the stored result.
"""

from __future__ import annotations

import numpy as np

from research.figures._style import mosaic

NAME = "optimality_fir_vs_ocp"
REPRODUCES = ("FIR overlap (plain, limits held) against the time-optimal OCP: cycle times and ratios of the README's "
              "optimality table (corner90, diamond)")
CONFIG = "experiments/figures/optimality_fir_vs_ocp.toml"
METHODS = (("fir", "FIR overlap (paper)", "C0"), ("fir_held", "FIR overlap, limits held", "C1"),
           ("ocp", "time-optimal OCP", "C2"))


def plot(record: dict, arrays: dict):
    """The figure (not saved) from a stored result of :data:`CONFIG`."""
    s, c = record["scalars"], record["config"]["optimality"]
    cases = [(p, v) for p in c["paths"] for v in c["conventions"]]
    predicted = {p["key"]: p["value"] for p in record["config"].get("paper", [])}
    paths = list(c["paths"])
    fig, ax = mosaic([["times", "ratios"], paths[:2] if len(paths) >= 2 else [paths[0], "ratios"]], figsize=(13, 9))
    x = np.arange(len(cases))
    w = 0.26
    a = ax["times"]
    for i, (key, label, color) in enumerate(METHODS):
        a.bar(x + (i - 1) * w, [s[f"{p}.{v}.{key}_cycle_time"] for p, v in cases], w, color=color, label=label)
    bound = [s[f"{p}.{v}.ocp_cycle_time"] / s[f"{p}.{v}.ocp_bound_ratio"] for p, v in cases]
    a.plot(x, bound, "k_", ms=30, mew=2, label="lower bound L_cut / F")
    a.set_xticks(x, [f"{p}\nlimits {v}" for p, v in cases])
    a.set(ylabel="cycle time [s]", title="(a) cycle time (F = 250 mm/s, eps = 500 um, T = 148/89 ms)")
    a.legend(loc="upper left", fontsize=7)
    b = ax["ratios"]
    for i, (key, label, color) in enumerate(METHODS[:2]):
        r = [s[f"{p}.{v}.{key}_ocp_ratio"] for p, v in cases]
        b.bar(x + (i - 0.5) * w, r, w, color=color, label=f"{label} / OCP")
        for xi, ri, (p, v) in zip(x + (i - 0.5) * w, r, cases):
            b.annotate(f"{ri:.3f}", (xi, ri), textcoords="offset points", xytext=(0, 3), ha="center", fontsize=7)
            k = f"{p}.{v}.{key}_ocp_ratio"
            if k in predicted:
                b.plot(xi, predicted[k], "k*", ms=8, label="README table (model prediction)" if (i, p, v) == (0, *cases[0]) else None)
    b.axhline(1.0, color="C2", lw=1)
    b.set_xticks(x, [f"{p}\nlimits {v}" for p, v in cases])
    b.set(ylabel="T / T_OCP [-]", ylim=(0.9, None), title="(b) cycle time / time-optimal OCP")
    b.legend(loc="upper left", fontsize=7)
    for n, p in enumerate(paths[:2]):
        a = ax[p]
        pts = arrays[f"opt.{p}.points"]
        a.plot(pts[:, 0], pts[:, 1], "k", lw=0.8, label="path (G01)")
        conv = "a" if "a" in c["conventions"] else c["conventions"][0]
        for key, label, color in METHODS:
            q = arrays[f"opt.{p}.{conv}.{key}.q"]
            a.plot(q[:, 0], q[:, 1], color=color, lw=1, label=label)
        corner = pts[1]
        r = 4 * c["tolerance_um"] * 1e-3
        a.set(xlim=(corner[0] - r, corner[0] + r), ylim=(corner[1] - r, corner[1] + r), xlabel="x [mm]", ylabel="y [mm]",
              title=f"({'cd'[n]}) {p}, limits {conv}: first corner (tube radius {c['tolerance_um']:g} um)")
        a.set_aspect("equal")
        a.legend(loc="best", fontsize=7)
    return fig
