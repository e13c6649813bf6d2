"""Sencer (2009) thesis Fig 5.10: orientation contour error (angle between the actual tool axis and the
reference orientation path, §4.5 / eq 5.40) at 50 mm/s for the coupling weights W = diag(w, w),
w = 0, 3, 4, 5, and its mean against w (simulation; thesis curves experimental). A second file is the
thesis Fig 4.7 check on its own SMC drives (SISO, 50 mm/s): the eq 4.34/4.35 orientation contour error
estimate against the exact one and their difference (thesis: below 6 urad). Reads the stored runs of
:mod:`research.figures.sencer2009_fig5_results`.
"""

from __future__ import annotations

from pathlib import Path

from research.control import FIG5_10_WEIGHTS
from research.figures import sencer2009_fig5_results as stored
from research.figures._style import figure, save

NAME = "sencer2009_fig5_10_orientation_weights"
REPRODUCES = ("Sencer 2009 thesis Fig 5.10 (orientation contour error for W = 0, 3, 4, 5: steady decline of the mean) "
              "and Fig 4.7 (eq 4.35 estimate within 6 urad of the true orientation contour error)")


def make_figure(out_dir: Path, fast: bool = False) -> list[Path]:
    """Write the figure to ``out_dir``; returns the files written."""
    out_dir = Path(out_dir)
    fig, ax = figure(1, 2, figsize=(11, 4), width_ratios=(3, 1))
    means = []
    weights = (0.0, 5.0) if fast else FIG5_10_WEIGHTS  # fast: the end points only
    for w, style in zip(weights, ("k", "C0", "C1", "C2")):
        run = stored.case("contour", W=w, fast=fast)
        means.append(run["summary"]["orientation_mean"] * 1e3)
        ax[0].plot(run["t"], run["orientation"] * 1e3, style, lw=0.9, label=f"W = diag({w:g}, {w:g})")
    ax[0].set(xlabel="time [s]", ylabel="orientation contour error [mrad]", title="(a) orientation contour error, 50 mm/s")
    ax[0].legend()
    ax[1].plot(weights, means, "ko-")
    ax[1].set(xlabel="w", ylabel="mean [mrad]", title="(b) mean orientation contour error")
    out = out_dir / f"{NAME}.png"
    save(fig, out)

    siso = stored.case("siso", fast=fast)
    fig, ax = figure(2, 1, figsize=(9, 6), sharex=True)
    ax[0].plot(siso["t"], siso["orientation"] * 1e3, "k", label="exact (closest reference orientation)")
    ax[0].plot(siso["t"], siso["orientation_estimate"] * 1e3, "C1--", label="|J_o eps_R|, eq 4.34/4.35")
    ax[0].set(ylabel="[mrad]", title="Fig 4.7: orientation contour error under the SISO SMC drives, 50 mm/s")
    ax[0].legend()
    d = (siso["orientation_estimate"] - siso["orientation"]) * 1e6
    ax[1].plot(siso["t"], d, "k")
    ax[1].axhline(6, color="r", ls=":", label="thesis bound 6 urad")
    ax[1].axhline(-6, color="r", ls=":")
    ax[1].set(xlabel="time [s]", ylabel="estimate - exact [urad]", title=f"discrepancy, max |.| = {abs(d).max():.2f} urad")
    ax[1].legend()
    out2 = out_dir / f"{NAME}_fig4_7.png"
    save(fig, out2)
    return [out, out2]
