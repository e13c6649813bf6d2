"""Sencer (2009) thesis Fig 5.7 and 5.8: tool-tip contour error and X, Y, Z, A, C tracking errors on the
Fig 5.5 path at 50 mm/s under the SISO sliding-mode controllers (Table 5.2, Fig 5.7) and under the
5-axis contour controller (Table 5.3, W = 0, Fig 5.8). Simulation (research.control; friction
identified from Fig 5.7's axis maxima, control period 0.1 ms: see research.control._study); the thesis'
curves are experimental. Reads the stored runs of :mod:`research.figures.sencer2009_fig5_results`.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from research.control import FIG5_7_AXIS_PEAKS, FIG5_7_CONTOUR, FIG5_8_AXIS_PEAKS
from research.figures import sencer2009_fig5_results as stored
from research.figures._style import mosaic, save

NAME = "sencer2009_fig5_7_siso_vs_contour"
REPRODUCES = ("Sencer 2009 thesis Fig 5.7 (SISO SMC: max e_x 15 um, e_y 13, e_z 7, e_a 2.2 mrad, e_c 1.7 mrad; "
              "contour mean 45 / max 317 um) and Fig 5.8 (contour controller: mean 10 / max 79 um; "
              "e_x 130, e_y 216, e_z 130 um)")
_LABELS = ("X [um]", "Y [um]", "Z [um]", "A [mrad]", "C [mrad]")


def _one(out_dir: Path, tag: str, runs, title: str) -> Path:
    fig, ax = mosaic([["a", "a"], ["b", "e"], ["c", "f"], ["d", "."]], figsize=(10, 9))
    for label, run, style in runs:
        s = run["summary"]
        ax["a"].plot(run["t"], run["contour"] * 1e3, style,
                     label=f"{label}: mean {s['contour_mean'] * 1e3:.1f} / max {s['contour_max'] * 1e3:.1f} um")
    ax["a"].set(xlabel="time [s]", ylabel="contour error [um]", title=f"(a) tool-tip contour error (exact), {title}")
    ax["a"].legend()
    main = runs[-1][1]
    for k, key in enumerate("bcdef"):
        e = main["axis_error"][:, k] * 1e3
        ax[key].plot(main["t"], e, "k")
        ax[key].set(xlabel="time [s]", ylabel=_LABELS[k], title=f"({key}) axis tracking error, max {np.abs(e).max():.2f}")
    out = out_dir / f"{NAME}_{tag}.png"
    save(fig, out)
    return out


def make_figure(out_dir: Path, fast: bool = False) -> list[Path]:
    """Write the Fig 5.7 and Fig 5.8 panels to ``out_dir``; returns the files written."""
    out_dir = Path(out_dir)
    siso = stored.case("siso", fast=fast)
    contour = stored.case("contour", fast=fast)
    thesis7 = ", ".join(f"{v * 1e3:g}" for v in FIG5_7_AXIS_PEAKS)
    thesis8 = ", ".join(f"{v * 1e3:g}" for v in FIG5_8_AXIS_PEAKS)
    return [
        _one(out_dir, "fig5_7", [("SISO SMC (sim.)", siso, "k")],
             f"SISO (thesis: mean {FIG5_7_CONTOUR['mean'] * 1e3:g} / max {FIG5_7_CONTOUR['max'] * 1e3:g} um; axis maxima {thesis7})"),
        _one(out_dir, "fig5_8", [("SISO SMC (sim.)", siso, "0.6"), ("contour controller (sim.)", contour, "k")],
             f"contour controller (thesis: mean 10 / max 79 um; X, Y, Z maxima {thesis8} um)"),
    ]
