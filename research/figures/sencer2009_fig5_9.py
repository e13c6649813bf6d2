"""Sencer (2009) thesis Fig 5.9 / Table 5.5 and Table 5.4: the tool-tip contour controller's contour
error for the three bandwidth sets of Table 5.5 at 60 mm/s, and max / mean contour error of the
contour and SISO controllers at 50 / 60 / 80 mm/s against Table 5.4 (simulation; thesis values are
experimental). Reads the stored runs of :mod:`research.figures.sencer2009_fig5_results`.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from research.control import TABLE_5_4, TABLE_5_5
from research.figures import sencer2009_fig5_results as stored
from research.figures._style import figure, save

NAME = "sencer2009_fig5_9_bandwidths_feeds"
REPRODUCES = ("Sencer 2009 thesis Fig 5.9 / Table 5.5 (directional bandwidths at 60 mm/s: 90/13, 115/18, 93/12 um) "
              "and Table 5.4 (contour vs SISO max/mean at 50/60/80 mm/s)")
FEEDS = (50.0, 60.0, 80.0)


def make_figure(out_dir: Path, fast: bool = False) -> list[Path]:
    """Write the Fig 5.9 and Table 5.4 panels to ``out_dir``; returns the files written."""
    out_dir = Path(out_dir)
    fig, ax = figure(figsize=(9, 4))
    for (wn, (tmax, tmean)), style in zip(TABLE_5_5.items(), ("k", "C0--", "C1:")):
        run = stored.case("contour", feed=60.0, wn=wn, fast=fast)
        s = run["summary"]
        ax.plot(run["t"], run["contour"] * 1e3, style,
                label=f"wn = {tuple(int(w) for w in wn)}: sim {s['contour_max'] * 1e3:.1f} / {s['contour_mean'] * 1e3:.2f} um "
                      f"(thesis {tmax:g} / {tmean:g})")
    ax.set(xlabel="time [s]", ylabel="contour error [um]", title="Fig 5.9: tool-tip contour error at 60 mm/s, max / mean")
    ax.legend()
    out1 = out_dir / f"{NAME}_fig5_9.png"
    save(fig, out1)

    fig, ax = figure(1, 2, figsize=(10, 4))
    feeds = (50.0, 80.0) if fast else FEEDS  # fast: the end points only
    sim = {kind: np.array([[stored.case(kind, feed=f, fast=fast)["summary"][k] for k in ("contour_max", "contour_mean")]
                           for f in feeds]) * 1e3 for kind in ("contour", "siso")}
    thesis = np.array([TABLE_5_4[f] for f in FEEDS]) * 1e3
    for j, what in enumerate(("max", "mean")):
        ax[j].semilogy(feeds, sim["siso"][:, j], "ko-", label="SISO (sim.)")
        ax[j].semilogy(FEEDS, thesis[:, 2 + j], "ks--", mfc="none", label="SISO (thesis)")
        ax[j].semilogy(feeds, sim["contour"][:, j], "C0o-", label="contour controller (sim.)")
        ax[j].semilogy(FEEDS, thesis[:, j], "C0s--", mfc="none", label="contour controller (thesis)")
        ax[j].set(xlabel="feed [mm/s]", ylabel=f"{what} contour error [um]", title=f"Table 5.4: {what} tool-tip contour error")
    ax[0].legend()
    out2 = out_dir / f"{NAME}_table5_4.png"
    save(fig, out2)
    return [out1, out2]
