"""Modulated tool path: sigmoid interpolator against two linear interpolators, through a drive.

One 10 mm MTP move at m = 20 mm/s with a 0.2 mm, 20 Hz oscillation along the feed, every
interpolator under a_max = 5000 mm/s^2 and j_max = 2e6 mm/s^3 (assumed: the paper prints no
limits or move). The linear interpolators follow the oscillation as 16 short G01 moves per period
(DiMarco 2015 §1, current practice): (1) each move an exact-stop S-curve; (2) the moves blended,
no stop, with acceleration/deceleration after interpolation (beyond the paper:
:func:`research.interpolators.mtp_blending_baseline`). The sigmoid interpolator blends the nominal
ramp and sinusoid in and out (eq 2-7, stop designed here). Each reference runs through the thesis
Table 6.1 P-PI drive (friction compensated, dc = 0; an assumption) to test the abstract's "better
tracking performance and lower accelerations than the linear interpolator".
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

import equinox as eqx

from research.drives import simulate, table_6_1_closed_loop
from research.figures._style import figure, save
from research.interpolators.sigmoid import mtp_blending_baseline, mtp_linear_baseline, mtp_motion
from research.trajectory import Trajectory

NAME = "dimarco2015_mtp_comparison"
REPRODUCES = "DiMarco 2015 §2 (MTP: sigmoid vs linear interpolator; lag, peak a/j, cycle time)"
MOVE = dict(length=10.0, feed=20.0, amplitude=0.2, frequency=20.0)
LIMITS = dict(acceleration=5000.0, jerk=2e6)


def compare(sample_period: float = 1e-4) -> dict:
    """The three interpolators on the figure's MTP move, sampled on one grid, and through the drive.

    Returns:
        ``{"t", "nominal", "sigmoid", "linear", "blending" (each ``[q, v, a, j]`` on ``t``),
        "actual": {name: drive position on t}, "metrics": {name: {...}}, "alpha", "blending_delays"}``.
        Metrics: cycle time [s]; peak reference |a| [mm/s^2] and |j| [mm/s^3]; max |reference -
        nominal| and max / RMS |actual - nominal| over the nominal move ``0 <= t <= L/m`` [mm].
    """
    motion = mtp_motion(**MOVE, **LIMITS)
    exact_stop, _ = mtp_linear_baseline(**MOVE, **LIMITS, sample_period=sample_period)
    blending, delays = mtp_blending_baseline(**MOVE, **LIMITS, sample_period=sample_period)
    end = max(motion.duration, float(exact_stop.duration), float(blending.duration)) + 0.2  # settle
    t = np.arange(0.0, end + sample_period / 2, sample_period)
    sig = motion.derivatives(t)

    def on_grid(tr):
        tt = np.asarray(tr.t)
        return [np.interp(t, tt, np.asarray(x)[:, 0], right=(float(tr.q[-1, 0]) if k == 0 else 0.0))
                for k, x in enumerate((tr.q, tr.v, tr.a, tr.j))]

    refs = {"sigmoid": (sig, motion.duration), "linear interpolator (exact stop)": (on_grid(exact_stop), float(exact_stop.duration)),
            "linear interpolator (blending)": (on_grid(blending), float(blending.duration))}
    arrival = MOVE["length"] / MOVE["feed"]
    nominal = np.where(t <= arrival, motion.nominal_position(t), MOVE["length"])
    drive = eqx.tree_at(lambda m: m.dc, table_6_1_closed_loop(), 0.0)
    during = t <= arrival
    rows, actual = {}, {}
    for name, (d, cycle) in refs.items():
        ref = Trajectory(t, d[0][:, None], d[1][:, None], d[2][:, None], d[3][:, None], np.float64(t[-1]), None, ("s",),
                         sample_period)
        actual[name] = np.asarray(simulate(drive, ref).position)[:, 0]
        err = actual[name] - nominal
        rows[name] = {
            "cycle_time_s": cycle,
            "max_abs_reference_error_mm": float(np.max(np.abs(d[0] - nominal)[during])),
            "max_abs_tracking_error_mm": float(np.max(np.abs(err[during]))),
            "rms_tracking_error_mm": float(np.sqrt(np.mean(err[during] ** 2))),
            "peak_acceleration_mm_s2": float(np.max(np.abs(d[2]))),
            "peak_jerk_mm_s3": float(np.max(np.abs(d[3]))),
        }
    return {"t": t, "nominal": nominal, "sigmoid": sig, "linear": refs["linear interpolator (exact stop)"][0],
            "blending": refs["linear interpolator (blending)"][0], "actual": actual, "metrics": rows,
            "alpha": motion.terms[0][1].alpha, "blending_delays": delays}


def make_figure(out_dir: Path, fast: bool = False) -> list[Path]:
    """Write the figure to ``out_dir``; returns the files written."""
    c = compare(1e-4 if not fast else 5e-4)
    t = c["t"]
    fig, ax = figure(2, 2, figsize=(12, 7))
    ax[0, 0].plot(t, c["nominal"], "k--", lw=0.8, label="nominal (part program)")
    styles = (("sigmoid", c["sigmoid"]), ("linear interpolator (exact stop)", c["linear"]),
              ("linear interpolator (blending)", c["blending"]))
    for name, d in styles:
        ax[0, 0].plot(t, d[0], lw=0.8, label=name)
        ax[0, 1].plot(t, c["actual"][name] - c["nominal"], lw=0.8, label=f"{name}, through the drive")
    ax[0, 0].set(xlabel="time [s]", ylabel="position along feed [mm]", title="MTP move: 10 mm at 20 mm/s + 0.2 mm x 20 Hz")
    ax[0, 1].set(xlabel="time [s]", ylabel="tracking error [mm]",
                 title="actual (Table 6.1 drive) - nominal motion", xlim=(0.0, 0.6))
    for k, (label, unit) in enumerate((("acceleration", "mm/s^2"), ("jerk", "mm/s^3"))):
        # magnitudes on a log axis: the linear interpolators' per-move spikes (16 moves per period) would
        # otherwise fill the panel as solid blocks over the sigmoid's smooth profile (drawn last, on top)
        a = ax[1, k]
        for i, (name, d) in reversed(list(enumerate(styles))):
            mag = np.abs(d[2 + k])
            a.semilogy(t, np.where(mag > 0, mag, np.nan), lw=1.4 if i == 0 else 0.6, color=f"C{i}", zorder=3 - i,
                       label=f"{name}: peak {mag.max():.3g}")
        top = max(np.abs(d[2 + k]).max() for _, d in styles)
        a.set(xlabel="time [s]", ylabel=f"|{label}| [{unit}] (log scale)", title=f"reference |{label}| (three decades "
              "below the largest peak)", xlim=(0.0, 0.6), ylim=(top * 1e-3, top * 3))
    for a in ax.ravel():
        a.legend(loc="lower right" if a in ax[1] else "best", fontsize=6)
    m = c["metrics"]
    text = "\n".join(
        f"{name}: cycle {r['cycle_time_s']:.3f} s, max |actual - nominal| {r['max_abs_tracking_error_mm']:.3f} mm "
        f"(RMS {r['rms_tracking_error_mm']:.3f}), "
        f"peak a {r['peak_acceleration_mm_s2']:.0f}, peak j {r['peak_jerk_mm_s3']:.3g}"
        for name, r in m.items()
    )
    fig.suptitle(text, fontsize=8)
    out = Path(out_dir) / f"{NAME}.png"
    save(fig, out)
    return [out]
