"""Thesis Fig 6.7-style Bode plots of the Table 6.1 P-PI virtual drive: tracking and disturbance
transfer functions of eq 6.1 (``G_track = x/x_r`` and ``G_dist = x/w`` per unit friction input of eq 6.3)."""

from __future__ import annotations

import pathlib

import numpy as np

from research.drives import frequency_response, table_6_1_closed_loop
from research.figures._style import figure, save

NAME = "sencer2009_fig6_7_drive_bode"
REPRODUCES = "Sencer 2009 thesis Fig 6.7 style: Bode plots of the Table 6.1 P-PI drive (eq 6.1/6.3)"


def make_figure(out_dir: pathlib.Path, fast: bool = False) -> list[pathlib.Path]:
    """Write ``sencer2009_fig6_7_drive_bode.png`` into ``out_dir``.

    Args:
        out_dir: destination folder (created if missing).
        fast: fewer frequency points and lower resolution (for tests).
    Returns:
        the list with the written PNG path.
    """
    out_dir = pathlib.Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    f = np.logspace(0, 2, 80 if fast else 400)  # 1-100 Hz, as thesis Fig 6.7
    fr = frequency_response(table_6_1_closed_loop(), f)
    track, dist = np.asarray(fr.tracking), np.asarray(fr.disturbance)
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
    fig.suptitle("Sencer 2009 Table 6.1 P-PI virtual drive (eq 6.1/6.3): wn 30.6 Hz, zeta 0.45, p 10.8 Hz")
    path = out_dir / f"{NAME}.png"
    save(fig, path)
    return [path]
