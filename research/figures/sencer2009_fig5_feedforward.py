"""Feedback against feed-forward on the thesis' Fig 5.5 path at 50 mm/s (issue 17 item 6, beyond the
thesis): SISO SMC, the 5-axis contour controller, and each with 1 and 3 passes of mirror compensation of
its reference (:func:`research.control.tracking_mirror_passes`). (a) tool-tip contour error,
(b) orientation contour error, (c) the table of max / mean errors and peak axis voltages.

Made from the config :data:`CONFIG` (six ``[[control.cases]]``) through the results store; :func:`plot`
only reads the stored result.
"""

from __future__ import annotations

import numpy as np

from research.figures._style import mosaic

NAME = "sencer2009_fig5_feedback_vs_feedforward"
REPRODUCES = ("beyond Sencer 2009: feedback (SISO SMC, contour controller) vs mirror feed-forward vs both on the "
              "Fig 5.5 path, 50 mm/s")
CONFIG = "experiments/figures/sencer2009_fig5_feedback_vs_feedforward.toml"

_SCHEMES = (("siso", "SISO SMC", "0.5", "-"), ("siso_mirror1", "SISO SMC + mirror, 1 pass", "C0", "-"),
            ("siso_mirror3", "SISO SMC + mirror, 3 passes", "C2", "-"), ("contour", "contour controller", "k", "--"),
            ("contour_mirror1", "contour controller + mirror, 1 pass", "C1", "--"),
            ("contour_mirror3", "contour controller + mirror, 3 passes", "C3", "--"))


def plot(record: dict, arrays: dict):
    """The figure (not saved) from a stored result of :data:`CONFIG`."""
    s = record["scalars"]
    fig, ax = mosaic([["a"], ["b"], ["c"]], figsize=(10, 11), height_ratios=(3, 3, 2))
    for label, name, colour, ls in _SCHEMES:
        t = arrays[f"control.{label}.t"]
        ax["a"].semilogy(t, np.maximum(arrays[f"control.{label}.tip_contour_error"] * 1e3, 1e-4), color=colour, ls=ls,
                         lw=0.8, label=name)
        ax["b"].semilogy(t, np.maximum(arrays[f"control.{label}.orientation_error"] * 1e3, 1e-5), color=colour, ls=ls,
                         lw=0.8, label=name)
    ax["a"].set(xlabel="time [s]", ylabel="tool-tip contour error [um] (log scale)", ylim=(1e-4, 1e5),
                title="(a) exact tool-tip contour error, 50 mm/s (simulation)")
    ax["a"].legend(loc="upper center", ncol=2, fontsize=7)
    ax["b"].set(xlabel="time [s]", ylabel="orientation contour error [mrad] (log scale)", ylim=(1e-4, 1e2),
                title="(b) orientation contour error (W = 0: contour runs on their SISO twins; eq 5.40 resolves 2e-8 rad)")
    ax["b"].legend(loc="upper center", ncol=2, fontsize=7)
    cells = [[name, f"{s[f'{lb}.tip_contour_error_max'] * 1e3:.2f}", f"{s[f'{lb}.tip_contour_error_mean'] * 1e3:.3f}",
              f"{s[f'{lb}.orientation_error_max'] * 1e3:.3f}", f"{s[f'{lb}.orientation_error_mean'] * 1e3:.4f}",
              " ".join(f"{s[f'{lb}.control_voltage_max.{a}']:.1f}" for a in "xyzac")]
             for lb, name, _, _ in _SCHEMES]
    ax["c"].axis("off")
    table = ax["c"].table(cellText=cells, colLabels=["scheme", "tip max [um]", "tip mean [um]", "orient. max [mrad]",
                                                     "orient. mean [mrad]", "peak |u| x y z a c [V]"], loc="center",
                          colWidths=(0.3, 0.11, 0.11, 0.13, 0.13, 0.22))
    table.auto_set_font_size(False)
    table.set_fontsize(7)
    ax["c"].set(title="(c) max / mean contour errors and peak axis effort")
    return fig
