"""Prévost, Lavernhe, Lartigue (HSM 2012) Fig 6: the sharp corner at 10 m/min. (a) CAM path, setpoint,
actual before and after CEC near the corner; (b) e1, eT before; (c) eT after two mirror passes (the
paper's "reduced by twice"); (d) the suggestion taken further: a tangent-continuous target within
17 um of the corner and a Q-filtered mirror, 12 passes.

Setup (:func:`research.contour.prevost2012_application2`): FIR T1 = 100 ms, T2 = 50 ms, cornering
tolerance 24 um (e1 = 17 um from the lines), Ts = 1 ms, Table 6.1 P-PI drive.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from research.contour import (
    execution_errors,
    mirror_passes,
    prevost2012_application2,
    simulate_setpoint,
    smoothed_corner_case,
)
from research.figures._style import mosaic, save

NAME = "prevost2012_fig6_cec_corner"
REPRODUCES = "Prévost 2012 Fig 6 (sharp corner: setpoint rounding e1, total error eT halved by CEC)"


def _worst(check) -> str:
    name, ratio = max(((k, float(np.max(v))) for k, v in check.ratios.items()), key=lambda kv: kv[1])
    return f"worst limit ratio: {name} x{ratio:.2f}" + (" (flagged)" if ratio > 1 else "")


def make_figure(out_dir: Path, fast: bool = False) -> list[Path]:
    """Write the figure to ``out_dir``; returns the files written."""
    case = prevost2012_application2()
    actual0 = simulate_setpoint(case.setpoint, case.drive)
    before = execution_errors(case.cam_path, case.setpoint, actual0)
    two = mirror_passes(case.problem, 2, limits=case.limits, control_limit=case.control_limit)
    after = execution_errors(case.cam_path, two.setpoint, two.response)
    smooth = smoothed_corner_case(case)
    taken = mirror_passes(smooth.problem, 12, smoothing=11, limits=smooth.limits, control_limit=smooth.control_limit)
    t = np.asarray(case.setpoint.t)
    fig, ax = mosaic([["a", "b"], ["c", "d"]], figsize=(12, 8))
    a = ax["a"]
    pts = case.cam_path.points
    a.plot(pts[:, 0], pts[:, 1], "k", label="CAM path")
    a.plot(*np.asarray(case.setpoint.q).T, "r", label="setpoint")
    a.plot(*np.asarray(actual0.position).T, "g", label="actual, before")
    a.plot(*np.asarray(two.setpoint.q).T, "m--", label="CEC setpoint (2 passes)")
    a.plot(*np.asarray(two.response.position).T, "b", label="actual, after")
    a.set(xlim=(-0.12, 0.06), ylim=(-0.06, 0.12), xlabel="x [mm]", ylabel="y [mm]", title="(a) near the corner")
    a.set_aspect("equal")
    a.legend(loc="upper left", fontsize=6)
    b = ax["b"]
    b.plot(t, before.e1 * 1e3, "r", label="e1")
    b.plot(t, before.eT * 1e3, "b", label="eT")
    m = before.max_abs()
    b.set(xlabel="time [s]", ylabel="error [um]", title=f"(b) before: max |e1| = {m['e1'] * 1e3:.1f} um, max |eT| = {m['eT'] * 1e3:.1f} um")
    b.legend()
    c = ax["c"]
    c.plot(t, before.eT * 1e3, "b:", label="eT before")
    c.plot(t, after.eT * 1e3, "b", label="eT after 2 passes")
    c.set(xlabel="time [s]", ylabel="error [um]",
          title=f"(c) CEC on the sharp corner: {two.before.max * 1e3:.1f} -> {two.after.max * 1e3:.1f} um "
                f"(x{two.after.max / two.before.max:.2f})\n{_worst(two.limits)}")
    c.legend()
    d = ax["d"]
    d.plot(np.arange(13), np.concatenate([[taken.before.max], taken.history]) * 1e3, "o-", label="C2 target, Q-filter 11 ms")
    d.plot(np.arange(3), np.concatenate([[two.before.max], two.history]) * 1e3, "s-", label="sharp CAM corner")
    d.set(xlabel="mirror passes", ylabel="max |eT| [um]",
          title=f"(d) tangent-continuous target: {taken.before.max * 1e3:.1f} -> {taken.after.max * 1e3:.1f} um\n"
                f"{_worst(taken.limits)}")
    d.legend()
    out = Path(out_dir) / f"{NAME}.png"
    save(fig, out)
    return [out]
