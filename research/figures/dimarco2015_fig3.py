"""DiMarco 2015 Fig 3: sigmoid-interpolated startup of a linear move for several alpha (eq 3-5).

The blended motion ``x_L = m t (1 - exp(-alpha t^3))`` lags the nominal ramp, its feed overshoots
the commanded ``m`` by ``3 e^(-4/3) = 79 %`` at ``t = (4 / (3 alpha))^(1/3)`` whatever alpha, then
catches up; larger alpha catches up sooner.

Made from the config :data:`CONFIG` through the results store; :func:`plot` only reads the stored result.
"""

from __future__ import annotations

import numpy as np

from research.figures._style import figure

NAME = "dimarco2015_fig3_sigmoid_startup"
REPRODUCES = "DiMarco 2015 Fig 3 (sigmoid startup of a linear move for several alpha, eq 3-5)"
CONFIG = "experiments/figures/dimarco2015_fig3_sigmoid_startup.toml"


def plot(record: dict, arrays: dict):
    """The figure (not saved) from a stored result of :data:`CONFIG`."""
    d, s = record["details"]["startup"], record["scalars"]
    m, t = d["feed_mm_per_s"], arrays["startup.t"]
    fig, ax = figure(1, 3, figsize=(13, 3.8))
    ax[0].plot(t, m * t, "k--", label="nominal x = m t (eq 1)")
    for i, alpha in enumerate(d["alphas"], start=1):
        x, v, a = (arrays[f"startup.alpha{i}.{k}"] for k in ("x", "v", "a"))
        ax[0].plot(t, x, color=f"C{i - 1}", label=f"alpha = {alpha:g} 1/s^3")
        ax[1].plot(t, v, color=f"C{i - 1}", label=f"alpha = {alpha:g}")
        ax[1].plot(s[f"startup_peak_time.alpha{i}"], s[f"startup_peak_feed.alpha{i}"], "o", color=f"C{i - 1}", ms=4)
        ax[2].plot(t, a, color=f"C{i - 1}", label=f"alpha = {alpha:g}")
    ax[1].axhline(m, color="k", ls="--", lw=0.8, label="m")
    ax[1].axhline(m * (1 + 3 * np.exp(-4 / 3)), color="C3", ls=":", lw=0.8, label="m (1 + 3 e^-4/3)")
    ax[0].set(xlabel="time [s]", ylabel="position [mm]", title="position (eq 3): lag, then catch-up")
    ax[1].set(xlabel="time [s]", ylabel="velocity [mm/s]", title="velocity (eq 4): overshoot of the feed (peaks marked)")
    ax[2].set(xlabel="time [s]", ylabel="acceleration [mm/s^2]", title="acceleration (eq 5): a(0) = 0")
    for a in ax:
        a.legend(loc="best", fontsize=7)
    return fig
