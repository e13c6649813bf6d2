"""Sencer (2009) thesis Fig 5.9 / Table 5.5 and Table 5.4: (a) the tool-tip contour controller's contour
error at 60 mm/s for the three tip bandwidth sets of Table 5.5; (b, c) max and mean tool-tip contour error
of the contour and SISO controllers at 50 / 60 / 80 mm/s beside Table 5.4 (simulation; the thesis' values
are measured); (d) Table 5.5's ratios to its first row, simulated and printed.

Made from the config :data:`CONFIG` (eight ``[[control.cases]]``) through the results store; :func:`plot`
only reads the stored result.
"""

from __future__ import annotations

import numpy as np

from research.figures._style import mosaic

NAME = "sencer2009_fig5_9_bandwidths_feeds"
REPRODUCES = ("Sencer 2009 thesis Table 5.4 (contour vs SISO at 50 / 60 / 80 mm/s) and Table 5.5 / Fig 5.9 "
              "(tip bandwidths at 60 mm/s)")
CONFIG = "experiments/figures/sencer2009_fig5_9_bandwidths_feeds.toml"

FEEDS = (50, 60, 80)
_BANDWIDTHS = (("contour_60", "100 / 230 / 230", "k", "-"), ("bw_100_200_200", "100 / 200 / 200", "C3", "--"),
               ("bw_70_230_230", "70 / 230 / 230", "C0", ":"))


def plot(record: dict, arrays: dict):
    """The figure (not saved) from a stored result of :data:`CONFIG`."""
    s = record["scalars"]
    declared = [(p["key"], p["value"]) for p in record["config"]["paper"]]
    paper = dict(declared)  # the last of a repeated key: contour_60 is Table 5.4's 60 mm/s row (87 / 14 um) ...
    table_5_5 = dict(reversed(declared))  # ... and, declared first, Table 5.5's row 1 (90 / 13 um)
    fig, ax = mosaic([["bw", "bw", "ratio"], ["max", "mean", "key"]], figsize=(13, 8))
    a = ax["bw"]
    for label, wn, colour, ls in _BANDWIDTHS:
        e = arrays[f"control.{label}.tip_contour_error"] * 1e3
        a.semilogy(arrays[f"control.{label}.t"], np.maximum(e, 1e-3), color=colour, ls=ls, lw=0.9,
                   label=f"wn = {wn} rad/s: max {s[f'{label}.tip_contour_error_max'] * 1e3:.2f} / mean "
                         f"{s[f'{label}.tip_contour_error_mean'] * 1e3:.3f} um (thesis "
                         f"{table_5_5[f'{label}.tip_contour_error_max'] * 1e3:g} / {table_5_5[f'{label}.tip_contour_error_mean'] * 1e3:g})")
    a.set(xlabel="time [s]", ylabel="tool-tip contour error [um] (log scale)", ylim=(1e-2, 1e3),
          title="(a) Fig 5.9: contour controller at 60 mm/s, tip bandwidths tangent / normal / binormal (simulation)")
    a.legend(loc="upper right", fontsize=7)
    for key, what in (("max", "max"), ("mean", "mean")):
        a = ax[key]
        for kind, colour, name in (("siso", "0.45", "SISO SMC"), ("contour", "k", "contour controller")):
            sim = [s[f"{kind}_{f}.tip_contour_error_{what}"] * 1e3 for f in FEEDS]
            thesis = [paper[f"{kind}_{f}.tip_contour_error_{what}"] * 1e3 for f in FEEDS]
            a.semilogy(FEEDS, sim, "o-", color=colour, label=f"{name} (simulation)")
            a.semilogy(FEEDS, thesis, "s--", color=colour, mfc="none", label=f"{name} (thesis, measured)")
        a.set(xlabel="feed [mm/s]", ylabel=f"{what} tool-tip contour error [um] (log scale)", xticks=FEEDS,
              title=f"({'b' if key == 'max' else 'c'}) Table 5.4: {what} tool-tip contour error")
    ax["key"].axis("off")
    ax["key"].legend(*ax["max"].get_legend_handles_labels(), loc="center", title="(b), (c)", fontsize=8)
    a = ax["ratio"]
    x = np.arange(2)
    for j, (label, wn, colour, _) in enumerate(_BANDWIDTHS[1:]):
        sim = [s[f"{label}.tip_contour_error_{w}_ratio.contour_60"] for w in ("max", "mean")]
        thesis = [paper[f"{label}.tip_contour_error_{w}_ratio.contour_60"] for w in ("max", "mean")]
        a.bar(x + 0.4 * j - 0.3, sim, 0.18, color=colour, label=f"{wn}: simulation")
        a.bar(x + 0.4 * j - 0.1, thesis, 0.18, color=colour, alpha=0.35, hatch="//", label=f"{wn}: thesis")
    a.axhline(1.0, color="k", lw=0.8)
    a.set(xticks=x, xticklabels=["max", "mean"], ylabel="contour error / row 1 (100 / 230 / 230) [-]", ylim=(0, 1.8),
          title="(d) Table 5.5: ratio to its first row")
    a.legend(loc="upper center", fontsize=7, ncol=2)
    fig.suptitle("Sencer 2009 Table 5.4 / 5.5, Fig 5.9: Fig 5.5 path, Table 5.1 drives (simulation) against the thesis' "
                 "measurements", fontsize=10)
    return fig
