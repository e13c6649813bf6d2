"""Sencer 2015 Fig 3: frequency response of the FIR filters (eq 8-10).

The magnitudes of the two filters of the paper's §4 experiment, T1 = 148 ms and T2 = 89 ms, and of
their chain, with the beam modes they were tuned to avoid (6.8 Hz in Y, 11.4 Hz in X). eq 10 puts a
zero on each mode; the paper's rounded delays leave a small residual, printed on the figure.

Made from the config :data:`CONFIG` through the results store; :func:`plot` only reads the stored result.
"""

from __future__ import annotations

import numpy as np

from research.figures._style import figure

NAME = "sencer2015_fig3_fir_spectrum"
REPRODUCES = "Sencer 2015 Fig 3 (FIR frequency response, eq 8-10)"
CONFIG = "experiments/figures/sencer2015_fig3_fir_spectrum.toml"
AXES_OF_MODES = ("Y", "X")  # §4: the 6.8 Hz beam on Y, the 11.4 Hz beam on X (the config's modes_hz order)


def plot(record: dict, arrays: dict):
    """The figure (not saved) from a stored result of :data:`CONFIG`."""
    d, s = record["details"]["spectrum"], record["scalars"]
    delays, modes, tuned = d["delays_s"], d["modes_hz"], d.get("tuned_delays_s", [])
    f = arrays["spectrum.f"]
    fig, ax = figure(1, 2, figsize=(10, 4.4))
    a = ax[0]
    for i, T in enumerate(delays):
        a.plot(f, 20 * np.log10(np.maximum(arrays[f"spectrum.T{i + 1}"], 1e-6)), f"C{i}", label=f"T = {T * 1e3:g} ms (zeros at k / T)")
    a.plot(f, 20 * np.log10(np.maximum(arrays["spectrum.given"], 1e-6)), "k", label="chain, eq 9")
    for m, axis in zip(modes, AXES_OF_MODES):
        a.axvline(m, color="C3", ls=":", lw=1)
        a.text(m + 0.3, -95, f"{axis} mode {m:g} Hz", rotation=90, va="bottom", ha="left", color="C3", fontsize=7)
    a.set(xlabel="frequency [Hz]", ylabel="|M(j w)| [dB]", ylim=(-100, 5), title="eq 8-9, paper delays")
    a.legend(loc="upper center", bbox_to_anchor=(0.5, -0.16), ncol=3, fontsize=7)
    a = ax[1]
    rows = []
    chains = [("given", "paper (" + ", ".join(f"{T * 1e3:g}" for T in delays) + " ms)")]
    if tuned:
        chains.append(("tuned", "eq 10 (" + ", ".join(f"{T * 1e3:.1f}" for T in tuned) + " ms)"))
    for key, label in chains:
        a.semilogy(f, np.maximum(arrays[f"spectrum.{key}"], 1e-12), label=label)
        rows.append(f"{label}: |M| at modes = " + ", ".join(f"{s[f'spectrum_gain.{key}.mode{j + 1}']:.1e}" for j in range(len(modes))))
    for m in modes:
        a.axvline(m, color="C3", ls=":", lw=1)
    a.set(xlabel="frequency [Hz]", ylabel="|M(j w)|", ylim=(1e-8, 2), xlim=(0, 20), title="tuning delays to the modes, eq 10")
    a.legend(loc="upper center", bbox_to_anchor=(0.5, -0.16), ncol=2, fontsize=7)
    a.text(0.98, 0.98, "\n".join(rows), transform=a.transAxes, ha="right", va="top", fontsize=6)
    return fig
