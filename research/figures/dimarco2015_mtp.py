"""Modulated tool path: sigmoid interpolator against two linear interpolators, through a drive (DiMarco 2015).

One 10 mm MTP move at m = 20 mm/s with a 0.2 mm, 20 Hz oscillation along the feed, every interpolator under
a_max = 5000 mm/s^2 and j_max = 2e6 mm/s^3 (assumed: the paper prints no limits or move). The linear
interpolators follow the oscillation as 16 short G01 moves per period (DiMarco 2015 §1, current practice):
(1) each move an exact-stop S-curve; (2) the moves blended, no stop, with acceleration/deceleration after
interpolation (beyond the paper). The sigmoid interpolator blends the nominal ramp and sinusoid in and out
(eq 2-7). Each reference runs through the thesis Table 6.1 P-PI drive (dc = 0; an assumption) to test the
abstract's "better tracking performance and lower accelerations than the linear interpolator".

Made from the config :data:`CONFIG` through the results store (the ``[mtp]`` stage,
:mod:`research.experiments.stage_mtp`); :func:`plot` only reads the stored result.
"""

from __future__ import annotations

import numpy as np

from research.figures._style import figure

NAME = "dimarco2015_mtp_comparison"
REPRODUCES = "DiMarco 2015 §2 (MTP: sigmoid vs linear interpolator; lag, peak a/j, cycle time)"
CONFIG = "experiments/figures/dimarco2015_mtp_comparison.toml"
#: the config's move and limits (for the interpolator tests and benchmarks/bench_sigmoid.py)
MOVE = dict(length=10.0, feed=20.0, amplitude=0.2, frequency=20.0)
LIMITS = dict(acceleration=5000.0, jerk=2e6)
LABELS = {"sigmoid": "sigmoid", "exact_stop": "linear interpolator (exact stop)",
          "blending": "linear interpolator (blending)"}


def compare(sample_period: float = 1e-4) -> dict:
    """The config's comparison computed directly (no store), for the interpolator tests:
    :func:`research.experiments.stage_mtp.mtp_comparison` on :data:`MOVE`, :data:`LIMITS` and the Table 6.1
    drive with dc = 0, ``metrics`` keyed by the figure's labels (:data:`LABELS`)."""
    import equinox as eqx

    from research.drives import table_6_1_closed_loop
    from research.experiments.stage_mtp import mtp_comparison

    drive = eqx.tree_at(lambda m: m.dc, table_6_1_closed_loop(), 0.0)
    c = mtp_comparison(**MOVE, **LIMITS, drive=drive, sample_period=sample_period)
    return c | {"metrics": {LABELS[k]: v for k, v in c["metrics"].items()}}


def plot(record: dict, arrays: dict):
    """The figure (not saved) from a stored result of :data:`CONFIG`."""
    s, names = record["scalars"], record["details"]["mtp"]["references"]
    mc = record["config"]["mtp"]
    t, nominal = arrays["mtp.t"], arrays["mtp.nominal"]
    fig, ax = figure(2, 2, figsize=(12, 7))
    ax[0, 0].plot(t, nominal, "k--", lw=0.8, label="nominal (part program)")
    for name in names:
        ax[0, 0].plot(t, arrays[f"mtp.{name}.q"], lw=0.8, label=LABELS[name])
        ax[0, 1].plot(t, arrays[f"mtp.{name}.actual"] - nominal, lw=0.8, label=f"{LABELS[name]}, through the drive")
    ax[0, 0].set(xlabel="time [s]", ylabel="position along feed [mm]",
                 title=f"MTP move: {mc['length_mm']:g} mm at {mc['feed_mm_per_s']:g} mm/s + {mc['amplitude_mm']:g} mm x "
                       f"{mc['frequency_hz']:g} Hz")
    ax[0, 1].set(xlabel="time [s]", ylabel="tracking error [mm]",
                 title="actual (Table 6.1 drive, dc = 0) - nominal motion", xlim=(0.0, 0.6))
    for k, (key, label, unit) in enumerate((("a", "acceleration", "mm/s^2"), ("j", "jerk", "mm/s^3"))):
        # magnitudes on a log axis: the linear interpolators' per-move spikes (16 moves per period) would
        # otherwise fill the panel as solid blocks over the sigmoid's smooth profile (drawn last, on top)
        a = ax[1, k]
        for i, name in reversed(list(enumerate(names))):
            mag = np.abs(arrays[f"mtp.{name}.{key}"])
            a.semilogy(t, np.where(mag > 0, mag, np.nan), lw=1.4 if i == 0 else 0.6, color=f"C{i}", zorder=3 - i,
                       label=f"{LABELS[name]}: peak {mag.max():.3g}")
        top = max(np.abs(arrays[f"mtp.{name}.{key}"]).max() for name in names)
        a.set(xlabel="time [s]", ylabel=f"|{label}| [{unit}] (log scale)", title=f"reference |{label}| (three decades "
              "below the largest peak)", xlim=(0.0, 0.6), ylim=(top * 1e-3, top * 3))
    for a in ax.ravel():
        a.legend(loc="lower right" if a in ax[1] else "best", fontsize=6)
    fig.suptitle("\n".join(
        f"{LABELS[n]}: cycle {s[f'{n}.mtp_cycle_time']:.3f} s, max |actual - nominal| {s[f'{n}.mtp_max_tracking_error']:.3f} mm "
        f"(RMS {s[f'{n}.mtp_rms_tracking_error']:.3f}), peak a {s[f'{n}.mtp_peak_acceleration']:.0f}, "
        f"peak j {s[f'{n}.mtp_peak_jerk']:.3g}" for n in names), fontsize=8)
    return fig
