"""The whole chain on real data: the EMPS axis identified from its log, then CEC on a path within that
axis' stroke and limits, with the predicted contour error before and after.

The EMPS benchmark (Janot, Gautier, Brunot 2019) is a single real axis. The CEC study needs a contour,
so both axes of a hypothetical XY table are given the EMPS axis' identified closed-loop model (thesis
eq 6.3, fitted by :func:`research.identification.identify_emps`: bounded variable projection, then the
output-error fit; the output-error model is used). The path is Prévost's Application 1 B-spline
shifted by (+150, +100) mm into the logged stroke ``[0, 246]`` mm; the feed and the FIR delays keep the
nominal setpoint within the logged reference's peak velocity (127.8 mm/s) and acceleration
(~840 mm/s^2): F = 100 mm/s, T1 = 120 ms (a = F/T1 = 833 mm/s^2), T2 = 60 ms, Ts = 1 ms (the log's rate).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from research.contour._cec import CompensationResult, cec_problem, mirror_compensation, mirror_passes
from research.errors import ConvergenceError, ParameterError
from research.interpolators import fir_interpolate
from research.limits import AxisLimits
from research.paths.bspline import BSplinePath, prevost2012_bspline
from research.trajectory import Trajectory

EMPS_FEED = 100.0  # mm/s
EMPS_DELAYS = (0.12, 0.06)  # s
EMPS_OFFSET = np.array([150.0, 100.0])  # mm


@dataclass(frozen=True)
class EMPSChainResult:
    """Outcome of :func:`emps_cec_chain`.

    Attributes:
        model: the identified :class:`~research.drives.ClosedLoopModel`.
        validation_rms_um: RMS of measured minus simulated position on the held-out 3 s [um].
        validation_fit: tracking-error fit on the held-out 3 s [%].
        path: the CAM B-spline in the EMPS stroke.
        setpoint: FIR setpoint.
        limits: the logged reference's peak |v|, |a| (jerk unbounded) per axis.
        stroke: ``(lo, hi)`` [mm] of the logged positions.
        compensation: the CEC result (before / after contour errors, limit check).
    """

    model: object
    validation_rms_um: float
    validation_fit: float
    path: BSplinePath
    setpoint: Trajectory
    limits: AxisLimits
    stroke: tuple[float, float]
    compensation: CompensationResult


def emps_cec_chain(log_path, *, passes: int = 5, smoothing: int = 31, tolerance: float = 2e-3,
                   max_steps: int = 20) -> EMPSChainResult:
    """Identify the EMPS axis from ``log_path`` and compensate the shifted Prévost B-spline on it.

    The identified model has a right-half-plane zero (about +497 rad/s), so the plain mirror rule
    diverges after two passes (323 -> 26.6 -> 26.1 -> 35.7 ... um); the default therefore applies
    ``passes`` mirror passes with a ``smoothing``-sample zero-phase Q-filter
    (:func:`research.contour.mirror_step`), which reaches ~7 um in 5 passes and then stalls.

    Args:
        log_path: ``emps_estimation_first15s.mat`` (s, m, m, V; converted to mm on loading).
        passes: mirror passes; 0 runs the optimistix fixed-point iteration to ``tolerance`` instead.
        smoothing: Q-filter window [samples at 1 ms] for the passes.
        tolerance: target max |e_T| [mm] and max_steps the cap, for the fixed-point iteration.
    Returns:
        :class:`EMPSChainResult`; the fixed-point iteration's non-convergence is not hidden: the result
        then comes from the :class:`~research.errors.ConvergenceError` and has ``converged = False``.
    """
    from research.identification import identify_emps, load_emps  # identification is optional here

    _, oe = identify_emps(log_path)
    model = oe.result.model()
    log = load_emps(log_path)
    ref = np.asarray(log.reference, dtype=np.float64).ravel()
    Ts_log = float(np.median(np.diff(np.asarray(log.t))))
    v = np.gradient(ref, Ts_log)
    a = np.gradient(v, Ts_log)
    limits = AxisLimits.uniform(2, float(np.max(np.abs(v))), float(np.max(np.abs(a))), np.inf)
    act = np.asarray(log.actual, dtype=np.float64).ravel()
    stroke = (float(min(ref.min(), act.min())), float(max(ref.max(), act.max())))
    base = prevost2012_bspline()
    path = BSplinePath(base.control_points + EMPS_OFFSET, base.knots, base.degree, base.axes)
    setpoint = fir_interpolate(path.to_polyline(1e-4), EMPS_FEED, list(EMPS_DELAYS), 0.5, 1e-3, refine=False)
    q = np.asarray(setpoint.q)
    if q.min() < stroke[0] or q.max() > stroke[1]:
        raise ParameterError(f"the EMPS path leaves the logged stroke {stroke} mm")
    problem = cec_problem(path, setpoint, model)
    if passes:
        comp = mirror_passes(problem, passes, smoothing=smoothing, limits=limits)
    else:
        try:
            comp = mirror_compensation(problem, method="fixed_point", tolerance=tolerance, max_steps=max_steps,
                                       limits=limits)
        except ConvergenceError as err:
            comp = err.result
    return EMPSChainResult(model, float(oe.rms_error_um["validation"]), float(oe.fits["validation"]["tracking_error"]),
                           path, setpoint, limits, stroke, comp)
