"""Resonance calibration graph (issue 20): PSD per axis of a resonance test, the modes found, and the FIR
chain's |a'(j w)| of Sencer 2015 eq 9 with the delays eq 10 puts on them.

The log is synthetic and seeded (the config): the paper's beams, 11.4 Hz on X and 6.8 Hz on Y
(§4, damping 2 %: the paper gives none), excited by a 2-40 Hz sine sweep along the X-Y diagonal for
10 s at 3.2 kHz with 20 dB SNR. Each panel shows the PSD, the detection threshold, each mode's fit
(frequency +- standard error, damping), eq 9's magnitude for the tuned delays (right axis; zeros on
the modes) and the PSD times that magnitude squared: the spectrum the shaped motion leaves. Like the
graphs of Klipper's input-shaper calibration.

Made from the config :data:`CONFIG` through the results store; :func:`plot` only reads the stored result.
"""

from __future__ import annotations


import numpy as np

from research.figures._style import AXIS_COLOURS, figure
from research.interpolators import magnitude_response
from research.vibration import transmissibility_sq

NAME = "vibration_calibration"
REPRODUCES = ("issue 20: resonance-test PSD per axis with the modes found and the FIR |a'(j w)| (Sencer 2015 eq 9) "
              "of the eq 10 delays overlaid (synthetic log of the §4 beams, 11.4 Hz X / 6.8 Hz Y)")
CONFIG = "experiments/figures/vibration_calibration.toml"
F_MAX = 40.0  # Hz, plotted range


def plot(record: dict, arrays: dict):
    """The figure (not saved) from a stored result of :data:`CONFIG`."""
    d = record["details"]["vibration"]
    delays = np.asarray(d["tuned"]["delays_s"])
    axes_names = [k.split(".")[1] for k in arrays if k.startswith("vibration.") and k.endswith(".psd")]
    fig, axes = figure(1, len(axes_names), figsize=(4.2 * len(axes_names), 3.6), sharey=True)
    for a, ax_name in zip(np.atleast_1d(axes), axes_names):
        f_all = arrays[f"vibration.{ax_name}.f"]
        sel = f_all <= F_MAX
        f, psd, threshold = f_all[sel], arrays[f"vibration.{ax_name}.psd"][sel], arrays[f"vibration.{ax_name}.threshold"][sel]
        mag = np.asarray(magnitude_response(2 * np.pi * f, delays))
        colour = AXIS_COLOURS.get(ax_name, "k")
        a.semilogy(f, psd, color=colour, lw=1.0, label=f"PSD {ax_name}")
        a.semilogy(f, psd * mag**2, color=colour, lw=0.8, ls="--", alpha=0.8, label="PSD x |eq 9|^2 (shaped)")
        a.semilogy(f, threshold, color="0.5", lw=0.7, ls=":", label="detection threshold")
        for m in (m for m in d["modes"] if m["axis"] == ax_name):
            scale = m["peak_psd"] / transmissibility_sq(m["frequency_hz"], m["frequency_hz"], m["damping"])
            a.semilogy(f, scale * transmissibility_sq(f, m["frequency_hz"], m["damping"]), color="k", lw=0.6, alpha=0.6)
            a.plot(m["frequency_hz"], m["peak_psd"], "kv", ms=5)
            a.annotate(f"{m['frequency_hz']:.3f} +- {m['frequency_sd_hz']:.3f} Hz\nzeta {m['damping']:.4f}"
                       + (f"\n[{', '.join(m['flags'])}]" if m["flags"] else ""),
                       (m["frequency_hz"], m["peak_psd"]), textcoords="offset points", xytext=(6, -4), fontsize=7, va="top")
        a.set(xlabel="frequency [Hz]", title=f"axis {ax_name}", xlim=(0, F_MAX))
        b = a.twinx()
        b.semilogy(f, np.maximum(mag, 1e-6), color="C7", lw=0.9, label="|M(j w)| eq 9")
        b.set_ylim(1e-6, 2)
        if ax_name != axes_names[-1]:
            b.tick_params(labelright=False)
        if ax_name == axes_names[0]:
            a.set_ylabel("PSD [(mm/s^2)^2/Hz]")
            a.legend(loc="lower left", fontsize=6)
        if ax_name == axes_names[-1]:
            b.set_ylabel("|M(j w)| (eq 9)", color="C7")
            b.legend(loc="lower right", fontsize=6)
    top = max(float(np.max(arrays[f"vibration.{n}.psd"])) for n in axes_names)
    np.atleast_1d(axes)[0].set_ylim(top * 1e-9, top * 10)
    v = record["config"]["vibration"]
    text = ", ".join(f"T{i + 1} = {T * 1e3:.1f} ms ({ax} {fr:.3f} Hz)"
                     for i, (T, ax, fr) in enumerate(zip(delays, d["tuned"]["axes"], d["tuned"]["frequencies_hz"])))
    fig.suptitle(f"resonance test ({v['duration_s']:g} s sweep {v['f0_hz']:g}-{v['f1_hz']:g} Hz, {v['rate_hz']:g} Hz, "
                 f"SNR {v['snr_db']:g} dB); eq 10: {text}", fontsize=8)
    return fig
