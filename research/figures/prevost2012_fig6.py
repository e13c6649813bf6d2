"""Prévost, Lavernhe, Lartigue (HSM 2012) Fig 6: the sharp corner at 10 m/min. (a) CAM path, setpoint,
actual before and after one CEC pass near the corner; (b) e1 (setpoint to CAM path) and eT before;
(c) eT after the paper's single pass ("reduced by twice but is not null"); (d) max eT before and after
one pass for each case of the config: the stand-in (FIR 24/12 ms, 5 um), full overlap, and full overlap
with 100/50 ms filters.

Setup (the config; :func:`research.contour.prevost2012_application2` holds the same stand-ins): FIR
T1 = 24 ms, T2 = 12 ms, tolerance 5 um, the paper's Ts = 6 ms, Table 6.1 P-PI drive (stand-in).

Made from the config :data:`CONFIG` through the results store; :func:`plot` only reads the stored result.
"""

from __future__ import annotations

import numpy as np

from research.figures._style import mosaic
from research.paths import named_path

NAME = "prevost2012_fig6_cec_corner"
REPRODUCES = "Prévost 2012 Fig 6 (sharp corner: setpoint rounding e1, total error eT halved by CEC)"
CONFIG = "experiments/figures/prevost2012_fig6_cec_corner.toml"
MAIN = "standin"  # the case of panels (a)-(c)


def plot(record: dict, arrays: dict):
    """The figure (not saved) from a stored result of :data:`CONFIG`."""
    s, cases = record["scalars"], [i["label"] for i in record["config"]["interpolator"]]
    g = lambda k: arrays[f"{MAIN}.{k}"]  # noqa: E731
    t = g("t")
    n = t.size
    fig, ax = mosaic([["a", "b"], ["c", "d"]], figsize=(12, 8))
    a = ax["a"]
    pts = named_path(record["config"]["path"]["name"]).points
    a.plot(pts[:, 0], pts[:, 1], "k", label="CAM path")
    a.plot(*g("q").T, "r", label="setpoint")
    a.plot(*g("actual")[:n].T, "g", label="actual, before")
    a.plot(*g("cec.q").T, "m--", label="CEC setpoint (one pass)")
    a.plot(*g("cec.actual")[:n].T, "b", label="actual, after")
    a.set(xlim=(-0.4, 0.1), ylim=(-0.1, 0.4), xlabel="x [mm]", ylabel="y [mm]", title="(a) near the corner")
    a.set_aspect("equal")
    a.legend(loc="upper left", fontsize=6)
    b = ax["b"]
    e1, eT = g("cec.setpoint_error_before"), g("cec.error_before")
    b.plot(t, e1 * 1e3, "r", label="e1 (setpoint to CAM path)")
    b.plot(t, eT[:n] * 1e3, "b", label="eT (actual to CAM path)")
    b.set(xlabel="time [s]", ylabel="error [um]",
          title=f"(b) before: max e1 = {e1.max() * 1e3:.1f} um at the 6 ms samples ({s[f'{MAIN}.max_corner_error'] * 1e3:.1f} um "
                f"between them, at the corner),\nmax eT = {s[f'{MAIN}.cec_error_before'] * 1e3:.1f} um")
    b.legend(loc="upper right", fontsize=7)
    c = ax["c"]
    c.plot(t, eT[:n] * 1e3, "b:", label="eT before")
    c.plot(t, g("cec.error_after")[:n] * 1e3, "b", label="eT after one pass")
    c.set(xlabel="time [s]", ylabel="error [um]",
          title=f"(c) CEC on the sharp corner: {s[f'{MAIN}.cec_error_before'] * 1e3:.1f} -> "
                f"{s[f'{MAIN}.cec_error_after'] * 1e3:.1f} um (x{s[f'{MAIN}.cec_error_ratio']:.2f}; the paper: x0.5)")
    c.legend(loc="upper right", fontsize=7)
    d = ax["d"]
    x = np.arange(len(cases))
    before = np.array([s[f"{k}.cec_error_before"] for k in cases]) * 1e3
    after = np.array([s[f"{k}.cec_error_after"] for k in cases]) * 1e3
    d.semilogy(x, before, "o:", color="C0", label="before")
    d.semilogy(x, after, "s-", color="C1", label="after one pass")
    for i in x:
        d.annotate(f"x{after[i] / before[i]:.2f}", (i, after[i]), textcoords="offset points", xytext=(6, -10), fontsize=7)
    labels = []
    for ic in record["config"]["interpolator"]:
        tol = "full overlap" if ic["tolerance_um"] >= 1000 else f"{ic['tolerance_um']:g} um"
        labels.append(f"{ic['delays_ms'][0]:g}/{ic['delays_ms'][1]:g} ms\n{tol}")
    d.set_xticks(x, labels, fontsize=7)
    d.set(xlabel="FIR delays, cornering tolerance", ylabel="max |eT| [um]", title="(d) the config's cases: max eT before / after")
    d.legend(loc="upper left", fontsize=7)
    return fig
