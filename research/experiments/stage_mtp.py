"""The ``[mtp]`` stage: a modulated tool path (DiMarco 2015 §1-2) by the sigmoid interpolator and two linear
interpolators, each reference run through the config's ``[drive]``.

The move ``m t + A sin(2 pi f t)`` along one axis (length L): the sigmoid interpolator blends the ramp and the
sinusoid in and out (eq 2-7, :func:`research.interpolators.mtp_motion`); the linear interpolators follow the
oscillation as ``moves_per_period`` G01 moves per period (the paper's "current practice"), either each an
exact-stop S-curve (:func:`research.interpolators.mtp_linear_baseline`) or blended with acc/dec after
interpolation (:func:`research.interpolators.mtp_blending_baseline`, beyond the paper).
"""

from __future__ import annotations

import numpy as np

#: the three references, in the order of the results (labels of the scalars and arrays)
MTP_REFERENCES = ("sigmoid", "exact_stop", "blending")


def mtp_comparison(length: float, feed: float, amplitude: float, frequency: float, acceleration: float, jerk: float,
                   drive, *, moves_per_period: int = 16, sample_period: float = 1e-4, settle: float = 0.2) -> dict:
    """The three interpolators on one MTP move, sampled on one grid, and through ``drive``.

    Args:
        length, feed, amplitude, frequency: the move: L [mm], m [mm/s], A [mm], f [Hz].
        acceleration, jerk: limits of every interpolator [mm/s^2], [mm/s^3].
        drive: a :class:`~research.drives.ClosedLoopModel` (one axis).
        moves_per_period: G01 moves per oscillation period of the linear interpolators.
        sample_period: grid step [s]; settle: rest simulated after the longest reference [s].

    Returns:
        ``{"t", "nominal", "references": {name: [q, v, a, j]}, "actual": {name: position}, "metrics": {name:
        {...}}, "alpha", "blending_delays"}`` (names of :data:`MTP_REFERENCES`). Metrics: ``cycle_time_s``; peak
        reference |a| ``peak_acceleration_mm_s2`` and |j| ``peak_jerk_mm_s3``; over the nominal move
        ``0 <= t <= L/m``: ``max_abs_reference_error_mm`` (max |reference - nominal|), ``max_abs_tracking_error_mm``
        and ``rms_tracking_error_mm`` (|actual - nominal|) [mm].
    """
    from research.drives import simulate
    from research.interpolators.sigmoid import mtp_blending_baseline, mtp_linear_baseline, mtp_motion
    from research.trajectory import Trajectory

    move = dict(length=length, feed=feed, amplitude=amplitude, frequency=frequency, acceleration=acceleration, jerk=jerk)
    motion = mtp_motion(**move)
    exact_stop, _ = mtp_linear_baseline(**move, moves_per_period=moves_per_period, sample_period=sample_period)
    blending, delays = mtp_blending_baseline(**move, moves_per_period=moves_per_period, sample_period=sample_period)
    end = max(motion.duration, float(exact_stop.duration), float(blending.duration)) + settle
    t = np.arange(0.0, end + sample_period / 2, sample_period)

    def on_grid(tr):
        tt = np.asarray(tr.t)
        return [np.interp(t, tt, np.asarray(x)[:, 0], right=(float(tr.q[-1, 0]) if k == 0 else 0.0))
                for k, x in enumerate((tr.q, tr.v, tr.a, tr.j))]

    refs = {"sigmoid": ([np.asarray(x) for x in motion.derivatives(t)], motion.duration),
            "exact_stop": (on_grid(exact_stop), float(exact_stop.duration)),
            "blending": (on_grid(blending), float(blending.duration))}
    arrival = length / feed
    nominal = np.where(t <= arrival, motion.nominal_position(t), length)
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
    return {"t": t, "nominal": nominal, "references": {k: v[0] for k, v in refs.items()}, "actual": actual,
            "metrics": rows, "alpha": float(motion.terms[0][1].alpha), "blending_delays": delays}


def mtp_stage(mc, drive) -> tuple[dict, dict, dict]:
    """``[mtp]`` through ``drive`` (from the config's ``[drive]`` table; one model, not per axis).

    Returns:
        ``(scalars, details, arrays)``: per reference ``<name>.mtp_cycle_time`` [s], ``<name>.mtp_rms_tracking_error``,
        ``<name>.mtp_max_tracking_error``, ``<name>.mtp_max_reference_error`` [mm], ``<name>.mtp_peak_acceleration``
        [mm/s^2], ``<name>.mtp_peak_jerk`` [mm/s^3]; details ``{"references", "alpha", "blending_delays_s"}``;
        arrays ``mtp.t``, ``mtp.nominal``, ``mtp.<name>.q / v / a / j / actual``.
    """
    from research.errors import ConfigError

    if drive is None or isinstance(drive, tuple):
        raise ConfigError("key 'drive.model': the [mtp] stage needs one drive model for its axis (not \"ideal\", not "
                          "a per-axis Table 6.3 drive)")
    c = mtp_comparison(mc.length_mm, mc.feed_mm_per_s, mc.amplitude_mm, mc.frequency_hz, mc.acceleration_mm_per_s2,
                       mc.jerk_mm_per_s3, drive, moves_per_period=mc.moves_per_period,
                       sample_period=mc.sample_period_ms * 1e-3, settle=mc.settle_time_s)
    keys = {"cycle_time_s": "mtp_cycle_time", "rms_tracking_error_mm": "mtp_rms_tracking_error",
            "max_abs_tracking_error_mm": "mtp_max_tracking_error", "max_abs_reference_error_mm": "mtp_max_reference_error",
            "peak_acceleration_mm_s2": "mtp_peak_acceleration", "peak_jerk_mm_s3": "mtp_peak_jerk"}
    scalars = {f"{name}.{keys[k]}": float(v) for name, row in c["metrics"].items() for k, v in row.items()}
    arrays = {"mtp.t": c["t"], "mtp.nominal": c["nominal"]}
    for name, d in c["references"].items():
        arrays |= {f"mtp.{name}.{k}": x for k, x in zip("qvaj", d)} | {f"mtp.{name}.actual": c["actual"][name]}
    details = {"references": list(MTP_REFERENCES), "alpha": c["alpha"],
               "blending_delays_s": [float(x) for x in np.atleast_1d(c["blending_delays"])]}
    return scalars, details, arrays
