"""Sencer (2009) thesis Fig 4.6: true tool-tip contour error on the eq 4.36 5-axis path against the
basic (eq 4.20), shifted (eq 4.22) and compensated (eq 4.27) Frenet-frame estimates; (b) their
discrepancies; (c) the delay time of eq 4.21. Simulated with the Table 6.3 closed-loop axis models
(the thesis used measured data from its SMC-controlled machine).

Made from the config :data:`CONFIG` through the results store; :func:`plot` only reads the stored result.
"""

from __future__ import annotations

import numpy as np

from research.figures._style import mosaic

NAME = "sencer2009_fig4_6_contour_estimates"
REPRODUCES = "Sencer 2009 thesis Fig 4.6 (true vs basic/shifted/compensated Frenet contour error estimates)"
CONFIG = "experiments/figures/sencer2009_fig4_6_contour_estimates.toml"


def plot(record: dict, arrays: dict):
    """The figure (not saved) from a stored result of :data:`CONFIG`."""
    s = record["scalars"]
    t, exact = arrays["five_axis.t"], arrays["five_axis.exact"]
    fig, ax = mosaic([["a"], ["b"], ["c"]], figsize=(10, 9), sharex=True)
    ax["a"].plot(t, exact * 1e3, "k", lw=2, label="true")
    for name, style in (("basic", "C0--"), ("shifted", "C1-."), ("compensated", "C2:")):
        est = arrays[f"five_axis.{name}"]
        ax["a"].plot(t, est * 1e3, style, label=name)
        mean = s[f"five_axis.mean_estimator_error.{name}"]
        ax["b"].semilogy(t, np.maximum(np.abs(est - exact) * 1e3, 1e-9), style, label=f"{name}: mean {mean * 1e3:.2g} um while moving")
    ax["a"].set(ylabel="contour error [um]", title="(a) true tool-tip contour error and Frenet estimates (eq 4.20, 4.22, 4.27)")
    ax["a"].legend(loc="upper right", fontsize=7)
    ax["b"].set(ylabel="|estimate - true| [um]", title="(b) discrepancy (includes start/end at rest)")
    ax["b"].legend(loc="center", fontsize=7)  # between the Frenet curves (1e-2 um) and the compensated one (1e-7 um)
    ax["c"].plot(t, arrays["five_axis.delay"] * 1e3, "k")
    ax["c"].set(xlabel="time [s]", ylabel="t_d [ms]", title="(c) delay time, eq 4.21")
    return fig
