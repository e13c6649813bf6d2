"""Prévost, Lavernhe, Lartigue (HSM 2012) Fig 6: the sharp corner at 10 m/min. (a) CAM path, setpoint,
actual before and after one CEC pass near the corner; (b) e1, eT before; (c) eT after the paper's
single pass ("reduced by twice but is not null"); (d) the stand-in swept: max eT before and after
one pass against the cornering tolerance (5 um, the default read from the Fig 1 text, up to full
overlap) for the stand-in CNC's 24/12 ms filters and for 100/50 ms.

Setup (:func:`research.contour.prevost2012_application2`): stand-in FIR T1 = 24 ms, T2 = 12 ms,
tolerance 5 um, the paper's Ts = 6 ms, Table 6.1 P-PI drive (stand-in).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from research.contour import (
    contour_error,
    execution_errors,
    mirror_single_pass,
    prevost2012_application2,
    simulate_setpoint,
)
from research.figures._style import mosaic, save

NAME = "prevost2012_fig6_cec_corner"
SWEEP_TOLERANCES = (0.005, 0.01, 0.02, 0.05, 10.0)  # [mm]; 10 mm: full overlap
SWEEP_DELAYS = ((0.024, 0.012), (0.1, 0.05))  # [s]
REPRODUCES = "Prévost 2012 Fig 6 (sharp corner: setpoint rounding e1, total error eT halved by CEC)"


def _worst(check) -> str:
    name, ratio = max(((k, float(np.max(v))) for k, v in check.ratios.items()), key=lambda kv: kv[1])
    return f"worst limit ratio: {name} x{ratio:.2f}" + (" (flagged)" if ratio > 1 else "")


def make_figure(out_dir: Path, fast: bool = False) -> list[Path]:
    """Write the figure to ``out_dir``; returns the files written."""
    case = prevost2012_application2()
    actual0 = simulate_setpoint(case.setpoint, case.drive)
    before = execution_errors(case.cam_path, case.setpoint, actual0)
    two = mirror_single_pass(case.problem, limits=case.limits, control_limit=case.control_limit)
    after = execution_errors(case.cam_path, two.setpoint, two.response)
    sweep = {}
    for delays in (SWEEP_DELAYS[:1] if fast else SWEEP_DELAYS):
        rows = []
        for tol in SWEEP_TOLERANCES:
            r = mirror_single_pass(prevost2012_application2(tol, delays).problem)
            rows.append((r.before.max, r.after.max))
        sweep[delays] = np.array(rows)
    t = np.asarray(case.setpoint.t)
    fig, ax = mosaic([["a", "b"], ["c", "d"]], figsize=(12, 8))
    a = ax["a"]
    pts = case.cam_path.points
    a.plot(pts[:, 0], pts[:, 1], "k", label="CAM path")
    a.plot(*np.asarray(case.setpoint.q).T, "r", label="setpoint")
    a.plot(*np.asarray(actual0.position).T, "g", label="actual, before")
    a.plot(*np.asarray(two.setpoint.q).T, "m--", label="CEC setpoint (one pass)")
    a.plot(*np.asarray(two.response.position).T, "b", label="actual, after")
    a.set(xlim=(-0.4, 0.1), ylim=(-0.1, 0.4), xlabel="x [mm]", ylabel="y [mm]", title="(a) near the corner")
    a.set_aspect("equal")
    a.legend(loc="upper left", fontsize=6)
    b = ax["b"]
    b.plot(t, before.e1 * 1e3, "r", label="e1")
    b.plot(t, before.eT * 1e3, "b", label="eT")
    m = before.max_abs()
    e1_fine = contour_error(case.cam_path, case.setpoint.resample(1e-4)).max
    b.set(xlabel="time [s]", ylabel="error [um]",
          title=f"(b) before: max |e1| = {m['e1'] * 1e3:.1f} um at the 6 ms samples ({e1_fine * 1e3:.1f} um between them, "
                f"eps/sqrt 2), max |eT| = {m['eT'] * 1e3:.1f} um")
    b.legend()
    c = ax["c"]
    c.plot(t, before.eT * 1e3, "b:", label="eT before")
    c.plot(t, after.eT * 1e3, "b", label="eT after one pass")
    c.set(xlabel="time [s]", ylabel="error [um]",
          title=f"(c) CEC on the sharp corner: {two.before.max * 1e3:.1f} -> {two.after.max * 1e3:.1f} um "
                f"(x{two.after.max / two.before.max:.2f})\n{_worst(two.limits)}")
    c.legend()
    d = ax["d"]
    x = np.arange(len(SWEEP_TOLERANCES))
    for (delays, rows), colour in zip(sweep.items(), ("C0", "C1")):
        tag = f"FIR {delays[0] * 1e3:.0f}/{delays[1] * 1e3:.0f} ms"
        d.semilogy(x, rows[:, 0] * 1e3, "o:", color=colour, label=f"{tag}: before")
        d.semilogy(x, rows[:, 1] * 1e3, "s-", color=colour,
                   label=f"{tag}: one pass (x{', x'.join(f'{q:.2f}' for q in rows[:, 1] / rows[:, 0])})")
    d.set_xticks(x, [f"{t * 1e3:g} um" for t in SWEEP_TOLERANCES[:-1]] + ["full overlap"])
    d.set(xlabel="cornering tolerance", ylabel="max |eT| [um]",
          title="(d) stand-ins swept: the paper's x0.5 needs the slow filters")
    d.legend(fontsize=6)
    out = Path(out_dir) / f"{NAME}.png"
    save(fig, out)
    return [out]
