"""Prévost, Lavernhe, Lartigue (HSM 2012) applications as ready-made CEC problems.

The paper names neither its CNC interpolator nor its drive parameters; what is taken from its text
and what is a stand-in (every stand-in is an argument, and the figures sweep it):

- sample period: Ts = 6 ms, the paper's "T_sampling = 6ms" (§3), in both applications;
- programmed feed 10 m/min in both (§4.1, Fig 1);
- drive (stand-in): the thesis Table 6.1 P-PI virtual drive as a physical cascade
  (:func:`research.drives.table_6_1_ppi`) on both axes, so the control voltage is available for
  the effort check;
- interpolator (stand-in): the FIR interpolator (Sencer 2015), jerk-limited with two filters,
  T1 = 24 ms, T2 = 12 ms (:data:`STANDIN_DELAYS`), one CNC for both applications. Swept in
  Application 1 (12/6, 24/12, 48/24 ms): eT before 47 / 77 / 196 um, after one mirror pass
  2.4 / 3.4 / 8.6 um; the paper's 70 -> 2 um is a ratio of 35 (14 with its 5 um at the axis
  inversions), these give 20, 23 and 23;
- Application 1 (B-spline, Fig 4-5): "The machining program is executed using the B-spline format"
  (§4.1); here the B-spline is sampled as a polyline with 0.1 um chord error and run with full
  overlap at its (tiny) corners (eq 13/14 only, no short-segment refinement), which rounds the
  curve like a CNC filter does;
- Application 2 (sharp corner, Fig 1/6): two 50 mm lines at 90 deg. Cornering tolerance: the
  paper's Fig 1 text says the deviations at 0.1 m/min, where the servo errors vanish and only the
  CNC's rounding is left, do "not exceed 5µm"; 5 um (:data:`APPLICATION2_TOLERANCE`) is taken as
  the CNC's tolerance. (The previous version used 24 um, chosen so that e1 = 24 / sqrt(2) = 17 um,
  the paper's result; that was fitting the target.) A 90 deg corner rounded to ``eps`` at the
  vertex lies ``eps / sqrt(2)`` from the lines (eq 14 and symmetry), so e1 = 3.5 um here against
  the paper's 17 um: the paper's CNC rounds more than a 5 um tolerance would.
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
#: the NC sample period, "T_sampling = 6ms" (Prévost §3) [s]
PREVOST_TS = 0.006
#: stand-in FIR delays T1, T2 [s] of the unnamed CNC (module docstring; swept in the figures)
STANDIN_DELAYS = (0.024, 0.012)
#: Application 2 cornering tolerance [mm], from the Fig 1 text at 0.1 m/min (module docstring)
APPLICATION2_TOLERANCE = 0.005


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


def prevost2012_application1(delays=STANDIN_DELAYS) -> PrevostCase:
    """Application 1: the Fig 4 B-spline at 10 m/min, Ts = 6 ms (module docstring for the choices).

    Args:
        delays: FIR delays ``(T1, T2)`` [s] of the stand-in CNC.
    """
    c = prevost2012_bspline()
    return _case("prevost2012_application1", c, c.to_polyline(1e-4), tuple(delays), 0.05, PREVOST_TS, False)


def prevost2012_application2(tolerance: float = APPLICATION2_TOLERANCE, delays=STANDIN_DELAYS) -> PrevostCase:
    """Application 2: the 90 deg sharp corner at 10 m/min, Ts = 6 ms (module docstring).

    Args:
        tolerance: cornering tolerance ``eps`` [mm] at the vertex (a large value gives full overlap,
            the rounding set by the feed and the filters alone).
        delays: FIR delays ``(T1, T2)`` [s] of the stand-in CNC.
    """
    p = corner90()
    return _case("prevost2012_application2", p, p, tuple(delays), float(tolerance), PREVOST_TS, True)


def smoothed_corner_case(case: PrevostCase) -> PrevostCase:
    """The paper's suggestion (§4.2), taken further: replace the sharp CAM corner by a tangent-continuous
    target within the cornering tolerance, here the curve traced by the interpolated setpoint itself
    (C2, within ``eps / sqrt(2)`` of the CAM lines), and compensate towards it (beyond the paper)."""
    target = case.setpoint
    return PrevostCase(case.name + "_smoothed", target, case.setpoint, case.drive,
                       cec_problem(target, case.setpoint, case.drive), case.limits, case.control_limit)
