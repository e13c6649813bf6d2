"""Sencer (2009) thesis Fig 4.6: true tool-tip contour error on the eq 4.36 5-axis path against the
basic (eq 4.20), shifted (eq 4.22) and compensated (eq 4.27) Frenet-frame estimates; (b) their
discrepancies; (c) the delay time of eq 4.21. Simulated with the Table 6.3 closed-loop axis models
(the thesis used measured data from its SMC-controlled machine)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from research.contour import five_axis_contour_study
from research.figures._style import mosaic, save

NAME = "sencer2009_fig4_6_contour_estimates"
REPRODUCES = "Sencer 2009 thesis Fig 4.6 (true vs basic/shifted/compensated Frenet contour error estimates)"


def make_figure(out_dir: Path, fast: bool = False) -> list[Path]:
    """Write the figure to ``out_dir``; returns the files written."""
    st = five_axis_contour_study()
    t = st.t
    fig, ax = mosaic([["a"], ["b"], ["c"]], figsize=(10, 9), sharex=True)
    ax["a"].plot(t, st.exact * 1e3, "k", lw=2, label="true")
    for name, style in (("basic", "C0--"), ("shifted", "C1-."), ("compensated", "C2:")):
        ax["a"].plot(t, getattr(st.estimates, name) * 1e3, style, label=name)
        d = st.discrepancy(name)
        ax["b"].semilogy(t, np.maximum(d * 1e3, 1e-9), style, label=f"{name}: mean {d.mean() * 1e3:.2g} um")
    ax["a"].set(ylabel="contour error [um]", title="(a) true tool-tip contour error and Frenet estimates (eq 4.20, 4.22, 4.27)")
    ax["a"].legend()
    ax["b"].set(ylabel="|estimate - true| [um]", title="(b) discrepancy (includes start/end at rest)")
    ax["b"].legend()
    ax["c"].plot(t, st.estimates.delay * 1e3, "k")
    ax["c"].set(xlabel="time [s]", ylabel="t_d [ms]", title="(c) delay time, eq 4.21")
    out = Path(out_dir) / f"{NAME}.png"
    save(fig, out)
    return [out]
