"""DiMarco 2015 Fig 3: sigmoid-interpolated startup of a linear move for several alpha (eq 3-5).

The blended motion ``x_L = m t (1 - exp(-alpha t^3))`` lags the nominal ramp, its feed overshoots
the commanded ``m`` by ``3 e^(-4/3) = 79 %`` at ``t = (4 / (3 alpha))^(1/3)`` whatever alpha, then
catches up; larger alpha catches up sooner.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from research.figures._style import figure, save
from research.interpolators.sigmoid import Blend, Ramp, SigmoidMotion

NAME = "dimarco2015_fig3_sigmoid_startup"
REPRODUCES = "DiMarco 2015 Fig 3 (sigmoid startup of a linear move for several alpha, eq 3-5)"
FEED = 10.0  # m [mm/s]
ALPHAS = (1.0, 10.0, 100.0, 1000.0)  # [1/s^3]


def make_figure(out_dir: Path, fast: bool = False) -> list[Path]:
    """Write the figure to ``out_dir``; returns the files written."""
    t = np.linspace(0.0, 2.5, 500 if fast else 5000)
    fig, ax = figure(1, 3, figsize=(13, 3.8))
    ax[0].plot(t, FEED * t, "k--", label="nominal x = m t (eq 1)")
    for alpha in ALPHAS:
        x, v, a, _ = SigmoidMotion(((Ramp(FEED), Blend(alpha, 3)),), 0.0).derivatives(t)
        ax[0].plot(t, x, label=f"alpha = {alpha:g} 1/s^3")
        ax[1].plot(t, v, label=f"alpha = {alpha:g}")
        ax[2].plot(t, a, label=f"alpha = {alpha:g}")
    ax[1].axhline(FEED, color="k", ls="--", lw=0.8, label="m")
    ax[1].axhline(FEED * (1 + 3 * np.exp(-4 / 3)), color="C3", ls=":", lw=0.8, label="m (1 + 3 e^-4/3)")
    ax[0].set(xlabel="time [s]", ylabel="position [mm]", title="position (eq 3): lag, then catch-up")
    ax[1].set(xlabel="time [s]", ylabel="velocity [mm/s]", title="velocity (eq 4): overshoot of the feed")
    ax[2].set(xlabel="time [s]", ylabel="acceleration [mm/s^2]", title="acceleration (eq 5): a(0) = 0")
    for a in ax:
        a.legend(loc="best")
    out = Path(out_dir) / f"{NAME}.png"
    save(fig, out)
    return [out]
