"""Sencer (2009) thesis §6.5.3, Table 6.3 and Fig 6.13: each axis of the Table 6.3 virtual 5-axis machine
identified with LS (eq 6.12) and PSO (§6.4) on the §6.5 program, the estimate columns beside the thesis' "Actual"
and "PSO Estimated" columns, and the tool-tip contour error of the Chapter 4 spiral (eq 4.36) at 75 mm/s predicted
with the identified models against the true machine (thesis: "The discrepancy between the estimated and true
contour errors is observed to be less than 10 [micron]"). Simulation; assumptions in
:mod:`research.contour._identified_machine`.

Made from the config :data:`CONFIG` (the ``[identified_contour]`` stage) through the results store; :func:`plot`
only reads the stored result.
"""

from __future__ import annotations

import numpy as np

from research.figures._style import mosaic

NAME = "sencer2009_fig6_13_identified_5axis"
REPRODUCES = ("Sencer 2009 thesis Table 6.3 (LS / PSO estimates of the P-PI virtual 5-axis machine) and Fig 6.13 "
              "(identified models predict the 5-axis contour error at 75 mm/s within 10 um of the true machine)")
CONFIG = "experiments/figures/sencer2009_fig6_13_identified_5axis.toml"
_COLUMNS = ("actual", "ls", "pso", "thesis_pso")
BOUND_UM = 10.0  # thesis §6.5.3: discrepancy "less than 10 [micron]"


def _fmt(v) -> str:
    return "-" if v is None else (("yes" if v else "no") if isinstance(v, bool) else f"{v:.4g}")


def plot(record: dict, arrays: dict):
    """The figure (not saved) from a stored result of :data:`CONFIG`."""
    d = record["details"]["identified_contour"]
    t, true = arrays["identified_contour.t"], arrays["identified_contour.true"]
    fig, ax = mosaic([["a", "a"], ["b", "t"]], figsize=(13, 9))
    ax["a"].plot(t, true * 1e3, "k", lw=1.6, label="true Table 6.3 machine")
    for m, style in (("ls", "C0--"), ("pso", "C3:")):
        key = f"identified_contour.{m}"
        if key in arrays:
            dis = np.abs(arrays[key] - true) * 1e3
            ax["a"].plot(t, arrays[key] * 1e3, style, label=f"{m.upper()}-identified models (max discrepancy "
                                                            f"{dis.max():.2f} um)")
            ax["b"].semilogy(t, np.maximum(dis, 1e-4), style, label=f"{m.upper()}: max {dis.max():.2f} um")
    ax["a"].set(xlabel="time [s]", ylabel="tool-tip contour error [um]",
                title="(a) Fig 6.13: eq 4.36 spiral at 75 mm/s, 1500 mm/s^2: true and predicted contour error (exact)")
    ax["a"].legend(loc="upper right")
    ax["b"].axhline(BOUND_UM, color="C1", lw=1.2, label="thesis: 'less than 10 [micron]'")
    ax["b"].set(xlabel="time [s]", ylabel="|predicted - true| [um]", ylim=(1e-4, 100),
                title="(b) discrepancy (log scale; floor 1e-4 um)")
    ax["b"].legend(loc="upper center", ncol=3)  # between 10 and 100 um, above the data
    rows = [[a.upper(), c.replace("thesis_pso", "PSO thesis").replace("ls", "LS").replace("pso", "PSO"),
             *(_fmt(x) for x in cols[c][:4]), _fmt(cols[c][4])]
            for a, cols in d["columns"].items() for c in _COLUMNS]
    t_ax = ax["t"]
    t_ax.axis("off")
    tab = t_ax.table(cellText=rows, colLabels=["axis", "column", "wn [Hz]", "zeta", "p [Hz]", "dc", "stable"],
                     loc="center", fontsize=7)
    tab.scale(1, 0.9)
    t_ax.set_title("Table 6.3: actual, LS and PSO (this run), PSO (thesis, printed as is); dc [mm/s^2, rad/s^2]", pad=4)
    if d["excluded"]:
        fig.text(0.5, 0.005, "excluded: " + "; ".join(f"{k}: {v}" for k, v in d["excluded"].items()), ha="center",
                 fontsize=7)
    return fig
