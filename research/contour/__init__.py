"""Contour error and its compensation (Prévost, Lavernhe, Lartigue, HSM 2012; Sencer 2009 thesis
§4.3-4.4).

- Exact contour error (spatial index + local projection) and tracking error:
  :func:`contour_error`, :func:`tracking_error`, :func:`brute_force_contour_error` (reference only).
- Prévost's decomposition e1 / e2 / eT: :func:`execution_errors`.
- The thesis' estimators: :func:`frenet_contour_estimates` (basic eq 4.20, shifted eq 4.21-4.22,
  compensated eq 4.23-4.27), :func:`orientation_contour_error` (eq 4.28-4.35), the exact errors they
  approximate, and the §4.5 study on the eq 4.36 path (:func:`five_axis_contour_study`).
- CEC mirror compensation (eq 3-4): :func:`cec_problem`; Prévost's method, one mirror pass
  (:func:`mirror_single_pass`); extensions beyond the paper: :func:`mirror_compensation` (iterated
  mirror by optimistix ``FixedPointIteration``, or model inversion by ``Newton``) and
  :func:`mirror_passes`; the limit check :func:`check_setpoint`; Prévost's two applications
  ready-made (:func:`prevost2012_application1`, ...).
- Cornering tolerance held after the servo: :func:`servo_tolerance` plans the FIR at the reduced
  tolerance whose simulated actual corner error is eps (:func:`vertex_distances`).
- Thesis §6.5.3 / Fig 6.13: the Table 6.3 virtual machine identified axis by axis (LS, PSO) and the
  identified models predicting the eq 4.36 tip contour error (:func:`fig6_13`).
- The EMPS chain: identify the real EMPS axis, then CEC on a path within its stroke
  (:func:`emps_cec_chain`).
"""

from research.contour._cec import (
    EXTENSIONS,
    PAPER_METHOD,
    CECProblem,
    CompensationResult,
    cec_problem,
    corrected_setpoint,
    cubic_hold,
    execution_error_vector,
    intersample_response,
    mirror_compensation,
    mirror_passes,
    mirror_single_pass,
    mirror_step,
    q_filter,
    simulate_correction,
    simulate_setpoint,
)
from research.contour._decomposition import ExecutionErrors, execution_errors
from research.contour._emps import EMPSChainResult, emps_cec_chain
from research.contour._exact import (
    ContourError,
    TrackingError,
    brute_force_contour_error,
    check_same_grid,
    contour_error,
    tracking_error,
)
from research.contour._identified_machine import (
    FIG6_13_ACCELERATION,
    FIG6_13_BOUND,
    FIG6_13_FEED,
    TABLE_6_3_PSO,
    AxisIdentification,
    ContourPrediction,
    fig6_13,
    identify_table_6_3,
    predict_contour_error,
)
from research.contour._five_axis import FiveAxisContourStudy, eq436_trajectory, five_axis_contour_study
from research.contour._frenet import (
    FrenetEstimates,
    OrientationContourError,
    exact_orientation_contour_error,
    exact_tip_contour_error,
    frenet_contour_estimates,
    frenet_frame,
    orientation_contour_error,
    tip_reference,
)
from research.contour._geometry import Projection, dense_polyline, project, trajectory_polyline
from research.contour._limits import LimitCheck, check_setpoint
from research.contour._servo_tolerance import ServoTolerance, held_at_rest, servo_tolerance, vertex_distances
from research.contour._prevost import (
    APPLICATION2_TOLERANCE,
    PREVOST_FEED,
    PREVOST_TS,
    STANDIN_DELAYS,
    PrevostCase,
    prevost2012_application1,
    prevost2012_application2,
    smoothed_corner_case,
)

__all__ = [
    "AxisIdentification",
    "ContourPrediction",
    "FIG6_13_ACCELERATION",
    "FIG6_13_BOUND",
    "FIG6_13_FEED",
    "TABLE_6_3_PSO",
    "fig6_13",
    "identify_table_6_3",
    "predict_contour_error",
    "ServoTolerance",
    "held_at_rest",
    "servo_tolerance",
    "vertex_distances",
    "APPLICATION2_TOLERANCE",
    "CECProblem",
    "CompensationResult",
    "ContourError",
    "EMPSChainResult",
    "ExecutionErrors",
    "FiveAxisContourStudy",
    "FrenetEstimates",
    "LimitCheck",
    "OrientationContourError",
    "EXTENSIONS",
    "PAPER_METHOD",
    "PREVOST_FEED",
    "PREVOST_TS",
    "PrevostCase",
    "Projection",
    "TrackingError",
    "brute_force_contour_error",
    "cec_problem",
    "check_same_grid",
    "check_setpoint",
    "contour_error",
    "corrected_setpoint",
    "cubic_hold",
    "dense_polyline",
    "emps_cec_chain",
    "eq436_trajectory",
    "exact_orientation_contour_error",
    "exact_tip_contour_error",
    "execution_error_vector",
    "execution_errors",
    "five_axis_contour_study",
    "frenet_contour_estimates",
    "frenet_frame",
    "intersample_response",
    "mirror_compensation",
    "mirror_passes",
    "mirror_single_pass",
    "mirror_step",
    "orientation_contour_error",
    "prevost2012_application1",
    "prevost2012_application2",
    "project",
    "q_filter",
    "simulate_correction",
    "simulate_setpoint",
    "smoothed_corner_case",
    "STANDIN_DELAYS",
    "tip_reference",
    "tracking_error",
    "trajectory_polyline",
]
