"""Feedback against feed-forward on the thesis' Fig 5.5 path at 50 mm/s (issue 17 item 6, beyond the
thesis): SISO SMC, the 5-axis contour controller, and each with 1 and 3 passes of mirror compensation
of its reference (:func:`research.control.feedback_vs_feedforward`). (a) tool-tip contour error,
(b) orientation contour error, (c) the table of max / mean errors and peak axis voltages. Reads the
stored run of :mod:`research.figures.sencer2009_fig5_results`.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from research.figures import sencer2009_fig5_results as stored
from research.figures._style import mosaic, save

NAME = "sencer2009_fig5_feedback_vs_feedforward"
REPRODUCES = ("beyond Sencer 2009: feedback (SISO SMC, tool-tip contour controller) vs mirror feed-forward vs both "
              "on the Fig 5.5 path, 50 mm/s")


def make_figure(out_dir: Path, fast: bool = False) -> list[Path]:
    """Write the figure to ``out_dir``; returns the files written."""
    res = stored.feedforward_comparison(passes=1 if fast else 3, fast=fast)
    fig, ax = mosaic([["a"], ["b"], ["c"]], figsize=(10, 11), height_ratios=(3, 3, 2))
    t = res["t"]
    for i, name in enumerate(res["names"]):
        ax["a"].semilogy(t, np.maximum(res[f"contour_{i}"] * 1e3, 1e-4), lw=0.9, label=name)
        ax["b"].semilogy(t, np.maximum(res[f"orientation_{i}"] * 1e3, 1e-6), lw=0.9, label=name)
    ax["a"].set(xlabel="time [s]", ylabel="tool-tip contour error [um]", title="(a) tool-tip contour error (exact)")
    ax["a"].legend(ncol=2)
    ax["b"].set(xlabel="time [s]", ylabel="orientation contour error [mrad]", title="(b) orientation contour error")
    cells = [[name, f"{s['contour_max'] * 1e3:.2f}", f"{s['contour_mean'] * 1e3:.3f}", f"{s['orientation_max'] * 1e3:.3f}",
              f"{s['orientation_mean'] * 1e3:.4f}", " ".join(f"{u:.1f}" for u in s["u_max"])]
             for name, s in zip(res["names"], res["summaries"])]
    ax["c"].axis("off")
    table = ax["c"].table(cellText=cells, colLabels=["scheme", "tip max [um]", "tip mean [um]", "orient. max [mrad]",
                                                     "orient. mean [mrad]", "peak |u| x y z a c [V]"], loc="center")
    table.auto_set_font_size(False)
    table.set_fontsize(7)
    ax["c"].set(title="(c) max / mean contour errors and peak axis effort")
    out = Path(out_dir) / f"{NAME}.png"
    save(fig, out)
    return [out]
