"""Prévost 2012 §2.2 / Fig 5 decomposition of the execution error in the ``[compensation]`` stage: ``e1``
(setpoint to CAM path), ``e2`` (actual to the curve the setpoint traces) and ``eT`` (actual to CAM path),
signed on planar paths (positive to the left of travel), before and after CEC, against the curvilinear
abscissa of the actual position's foot on the CAM path (the abscissa of the paper's Fig 5); and the abscissae
where an axis of a B-spline CAM path reverses (the "axis direction inversions" the paper's peaks sit at).
"""

from __future__ import annotations

import numpy as np

#: scalars of this module (units of :data:`~research.experiments.config.METRIC_UNITS`)
EXECUTION_ERROR_METRIC_UNITS = {
    "cec_interpolation_error_before": "mm",  # max |e1|, the setpoint to the CAM path
    "cec_interpolation_error_after": "mm",
    "cec_drive_error_before": "mm",  # max |e2|, the actual motion to the curve the setpoint traces
    "cec_drive_error_after": "mm",
    "cec_drive_error_ratio": "-",  # max |e2| after / before (Prévost: e2 is "the same after and before")
    "cec_decomposition_residual": "mm",  # max |e1 + e2 - eT| (before and after): Prévost's "algebraic sum"
    "axis_reversal_abscissa": "mm",  # arc length where a B-spline path's axis velocity changes sign
}


def abscissa(cam_path, points) -> np.ndarray:
    """Arc length [mm] along ``cam_path`` (Polyline or BSplinePath) of the closest point to each ``(N, d)`` point."""
    from research.paths.bspline import BSplinePath

    points = np.asarray(points, dtype=np.float64)
    if isinstance(cam_path, BSplinePath):
        return cam_path.arc_length(cam_path.project(points)[1])
    _, seg, frac = cam_path.project(points)
    return cam_path.arc_length[seg] + frac * cam_path.lengths[seg]


def axis_reversals(curve, samples: int = 20001) -> dict[str, list[float]]:
    """Arc lengths [mm] where each axis' velocity ``dC_k/du`` changes sign inside the curve (a sign change
    between neighbouring ones of ``samples`` parameters, refined by bisection to 1e-13 in ``u``; a sample where it
    is exactly zero between opposite signs is the reversal itself), per axis name."""
    u0, u1 = curve.domain
    u = np.linspace(u0, u1, samples)
    d = curve(u, 1)
    out = {}
    for k, axis in enumerate(curve.axes):
        sign = np.sign(d[:, k])
        found = []
        for i in np.flatnonzero(sign[:-1] * sign[1:] < 0):
            lo, hi = u[i], u[i + 1]
            while hi - lo > 1e-13:
                mid = 0.5 * (lo + hi)
                lo, hi = (mid, hi) if np.sign(curve(mid, 1)[0, k]) == sign[i] else (lo, mid)
            found.append(0.5 * (lo + hi))
        found += [u[i] for i in np.flatnonzero(sign[1:-1] == 0) + 1 if sign[i - 1] * sign[i + 1] < 0]
        out[axis] = [float(s) for s in curve.arc_length(np.sort(found))] if found else []
    return out


def execution_error_stage(cam_path, traj, actual, cec) -> tuple[dict, dict]:
    """e1, e2, eT before (``traj`` and the drive's ``actual`` positions on its grid) and after CEC (``cec``, a
    :class:`~research.contour.CompensationResult`), against the CAM path.

    Returns:
        ``(scalars [mm or -], arrays)``: the scalars of :data:`EXECUTION_ERROR_METRIC_UNITS` (and, for a B-spline,
        ``axis_reversal_abscissa.<axis>[.<i>]``); arrays ``cec.<e1|e2|eT>_<before|after>`` and ``cec.s_<before|after>``
        (abscissa of the actual position) per sample [mm].
    """
    from research.contour import execution_errors
    from research.paths.bspline import BSplinePath

    n = traj.n_samples
    t = np.asarray(traj.t)
    runs = {"before": (traj, np.asarray(actual)[:n]), "after": (cec.setpoint, np.asarray(cec.response.position))}
    scalars, arrays, residual = {}, {}, 0.0
    for when, (setpoint, position) in runs.items():
        ex = execution_errors(cam_path, setpoint, (t, position))
        arrays |= {f"cec.e1_{when}": ex.e1, f"cec.e2_{when}": ex.e2, f"cec.eT_{when}": ex.eT,
                   f"cec.s_{when}": abscissa(cam_path, position)}
        m = ex.max_abs()
        scalars |= {f"cec_interpolation_error_{when}": m["e1"], f"cec_drive_error_{when}": m["e2"]}
        residual = max(residual, float(np.max(np.abs(ex.e1 + ex.e2 - ex.eT))))
    scalars["cec_decomposition_residual"] = residual
    if scalars["cec_drive_error_before"] > 0:
        scalars["cec_drive_error_ratio"] = scalars["cec_drive_error_after"] / scalars["cec_drive_error_before"]
    if isinstance(cam_path, BSplinePath):
        for axis, found in axis_reversals(cam_path).items():
            for i, s in enumerate(found):
                scalars[f"axis_reversal_abscissa.{axis}" + (f".{i}" if len(found) > 1 else "")] = s
    return scalars, arrays
