"""The ``[control]`` stage: thesis ch 5 closed loop from a :class:`~research.experiments.config_control.ControlConfig`.

Builds the controller from the config (thesis tables unless overridden), runs the Fig 5.5 path through
the Table 5.1 drives (:func:`research.control.run_case`, or :func:`research.control.tracking_mirror_passes`
when ``mirror_passes > 0``) and returns the §5.4 metrics: tool-tip contour error (exact, max and mean),
the ch 4 compensated estimate's largest error, orientation contour error and the eq 4.34/4.35 estimate's
largest error, peak axis errors and voltages, and whether the loop diverged.

A table with ``cases`` (``[[control.cases]]``, :class:`~research.experiments.config_control.ControlCase`) runs
each case (its keys over the table's) with the friction identified once, and reports every case's metrics
under its label and the ratios each case asks for (``ratio_to``): the thesis compares runs (SISO against
contour controller, feeds, bandwidths, weights W) by such ratios and orderings.
"""

from __future__ import annotations

import numpy as np

from research.experiments.config_control import ControlConfig

AXES = ("x", "y", "z", "a", "c")


def _pick(given, default):
    """The configured gains where given, else the table's ``default``."""
    return np.asarray(default) if given is None else np.asarray(given, dtype=np.float64)


def controller_from_config(cc: ControlConfig):
    """The :class:`~research.control.AxisSMC` or :class:`~research.control.ContourGains` the config describes."""
    from research.control import AxisSMC, ContourGains, TipGains, table_5_2, table_5_3

    if cc.controller == "siso":
        base = table_5_2()
        return AxisSMC(_pick(cc.siso_bandwidth_rad_per_s, base.lam), _pick(cc.siso_Ks, base.Ks),
                       _pick(cc.siso_Gamma, base.Gamma))
    base = table_5_3(cc.tip_damping)
    tip = TipGains(_pick(cc.tip_bandwidth_rad_per_s, base.tip.wn), _pick(cc.tip_Ks, base.tip.Ks),
                   _pick(cc.tip_Gamma, base.tip.Gamma), cc.tip_damping)
    rotary = AxisSMC(_pick(cc.rotary_bandwidth_rad_per_s, base.rotary.lam), _pick(cc.rotary_Ks, base.rotary.Ks),
                     _pick(cc.rotary_Gamma, base.rotary.Gamma), n=2)  # A and C of the contour scheme (Fig 5.4)
    return ContourGains(tip, rotary, tuple(cc.orientation_weights_per_s))


def control_stage(cc: ControlConfig) -> tuple[dict[str, float], dict, dict[str, np.ndarray]]:
    """Run the closed loop of ``cc``: one run, or each of its ``cases`` (friction identified once).

    Returns:
        ``(scalars, details, arrays)``: scalars named as :data:`CONTROL_METRIC_UNITS` (per-axis ones
        suffixed ``.x`` ... ``.c``); details: the controller, friction used and the summary; arrays
        ``control.t`` [s], ``control.axis_error`` ``(M, 5)`` [mm, rad], ``control.tip_contour_error``
        [mm], ``control.orientation_error`` [rad], ``control.orientation_estimate`` (eq 4.34/4.35) [rad],
        ``control.u`` ``(M, 5)`` [V], read at 1 kHz. With cases: every scalar ``<label>.<metric>``, plus
        ``<label>.<metric>_ratio.<other>`` for each label of its ``ratio_to``; arrays
        ``control.<label>.<name>``; details ``{"coulomb_V", "control_period_s", "labels", "cases": {label:
        details}}``.
    Raises:
        UnstableGainsError: a gain set whose sampled loop is unstable at the control period (the
        eigenvalue is named); ParameterError: inconsistent gains.
    """
    from research.control import eq436_reference, identify_coulomb, thesis_plant

    T = cc.control_period_ms * 1e-3
    plant = thesis_plant()
    runs = cc.case_configs()
    references = {}  # (feed, acceleration) -> the eq 4.36 reference, built once per config (it costs more than a run)

    def reference(feed, acceleration):
        if (feed, acceleration) not in references:
            references[feed, acceleration] = eq436_reference(feed=feed, acceleration=acceleration, sample_period=T)
        return references[feed, acceleration]

    if cc.coulomb_V is None:  # identified on the thesis' Fig 5.7 run (50 mm/s, 1500 mm/s^2)
        coulomb = identify_coulomb(plant, T=T, reference=reference(50.0, 1500.0)[0])
    else:
        coulomb = np.asarray(cc.coulomb_V, dtype=np.float64)
    if cc.cases is None:
        return _one_run(cc, plant, coulomb, T, reference(cc.feed_mm_per_s, cc.acceleration_mm_per_s2))
    scalars, details, arrays = {}, {"coulomb_V": [float(c) for c in coulomb], "control_period_s": T, "cases": {}}, {}
    for label, case_cc in runs.items():
        found, details["cases"][label], more = _one_run(
            case_cc, plant, coulomb, T, reference(case_cc.feed_mm_per_s, case_cc.acceleration_mm_per_s2))
        scalars |= {f"{label}.{k}": v for k, v in found.items()}
        arrays |= {f"control.{label}.{k.removeprefix('control.')}": v for k, v in more.items()}
    ratios = {}
    for case in cc.cases:
        for other in case.ratio_to:
            for k, v in scalars.items():
                if k.startswith(f"{case.label}.") and not k.endswith(".diverged"):
                    metric, _, axis = k.removeprefix(f"{case.label}.").partition(".")
                    axis = f".{axis}" if axis else ""
                    denominator = scalars[f"{other}.{metric}{axis}"]
                    ratios[f"{case.label}.{metric}_ratio.{other}{axis}"] = v / denominator if denominator else float("nan")
    scalars |= ratios
    details["labels"] = list(runs)
    return scalars, details, arrays


def _one_run(cc: ControlConfig, plant, coulomb, T, reference) -> tuple[dict[str, float], dict, dict[str, np.ndarray]]:
    """One closed-loop run of ``cc`` on ``plant`` with friction ``coulomb`` [V] at period ``T`` [s] on ``reference``
    (the pair of :func:`research.control.eq436_reference` at the run's feed and acceleration)."""
    from research.control import check_controller, measure, run_case, tracking_mirror_passes

    controller = controller_from_config(cc)
    if cc.mirror_passes == 0:
        limit = cc.amplifier_limit_V
        u_max = None if limit is None else np.broadcast_to(np.asarray(limit, dtype=np.float64), (5,))
        case = run_case(controller, feed=cc.feed_mm_per_s, coulomb=coulomb, plant=plant, T=T,
                        acceleration=cc.acceleration_mm_per_s2, u_max=u_max, reference=reference)
    else:
        loaded = plant.with_coulomb(coulomb)
        check_controller(controller, loaded, T)
        ref, traj = reference
        runs = tracking_mirror_passes(loaded, ref, controller, cc.mirror_passes)
        case = measure(ref, traj, runs[-1])
    s = case.summary()
    scalars = {"tip_contour_error_max": s["contour_max"], "tip_contour_error_mean": s["contour_mean"],
               "tip_estimate_error_max": s["estimate_error_max"]["estimate"],
               "orientation_error_max": s["orientation_max"], "orientation_error_mean": s["orientation_mean"],
               "orientation_estimate_error_max": s["orientation_estimate_error_max"],
               "diverged": float(s["diverged"])}
    scalars |= {f"axis_error_max.{a}": v for a, v in zip(AXES[:3], s["axis_max"][:3])}
    scalars |= {f"rotary_axis_error_max.{a}": v for a, v in zip(AXES[3:], s["axis_max"][3:])}
    scalars |= {f"control_voltage_max.{a}": v for a, v in zip(AXES, s["u_max"])}
    details = {"controller": cc.controller, "feed_mm_per_s": cc.feed_mm_per_s,
               "coulomb_V": [float(c) for c in np.atleast_1d(coulomb)], "control_period_s": T,
               "mirror_passes": cc.mirror_passes, "orientation_weights_per_s": list(cc.orientation_weights_per_s),
               "summary": s}
    if cc.controller == "contour":
        details["tip_bandwidth_rad_per_s"] = [float(w) for w in np.asarray(controller.tip.wn)]
    arrays = {"control.t": case.t, "control.axis_error": case.axis_error, "control.tip_contour_error": case.contour,
              "control.orientation_error": case.orientation, "control.orientation_estimate": case.orientation_estimate,
              "control.u": case.u}
    return scalars, details, arrays
