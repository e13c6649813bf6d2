"""Thesis Fig 6.7-style Bode plots of the Table 6.1 P-PI virtual drive: tracking and disturbance
transfer functions of eq 6.1 (``G_track = x/x_r`` and ``G_dist = x/w`` per unit friction input of eq 6.3).

Made from the config :data:`CONFIG` through the results store; :func:`plot` only reads the stored result.
"""

from __future__ import annotations

import numpy as np

from research.figures._style import figure

NAME = "sencer2009_fig6_7_drive_bode"
REPRODUCES = "Sencer 2009 thesis Fig 6.7 style: Bode plots of the Table 6.1 P-PI drive (eq 6.1/6.3)"
CONFIG = "experiments/figures/sencer2009_fig6_7_drive_bode.toml"


def plot(record: dict, arrays: dict):
    """The figure (not saved) from a stored result of :data:`CONFIG`."""
    f, track, dist = arrays["bode.f"], arrays["bode.tracking"], arrays["bode.disturbance"]
    s = record["scalars"]
    fig, ax = figure(2, 2, figsize=(10, 6), sharex=True)
    for col, (g, title, unit) in enumerate(((track, "a) tracking $G_{track} = x/x_r$", "[mm/mm]"),
                                            (dist, "b) disturbance $G_{dist} = x/w$", "[mm/(mm/s$^2$)]"))):
        ax[0, col].loglog(f, np.abs(g), color="C0")
        ax[0, col].set_ylabel(f"Magnitude {unit}")
        ax[0, col].set_title(title)
        ax[1, col].semilogx(f, np.degrees(np.unwrap(np.angle(g))), color="C0")
        ax[1, col].set_ylabel("Phase [deg]")
        ax[1, col].set_xlabel("Frequency [Hz]")
        for a in ax[:, col]:
            a.grid(True, which="both", alpha=0.3)
    if "drive_bandwidth_hz" in s:
        ax[0, 0].axhline(1 / np.sqrt(2), color="k", ls=":", lw=0.8)
        ax[0, 0].axvline(s["drive_bandwidth_hz"], color="C3", ls="--", lw=0.8,
                         label=f"-3 dB: {s['drive_bandwidth_hz']:.1f} Hz")
        ax[0, 0].legend(loc="lower left")
    fig.suptitle(f"Sencer 2009 Table 6.1 P-PI virtual drive (eq 6.1/6.3): wn {s['drive_wn_hz']:.2f} Hz, zeta "
                 f"{s['drive_zeta']:.3f}, p {s['drive_p_hz']:.2f} Hz from the printed coefficients "
                 "(table: 30.6 Hz, 0.45, 10.8 Hz)")
    return fig
