"""Modulated tool path: sigmoid interpolator against the jerk-limited linear interpolator.

One 10 mm MTP move at m = 20 mm/s with a 0.2 mm, 20 Hz oscillation along the feed, both
interpolators under a_max = 5000 mm/s^2 and j_max = 2e6 mm/s^3. The linear interpolator follows
the oscillation as 16 short G01 moves per period, each an exact-stop S-curve (DiMarco 2015 §1,
current practice); the sigmoid interpolator blends the nominal ramp and sinusoid in and out
(eq 2-7, stop designed here).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from research.figures._style import figure, save
from research.interpolators.sigmoid import mtp_linear_baseline, mtp_motion

NAME = "dimarco2015_mtp_comparison"
REPRODUCES = "DiMarco 2015 §2 (MTP: sigmoid vs linear interpolator; lag, peak a/j, cycle time)"
MOVE = dict(length=10.0, feed=20.0, amplitude=0.2, frequency=20.0)
LIMITS = dict(acceleration=5000.0, jerk=2e6)


def compare(sample_period: float = 1e-4) -> dict:
    """Both interpolators on the figure's MTP move: sampled motions and their metrics."""
    motion = mtp_motion(**MOVE, **LIMITS)
    baseline, _ = mtp_linear_baseline(**MOVE, **LIMITS, sample_period=sample_period)
    end = max(motion.duration, float(baseline.duration))
    t = np.arange(0.0, end + sample_period, sample_period)
    sig = motion.derivatives(t)
    lin = [np.interp(t, baseline.t, np.asarray(x)[:, 0]) for x in (baseline.q, baseline.v, baseline.a, baseline.j)]
    arrival = MOVE["length"] / MOVE["feed"]
    nominal = np.where(t <= arrival, motion.nominal_position(t), MOVE["length"])
    rows = {}
    for name, d, cycle in (("sigmoid", sig, motion.duration), ("linear interpolator", lin, float(baseline.duration))):
        lag = d[0] - nominal
        rows[name] = {
            "cycle_time_s": cycle,
            "max_abs_tracking_error_mm": float(np.max(np.abs(lag[t <= arrival]))),
            "tracking_error_at_nominal_end_mm": float(np.interp(arrival, t, lag)),
            "peak_acceleration_mm_s2": float(np.max(np.abs(d[2]))),
            "peak_jerk_mm_s3": float(np.max(np.abs(d[3]))),
        }
    return {"t": t, "nominal": nominal, "sigmoid": sig, "linear": lin, "metrics": rows, "alpha": motion.terms[0][1].alpha}


def make_figure(out_dir: Path, fast: bool = False) -> list[Path]:
    """Write the figure to ``out_dir``; returns the files written."""
    c = compare(1e-4 if not fast else 5e-4)
    t = c["t"]
    fig, ax = figure(2, 2, figsize=(12, 7))
    ax[0, 0].plot(t, c["nominal"], "k--", lw=0.8, label="nominal (part program)")
    ax[0, 0].plot(t, c["sigmoid"][0], label="sigmoid")
    ax[0, 0].plot(t, c["linear"][0], label="linear interpolator (16 G01 / period)")
    ax[0, 0].set(xlabel="time [s]", ylabel="position along feed [mm]", title="MTP move: 10 mm at 20 mm/s + 0.2 mm x 20 Hz")
    ax[0, 1].plot(t, c["sigmoid"][0] - c["nominal"], label="sigmoid")
    ax[0, 1].plot(t, c["linear"][0] - c["nominal"], label="linear interpolator")
    ax[0, 1].set(xlabel="time [s]", ylabel="tracking error [mm]", title="error against the nominal motion")
    for k, (label, unit) in enumerate((("acceleration", "mm/s^2"), ("jerk", "mm/s^3"))):
        a = ax[1, k]
        a.plot(t, c["sigmoid"][2 + k], lw=0.8, label="sigmoid")
        a.plot(t, c["linear"][2 + k], lw=0.8, label="linear interpolator")
        a.set(xlabel="time [s]", ylabel=f"{label} [{unit}]", title=label)
    for a in ax.ravel():
        a.legend(loc="best")
    m = c["metrics"]
    text = "\n".join(
        f"{name}: cycle {r['cycle_time_s']:.3f} s, max |error| {r['max_abs_tracking_error_mm']:.3f} mm, "
        f"peak a {r['peak_acceleration_mm_s2']:.0f}, peak j {r['peak_jerk_mm_s3']:.3g}"
        for name, r in m.items()
    )
    fig.suptitle(text, fontsize=8)
    out = Path(out_dir) / f"{NAME}.png"
    save(fig, out)
    return [out]
