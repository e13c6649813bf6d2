"""Prévost, Lavernhe, Lartigue (HSM 2012) applications as ready-made CEC problems.

Choices (the paper names neither its CNC interpolator nor its drive parameters):

- drive: the thesis Table 6.1 P-PI virtual drive as a physical cascade
  (:func:`research.drives.table_6_1_ppi`), on both axes, so the control voltage is available for the
  effort check;
- interpolator: the FIR interpolator (Sencer 2015), jerk-limited with two filters;
- Application 1 (B-spline, Fig 4-5): Ts = 6 ms (the paper's T_sampling), T1 = 24 ms, T2 = 12 ms, on the
  B-spline sampled as a polyline with 0.1 um chord error, full overlap at its (tiny) corners (eq 13/14
  only, no short-segment refinement): this rounds the curve like a CNC filter does;
- Application 2 (sharp corner, Fig 1/6): two 50 mm lines at 90 deg, Ts = 1 ms, T1 = 100 ms,
  T2 = 50 ms, cornering tolerance 24 um at the vertex, i.e. e1 = 24 / sqrt(2) = 17 um from the lines,
  Prévost's "deviations e1 up to 17 um" (Fig 6b);
- both at the paper's programmed feed of 10 m/min.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from research.contour._cec import CECProblem, cec_problem, simulate_setpoint
from research.drives import table_6_1_ppi
from research.interpolators import fir_interpolate
from research.limits import AxisLimits
from research.paths.bspline import prevost2012_bspline
from research.paths.library import corner90
from research.trajectory import Trajectory

#: programmed feed of both applications, 10 m/min in mm/s (Prévost §4.1)
PREVOST_FEED = 10000.0 / 60.0


@dataclass(frozen=True)
class PrevostCase:
    """A CEC case: CAM path, setpoint, drive, the loop problem and the limits it is checked against.

    Attributes:
        name: case name.
        cam_path: CAM path.
        setpoint: interpolator output.
        drive: drive model (both axes).
        problem: :class:`CECProblem` for the CAM path.
        limits: the interpolator's nominal envelope ``v = F``, ``a = F/T1``, ``j = F/(T1 T2)`` with
            5 % headroom.
        control_limit: ``(A,)`` 1.05 x the uncompensated peak control voltage [V] (Prévost: current and
            jerk after compensation should stay "very close to those before"; the virtual drive's
            voltage scale has no physical amplifier limit).
    """

    name: str
    cam_path: object
    setpoint: Trajectory
    drive: object
    problem: CECProblem
    limits: AxisLimits
    control_limit: np.ndarray


def _case(name, path, polyline, delays, tolerance, Ts, refine):
    setpoint = fir_interpolate(polyline, PREVOST_FEED, list(delays), tolerance, Ts, refine=refine)
    drive = table_6_1_ppi()
    env = AxisLimits.fir_envelope(2, PREVOST_FEED, delays)
    limits = AxisLimits(env.velocity * 1.05, env.acceleration * 1.05, env.jerk * 1.05)
    control = np.max(np.abs(np.asarray(simulate_setpoint(setpoint, drive).control)), axis=0) * 1.05
    return PrevostCase(name, path, setpoint, drive, cec_problem(path, setpoint, drive), limits, control)


def prevost2012_application1() -> PrevostCase:
    """Application 1: the Fig 4 B-spline at 10 m/min (module docstring for the choices)."""
    c = prevost2012_bspline()
    return _case("prevost2012_application1", c, c.to_polyline(1e-4), (0.024, 0.012), 0.05, 0.006, False)


def prevost2012_application2() -> PrevostCase:
    """Application 2: the 90 deg sharp corner at 10 m/min (module docstring for the choices)."""
    p = corner90()
    return _case("prevost2012_application2", p, p, (0.1, 0.05), 0.024, 0.001, True)


def smoothed_corner_case(case: PrevostCase) -> PrevostCase:
    """The paper's suggestion (§4.2), taken further: replace the sharp CAM corner by a tangent-continuous
    target within the cornering tolerance, here the curve traced by the interpolated setpoint itself
    (C2, within 17 um of the CAM lines), and compensate towards it."""
    target = case.setpoint
    return PrevostCase(case.name + "_smoothed", target, case.setpoint, case.drive,
                       cec_problem(target, case.setpoint, case.drive), case.limits, case.control_limit)
