"""Sencer (2009) thesis Fig 5.7 and 5.8: tool-tip contour error and X, Y, Z, A, C tracking errors on the
Fig 5.5 path at 50 mm/s under the SISO sliding-mode controllers (Table 5.2, Fig 5.7) and under the
5-axis contour controller (Table 5.3, W = 0, Fig 5.8). Simulation (research.control; friction
identified from Fig 5.7's axis maxima, control period 0.1 ms: see research.control._study); the thesis'
curves are experimental. The thesis' printed maxima are drawn as dashed lines.

Made from the config :data:`CONFIG` (two ``[[control.cases]]``) through the results store; :func:`plot`
only reads the stored result.
"""

from __future__ import annotations

import numpy as np
from matplotlib.lines import Line2D

from research.control import FIG5_7_AXIS_PEAKS
from research.figures._style import mosaic

NAME = "sencer2009_fig5_7_siso_vs_contour"
REPRODUCES = "Sencer 2009 thesis Fig 5.7 / 5.8 (SISO SMC vs 5-axis contour controller at 50 mm/s)"
CONFIG = "experiments/figures/sencer2009_fig5_7_siso_vs_contour.toml"

_AXES = (("x", "X", "um"), ("y", "Y", "um"), ("z", "Z", "um"), ("a", "A", "mrad"), ("c", "C", "mrad"))
_STYLE = {"siso": dict(color="0.55", lw=0.8, label="SISO SMC (Fig 5.7)"),
          "contour": dict(color="k", lw=0.8, label="contour controller (Fig 5.8)")}


def _paper(record: dict) -> dict[str, float]:
    """``{key: value}`` of the config's declared thesis numbers."""
    return {p["key"]: p["value"] for p in record["config"]["paper"]}


def plot(record: dict, arrays: dict):
    """The figure (not saved) from a stored result of :data:`CONFIG`."""
    s, paper = record["scalars"], _paper(record)
    fig, ax = mosaic([["tip", "tip"], ["x", "a"], ["y", "c"], ["z", "key"]], figsize=(11, 10))
    a = ax["tip"]
    for label in ("siso", "contour"):
        e = arrays[f"control.{label}.tip_contour_error"] * 1e3
        a.semilogy(arrays[f"control.{label}.t"], np.maximum(e, 1e-3), **(_STYLE[label] | {
            "label": f"{_STYLE[label]['label']}: max {s[f'{label}.tip_contour_error_max'] * 1e3:.1f} / "
                     f"mean {s[f'{label}.tip_contour_error_mean'] * 1e3:.2f} um"}))
        thesis = paper[f"{label}.tip_contour_error_max"] * 1e3
        a.axhline(thesis, color=_STYLE[label]["color"], ls="--", lw=1,
                  label=f"thesis max {thesis:g} um ({'Fig 5.7a' if label == 'siso' else 'Fig 5.8a'}, measured)")
    a.set(xlabel="time [s]", ylabel="tool-tip contour error [um] (log scale)", ylim=(1e-2, 3e4),
          title="(a) exact tool-tip contour error, 50 mm/s (simulation)")
    a.legend(loc="upper right", fontsize=7, ncol=2)
    for k, (axis, name, unit) in enumerate(_AXES):
        a = ax[axis]
        for label in ("siso", "contour"):
            a.plot(arrays[f"control.{label}.t"], arrays[f"control.{label}.axis_error"][:, k] * 1e3, **_STYLE[label])
        marks = [("siso", FIG5_7_AXIS_PEAKS[k] * 1e3, "Fig 5.7 (friction input)")]
        if f"contour.axis_error_max.{axis}" in paper:
            marks.append(("contour", paper[f"contour.axis_error_max.{axis}"] * 1e3, "Fig 5.8"))
        for label, v, what in marks:
            for sign in (1, -1):
                a.axhline(sign * v, color=_STYLE[label]["color"], ls="--", lw=0.8)
        metric = "axis_error_max" if k < 3 else "rotary_axis_error_max"
        sim = ", ".join(f"{lb} {s[f'{lb}.{metric}.{axis}'] * 1e3:.3g}" for lb in ("siso", "contour"))
        same = " (identical: W = 0)" if k >= 3 else ""
        a.set(xlabel="time [s]", ylabel=f"{name} tracking error [{unit}]", title=f"{name} axis: max |e| {sim} {unit}{same}")
    key = ax["key"]
    key.axis("off")
    key.legend(handles=[Line2D([], [], **_STYLE["siso"]), Line2D([], [], **_STYLE["contour"]),
                        Line2D([], [], color=_STYLE["siso"]["color"], ls="--", label="thesis max, Fig 5.7 (SISO; the friction "
                                                                                      "is identified from these)"),
                        Line2D([], [], color="k", ls="--", label="thesis max, Fig 5.8 (contour controller)")],
               loc="center", title="axis tracking errors e = q_ref - q (simulation)", fontsize=8)
    fig.suptitle("Sencer 2009 Fig 5.7 / 5.8: SISO SMC (Table 5.2) vs 5-axis contour controller (Table 5.3, W = 0)",
                 fontsize=10)
    return fig
