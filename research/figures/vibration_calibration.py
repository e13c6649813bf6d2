"""Resonance calibration graph (issue 20): PSD per axis of a resonance test, the modes found, and the FIR
chain's |a'(j w)| of Sencer 2015 eq 9 with the delays eq 10 puts on them.

The log is synthetic and seeded (module constants): the paper's beams, 11.4 Hz on X and 6.8 Hz on Y
(§4, damping 2 %: the paper gives none), excited by a 2-40 Hz sine sweep along the X-Y diagonal for
10 s at 3.2 kHz with 20 dB SNR. Each panel shows the PSD, the detection threshold, each mode's fit
(frequency +- standard error, damping), eq 9's magnitude for the tuned delays (right axis; zeros on
the modes) and the PSD times that magnitude squared: the spectrum the shaped motion leaves. Like the
graphs of Klipper's input-shaper calibration.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from research.figures._style import AXIS_COLOURS, figure, save
from research.interpolators import magnitude_response
from research.vibration import TrueMode, estimate_modes, synthetic_accel_log, transmissibility_sq, tune_delays

NAME = "vibration_calibration"
REPRODUCES = ("issue 20: resonance-test PSD per axis with the modes found and the FIR |a'(j w)| (Sencer 2015 eq 9) "
              "of the eq 10 delays overlaid (synthetic log of the §4 beams, 11.4 Hz X / 6.8 Hz Y)")
TRUTH = (TrueMode("x", 11.4, 0.02), TrueMode("y", 6.8, 0.02))
SWEEP = dict(excitation="sweep", f0=2.0, f1=40.0, duration=10.0, rate=3200.0, snr_db=20.0, seed=0)
F_MAX = 40.0  # Hz, plotted range


def make_figure(out_dir: Path, fast: bool = False) -> list[Path]:
    """Write the figure to ``out_dir``; returns the files written (``fast``: an 800 Hz log)."""
    kw = SWEEP | ({"rate": 800.0} if fast else {})
    log = synthetic_accel_log(list(TRUTH), **kw)
    survey = estimate_modes(log)
    dominant = survey.dominant()
    tuned = tune_delays(list(dominant.values()))
    fig, axes = figure(1, len(survey.spectra), figsize=(4.2 * len(survey.spectra), 3.6), sharey=True)
    for a, (ax_name, spec) in zip(np.atleast_1d(axes), survey.spectra.items()):
        sel = spec.frequency_hz <= F_MAX
        f = spec.frequency_hz[sel]
        mag = np.asarray(magnitude_response(2 * np.pi * f, np.asarray(tuned.delays_s)))
        colour = AXIS_COLOURS.get(ax_name, "k")
        a.semilogy(f, spec.psd[sel], color=colour, lw=1.0, label=f"PSD {ax_name}")
        a.semilogy(f, spec.psd[sel] * mag**2, color=colour, lw=0.8, ls="--", alpha=0.8, label="PSD x |eq 9|^2 (shaped)")
        a.semilogy(f, spec.threshold[sel], color="0.5", lw=0.7, ls=":", label="detection threshold")
        for m in spec.modes:
            scale = m.peak_psd / transmissibility_sq(m.frequency_hz, m.frequency_hz, m.damping)
            a.semilogy(f, scale * transmissibility_sq(f, m.frequency_hz, m.damping), color="k", lw=0.6, alpha=0.6)
            a.plot(m.frequency_hz, m.peak_psd, "kv", ms=5)
            a.annotate(f"{m.frequency_hz:.3f} +- {m.frequency_sd_hz:.3f} Hz\nzeta {m.damping:.4f}"
                       + (f"\n[{', '.join(m.flags)}]" if m.flags else ""),
                       (m.frequency_hz, m.peak_psd), textcoords="offset points", xytext=(6, -4), fontsize=7, va="top")
        a.set(xlabel="frequency [Hz]", title=f"axis {ax_name}", xlim=(0, F_MAX))
        b = a.twinx()
        b.semilogy(f, np.maximum(mag, 1e-6), color="C7", lw=0.9, label="|M(j w)| eq 9")
        b.set_ylim(1e-6, 2)
        if ax_name != list(survey.spectra)[-1]:
            b.tick_params(labelright=False)
        if ax_name == next(iter(survey.spectra)):
            a.set_ylabel("PSD [(mm/s^2)^2/Hz]")
            a.legend(loc="lower left", fontsize=6)
        if ax_name == list(survey.spectra)[-1]:
            b.set_ylabel("|M(j w)| (eq 9)", color="C7")
            b.legend(loc="lower right", fontsize=6)
    top = max(float(np.max(s.psd)) for s in survey.spectra.values())
    np.atleast_1d(axes)[0].set_ylim(top * 1e-9, top * 10)
    delays = ", ".join(f"T{i + 1} = {T * 1e3:.1f} ms ({ax} {fr:.3f} Hz)"
                       for i, (T, ax, fr) in enumerate(zip(tuned.delays_s, tuned.axes, tuned.frequencies_hz)))
    fig.suptitle(f"resonance test ({log.duration:.0f} s sweep {kw['f0']:g}-{kw['f1']:g} Hz, {log.sample_rate:g} Hz, "
                 f"SNR {kw['snr_db']:g} dB); eq 10: {delays}", fontsize=8)
    out = Path(out_dir) / f"{NAME}.png"
    save(fig, out)
    return [out]
