"""The ``[optimality]`` stage: FIR overlap, plain and holding the limits, against the converged time-optimal OCP
on the optimality study's paths (the study's own functions: :func:`~research.experiments.optimality.study_limits`,
:func:`~research.experiments.optimality.cam_like_path`; the OCP by :func:`research.optimal.converged_time_optimal`
as the study solves it). Two checks computed apart from the planners:

- the plain FIR's cycle time equals its closed form ``sum L_k / F_k + T_d + sum_k (T_d - T_k)`` (Sencer 2015 eq 5 and 11:
  each block lasts its pulse plus the chain delay ``T_d = sum T_i``, consecutive blocks overlap by ``T_k``); the
  limit-holding planner may split a block into pieces of lower feed, so it is not checked there;
- the OCP's cycle time is at least ``L_cut / F``: the motion stays in the tube of radius ``eps`` and so crosses each
  corner's bisector within ``r_k = eps / sin(alpha_k / 2)`` of the vertex (``alpha_k`` the interior angle), so its
  length is at least ``L_cut = sum_i max(0, L_i - r_i - r_(i+1))`` (``r = 0`` at the ends), at speed ``<= F``.
"""

from __future__ import annotations

import numpy as np


def cut_length(path, tolerance: float) -> float:
    """``L_cut`` [mm] of the module docstring: the polyline length less, at each corner, the radius ``r_k``
    within which a curve in the tube of radius ``tolerance`` [mm] must cross the corner's bisector."""
    alpha = np.pi - np.asarray(path.turning_angles)  # interior angle at each corner
    r = np.concatenate([[0.0], tolerance / np.maximum(np.sin(alpha / 2), 1e-12), [0.0]])
    return float(np.sum(np.maximum(0.0, np.asarray(path.lengths) - r[:-1] - r[1:])))


def fir_closed_form(path, plan) -> float:
    """``sum L_k / F_k + T_d + sum_k (T_d - T_k)`` [s] from the plan's feeds and overlaps (Sencer 2015 eq 5, 11)."""
    Td = float(np.sum(np.asarray(plan.delays)))
    return float(np.sum(np.asarray(path.lengths) / np.asarray(plan.feeds)) + Td
                 + np.sum(Td - np.asarray(plan.overlaps)))


def optimality_stage(c) -> tuple[dict, dict, dict]:
    """Run ``c`` (:class:`~research.experiments.config_optimality.OptimalityConfig`).

    Returns:
        ``(scalars, details, arrays)``: per ``<path>.<convention>.`` the metrics of
        :data:`~research.experiments.config_optimality.OPTIMALITY_METRIC_UNITS`; details per path and convention
        (OCP grid history ``[N, T, iterations, IPOPT s]``, dense check ratio, limits); arrays
        ``opt.<path>.<convention>.<fir|fir_held|ocp>.t / .q`` [s, mm] and ``opt.<path>.points`` [mm].
    """
    from research.experiments.optimality import cam_like_path, study_limits
    from research.interpolators import plan_fir
    from research.optimal import converged_time_optimal
    from research.paths import named_path

    feed, tol, delays = c.feed_mm_per_s, c.tolerance_um * 1e-3, np.asarray(c.delays_ms) * 1e-3
    Ts = c.sample_period_ms * 1e-3
    scalars, details, arrays = {}, {}, {}
    for name in c.paths:
        path = cam_like_path(30) if name == "cam30" else named_path(name)
        arrays[f"opt.{name}.points"] = np.asarray(path.points)
        plain = plan_fir(path, feed, delays, tol)
        fir = plain.trajectory(Ts)
        lower = cut_length(path, tol) / feed
        details[name] = {"length_mm": float(np.sum(path.lengths)), "cut_length_mm": lower * feed}
        for conv in c.conventions:
            limits = study_limits(conv, path, fir, feed, delays)
            held_plan = plan_fir(path, feed, delays, tol, limits=limits)
            held = held_plan.trajectory(Ts)
            ocp = converged_time_optimal(path, limits, tol, feed=feed, warm_start=fir if conv == "a" else None,
                                         start_intervals=c.start_intervals, rel_change=c.rel_change_percent * 1e-2,
                                         max_intervals=c.max_intervals, sample_period=Ts)
            T = {"fir": float(fir.duration), "fir_held": float(held.duration), "ocp": float(ocp.cycle_time)}
            p = f"{name}.{conv}."
            scalars |= {p + "fir_cycle_time": T["fir"], p + "fir_held_cycle_time": T["fir_held"],
                        p + "ocp_cycle_time": T["ocp"], p + "fir_ocp_ratio": T["fir"] / T["ocp"],
                        p + "fir_held_ocp_ratio": T["fir_held"] / T["ocp"], p + "ocp_bound_ratio": T["ocp"] / lower,
                        p + "ocp_converged": float(ocp.converged),
                        p + "fir_closed_form_gap": abs(T["fir"] - fir_closed_form(path, plain))}
            details[name][conv] = {"ocp_history": [list(map(float, h)) for h in ocp.history],
                                   "ocp_dense_check": float(ocp.result.verification.worst_ratio),
                                   "limits": {k: np.asarray(getattr(limits, k)).tolist()
                                              for k in ("velocity", "acceleration", "jerk")}}
            for key, tr in (("fir", fir), ("fir_held", held), ("ocp", ocp.result.trajectory)):
                arrays |= {f"opt.{name}.{conv}.{key}.t": np.asarray(tr.t), f"opt.{name}.{conv}.{key}.q": np.asarray(tr.q)}
    return scalars, details, arrays
