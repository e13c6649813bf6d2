"""The ``[feedrate]`` stage: thesis ch 3 along a 5-axis ``[path]`` from a
:class:`~research.experiments.config_feedrate.FeedrateConfig`.

The optimized B-spline feed (:func:`research.optimal.optimize_feedrate`) and each constant feed
(:func:`research.optimal.constant_feed`) under thesis Table 3.1 (:func:`research.optimal.table31_limits`), the axis
limits reflected on the feed (Fig 3.10, :func:`research.optimal.axis_feed_limits`), and with ``[feedrate.drive]``
every schedule through the SISO SMC drives with the Table 3.1 amplifier limit (Fig 3.13,
:func:`research.control.feed_tracking`).
"""

from __future__ import annotations

import numpy as np

from research.experiments.config_feedrate import FeedrateConfig, FeedrateDriveConfig, constant_label

AXES = ("x", "y", "z", "a", "c")
KINDS = ("velocity", "acceleration", "jerk")


def _schedule_scalars(label: str, result, tolerance: float) -> dict[str, float]:
    ratios = np.stack([np.asarray(getattr(result.check, f"{k}_ratio"), dtype=np.float64) for k in KINDS])
    worst = float(ratios.max())
    return {f"{label}.feedrate_cycle_time": float(result.cycle_time), f"{label}.feedrate_limit_ratio": worst,
            f"{label}.feedrate_limits_violated": float(worst > 1.0 + tolerance)}


def _schedule_details(result) -> dict:
    return {"method": result.method, "status": result.status, "iterations": int(result.iterations),
            "cycle_time_s": float(result.cycle_time),
            "limit_ratio": {k: np.asarray(getattr(result.check, f"{k}_ratio")).tolist() for k in KINDS},
            "feed_ratio": None if np.isnan(result.check.feed_ratio) else float(result.check.feed_ratio),  # no cap: None
            "binding": [{"axis": b.axis, "kind": b.kind, "s_start_mm": float(b.s_start), "s_end_mm": float(b.s_end),
                         "peak": float(b.peak)} for b in result.binding]}


def coulomb_friction(dc: FeedrateDriveConfig, plant, T: float) -> np.ndarray:
    """Coulomb friction [V] per axis as ``dc`` asks (given, identified from Fig 5.7, or the isolated-reversal estimate)."""
    from research.control import FIG5_7_AXIS_PEAKS, identify_coulomb, step_disturbance_peak, table_5_2

    if dc.coulomb_V is not None:
        return np.asarray(dc.coulomb_V, dtype=np.float64)
    if dc.friction == "identified":
        return identify_coulomb(plant, T=T)
    g = table_5_2()
    return np.asarray(FIG5_7_AXIS_PEAKS) / (2.0 * np.array(
        [step_disturbance_peak(float(plant.m[i]), float(plant.c[i]), g, i, T) for i in range(5)]))


def feedrate_stage(fc: FeedrateConfig, path) -> tuple[dict[str, float], dict, dict[str, np.ndarray]]:
    """Run ``fc`` along ``path`` (a :class:`~research.paths.pose_spline.PoseSpline`).

    Returns:
        ``(scalars, details, arrays)``. Scalars (names of :data:`FEEDRATE_METRIC_UNITS`): ``feedrate_path_length``;
        per schedule label (``optimized``, ``constant_<F>``) ``<label>.feedrate_cycle_time`` [s],
        ``.feedrate_limit_ratio`` (largest axis |v|, |a|, |j| over its limit), ``.feedrate_limits_violated`` (0 / 1);
        per constant feed ``.feedrate_time_ratio`` (its time / the optimized time); with ``[feedrate.drive]``
        ``amplifier_limit.<axis>`` [V] and per label ``.drive_axis_error_max.<x|y|z>`` [mm],
        ``.drive_rotary_error_max.<a|c>`` [rad], ``.drive_saturated_fraction.<axis>``, ``.drive_saturated``,
        ``.drive_diverged``. Details: limits, schedules (method, status, limit ratios, binding stretches), drive.
        Arrays: ``feedrate.envelope.s`` [mm] and ``.velocity / .acceleration / .jerk`` ``(N, 5)`` [mm/s] (Fig 3.10,
        ``inf`` where an axis does not move); per label ``feedrate.<label>.s``, ``.feed`` (dense schedule) and
        ``.t``, ``.q``, ``.v``, ``.a``, ``.j`` (axis trajectory, ``x..c`` [mm, rad]); with the drive
        ``feedrate.<label>.drive.t``, ``.axis_error`` ``(M, 5)``, ``.saturated`` ``(M, 5)`` (0 / 1), read every 1 ms.
    Raises:
        InfeasibleProblem: the optimisation fails (named window and status); UnstableGainsError: drive gains
        unstable at the control period.
    """
    from research.optimal import axis_feed_limits, constant_feed, optimize_feedrate, table31_limits

    limits = table31_limits(fc.rotary_jerk_unit)
    Ts = fc.sample_period_ms * 1e-3
    schedules = {"optimized": optimize_feedrate(
        path, limits, fc.feed_mm_per_s, control_points=fc.control_points, checks_per_span=fc.checks_per_span,
        refinements=fc.refinements, tolerance=fc.tolerance, constraint_form=fc.constraint_form,
        objective=fc.objective, sample_period=Ts)}
    for f in fc.constant_feeds_mm_per_s:
        schedules[constant_label(f)] = constant_feed(path, limits, f, sample_period=Ts)
    scalars = {"feedrate_path_length": float(path.length)}
    details = {"path": getattr(path, "name", ""), "path_length_mm": float(path.length),
               "limits": {"velocity": limits.velocity.tolist(), "acceleration": limits.acceleration.tolist(),
                          "jerk": limits.jerk.tolist(), "units": "mm, rad per s^k (x y z a c)"},
               "feed_mm_per_s": fc.feed_mm_per_s, "schedules": {}}
    s_env = np.linspace(0.0, float(path.length), fc.envelope_points)
    env = axis_feed_limits(path, limits, s_env)
    arrays = {"feedrate.envelope.s": s_env} | {f"feedrate.envelope.{k}": np.asarray(env[k]) for k in KINDS}
    t_opt = float(schedules["optimized"].cycle_time)
    for label, r in schedules.items():
        scalars |= _schedule_scalars(label, r, fc.tolerance)
        if label != "optimized":
            scalars[f"{label}.feedrate_time_ratio"] = float(r.cycle_time) / t_opt
        details["schedules"][label] = _schedule_details(r)
        tr = r.trajectory
        arrays |= {f"feedrate.{label}.s": np.asarray(r.s), f"feedrate.{label}.feed": np.asarray(r.feed)}
        arrays |= {f"feedrate.{label}.{k}": np.asarray(getattr(tr, k)) for k in ("t", "q", "v", "a", "j")}
    if fc.drive is not None:
        found, details["drive"], more = _drive(fc.drive, limits, schedules)
        scalars |= found
        arrays |= more
    return scalars, details, arrays


def _drive(dc: FeedrateDriveConfig, limits, schedules: dict) -> tuple[dict, dict, dict]:
    """Fig 3.13: each schedule through the SISO SMC drives with the Table 3.1 amplifier limit."""
    from research.control import amplifier_limits, feed_tracking, thesis_plant

    T = dc.control_period_ms * 1e-3
    plant0 = thesis_plant()
    coulomb = coulomb_friction(dc, plant0, T)
    plant = thesis_plant(coulomb)
    u_max = amplifier_limits(plant, limits)
    scalars = {f"amplifier_limit.{a}": float(u) for a, u in zip(AXES, u_max)}
    arrays, runs = {}, {}
    for label, sched in schedules.items():
        run = feed_tracking(sched.trajectory, plant, u_max, T=T, divergence_limit=dc.divergence_limit)
        e = run.max_error()
        scalars |= {f"{label}.drive_axis_error_max.{a}": float(v) for a, v in zip(AXES[:3], e[:3])}
        scalars |= {f"{label}.drive_rotary_error_max.{a}": float(v) for a, v in zip(AXES[3:], e[3:])}
        scalars |= {f"{label}.drive_saturated_fraction.{a}": float(v) for a, v in zip(AXES, run.saturated_fraction)}
        scalars |= {f"{label}.drive_saturated": float(np.any(run.saturated_fraction > 0)),
                    f"{label}.drive_diverged": float(run.diverged)}
        arrays |= {f"feedrate.{label}.drive.t": run.t, f"feedrate.{label}.drive.axis_error": run.axis_error,
                   f"feedrate.{label}.drive.saturated": run.saturated.astype(np.int8)}
        runs[label] = {"diverged_at_s": None if np.isnan(run.diverged_at) else float(run.diverged_at)}
    details = {"control_period_s": T, "coulomb_V": coulomb.tolist(), "u_max_V": u_max.tolist(),
               "friction": "given" if dc.coulomb_V is not None else dc.friction, "runs": runs}
    return scalars, details, arrays
