"""Feedback controllers beyond the drives' own loops (Sencer 2009 thesis ch 5): the SISO sliding-mode
axis controller with disturbance adaptation (thesis [35], Table 5.2), the tool-tip contour controller
(§5.2, eq 5.1-5.17, Table 5.3) and the orientation contour controller (§5.3, eq 5.18-5.39), run in
closed loop on the rigid-body drives of Table 5.1 through the A/C table-tilting kinematics; and the
thesis' end-to-end results that need these drives: Fig 3.13 (feed schedules through the SISO drives
with an amplifier limit, :func:`feed_tracking`). (§6.5.3 / Fig 6.13, the identified Table 6.3 machine
predicting contour errors, is :func:`research.contour.fig6_13`.) Units: mm, s, rad; voltages in V.
"""

from research.control._compensation import SchemeResult, corrected_reference, feedback_vs_feedforward, tracking_mirror_passes
from research.control._gains import (
    AXES,
    DIRECTIONS,
    AxisSMC,
    ContourGains,
    TipGains,
    check_axis_gains,
    check_tip_gains,
    closed_loop_eigenvalues,
    plant_step_matrices,
    table_5_2,
    table_5_3,
)
from research.control._feed_tracking import FeedTracking, amplifier_limits, feed_tracking
from research.control._loop import ClosedLoopResult, direction_inertia, simulate_closed_loop
from research.control._plant import FiveAxisPlant, thesis_plant
from research.control._reference import ContourReference, eq436_reference, joint_reference, parametric_reference
from research.control._study import (
    CONTROL_PERIOD,
    FIG5_7_AXIS_PEAKS,
    FIG5_7_CONTOUR,
    LOG_PERIOD,
    TABLE_5_4,
    TABLE_5_5,
    CaseResult,
    check_controller,
    identify_coulomb,
    measure,
    run_case,
    step_disturbance_peak,
    table_5_4,
    table_5_5,
)

__all__ = [
    "FeedTracking",
    "amplifier_limits",
    "feed_tracking",
    "joint_reference",
    "AXES",
    "CONTROL_PERIOD",
    "CaseResult",
    "FIG5_7_AXIS_PEAKS",
    "FIG5_7_CONTOUR",
    "LOG_PERIOD",
    "TABLE_5_4",
    "TABLE_5_5",
    "SchemeResult",
    "check_controller",
    "corrected_reference",
    "feedback_vs_feedforward",
    "identify_coulomb",
    "measure",
    "tracking_mirror_passes",
    "run_case",
    "step_disturbance_peak",
    "table_5_4",
    "table_5_5",
    "AxisSMC",
    "ClosedLoopResult",
    "ContourGains",
    "ContourReference",
    "DIRECTIONS",
    "FiveAxisPlant",
    "TipGains",
    "check_axis_gains",
    "check_tip_gains",
    "closed_loop_eigenvalues",
    "direction_inertia",
    "eq436_reference",
    "parametric_reference",
    "plant_step_matrices",
    "simulate_closed_loop",
    "table_5_2",
    "table_5_3",
    "thesis_plant",
]
