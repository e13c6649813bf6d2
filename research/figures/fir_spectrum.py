"""Sencer 2015 Fig 3: frequency response of the FIR filters (eq 8-10).

The magnitudes of the two filters of the paper's §4 experiment, T1 = 148 ms and T2 = 89 ms, and of
their chain, with the beam modes they were tuned to avoid (6.8 Hz in Y, 11.4 Hz in X). eq 10 puts a
zero on each mode; the paper's rounded delays leave a small residual, printed on the figure.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from research.figures._style import figure, save
from research.interpolators import delays_for_modes, magnitude_response

NAME = "sencer2015_fig3_fir_spectrum"
REPRODUCES = "Sencer 2015 Fig 3 (FIR frequency response, eq 8-10)"
PAPER_DELAYS = (0.148, 0.089)  # s, §4
MODES_HZ = (6.8, 11.4)  # Y and X beam modes, §4


def make_figure(out_dir: Path, fast: bool = False) -> list[Path]:
    """Write the figure to ``out_dir``; returns the files written."""
    f = np.linspace(0.01, 40.0, 800 if fast else 4000)
    w = 2 * np.pi * f
    fig, ax = figure(1, 2, figsize=(10, 3.8))
    a = ax[0]
    for T, style in zip(PAPER_DELAYS, ("C0", "C1")):
        a.plot(f, 20 * np.log10(np.maximum(np.asarray(magnitude_response(w, [T])), 1e-6)), style, label=f"T = {T * 1e3:g} ms (zeros at k / T)")
    a.plot(f, 20 * np.log10(np.maximum(np.asarray(magnitude_response(w, PAPER_DELAYS)), 1e-6)), "k", label="chain, eq 9")
    for m, axis in zip(MODES_HZ, ("Y", "X")):
        a.axvline(m, color="C3", ls=":", lw=1)
        a.text(m + 0.3, -95, f"{axis} mode {m} Hz", rotation=90, va="bottom", ha="left", color="C3", fontsize=7)
    a.set(xlabel="frequency [Hz]", ylabel="|M(j w)| [dB]", ylim=(-100, 5), title="eq 8-9, paper delays")
    a.legend(loc="lower left")
    a = ax[1]
    tuned = delays_for_modes(MODES_HZ)
    rows = []
    for label, delays in (("paper (148, 89 ms)", PAPER_DELAYS), (f"eq 10 ({tuned[0] * 1e3:.1f}, {tuned[1] * 1e3:.1f} ms)", tuned)):
        mag = np.asarray(magnitude_response(w, delays))
        a.semilogy(f, np.maximum(mag, 1e-12), label=label)
        rows.append(f"{label}: |M| at modes = " + ", ".join(f"{float(magnitude_response(2 * np.pi * m, delays)):.1e}" for m in MODES_HZ))
    for m in MODES_HZ:
        a.axvline(m, color="C3", ls=":", lw=1)
    a.set(xlabel="frequency [Hz]", ylabel="|M(j w)|", ylim=(1e-8, 2), xlim=(0, 20), title="tuning delays to the modes, eq 10")
    a.legend(loc="lower left")
    a.text(0.98, 0.98, "\n".join(rows), transform=a.transAxes, ha="right", va="top", fontsize=6)
    out = Path(out_dir) / f"{NAME}.png"
    save(fig, out)
    return [out]
