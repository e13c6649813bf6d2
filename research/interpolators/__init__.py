"""Interpolators: tool path -> :class:`~research.trajectory.Trajectory`.

- FIR-overlap cornering (Sencer 2015): :func:`plan_fir`, :func:`fir_interpolate`; per-corner
  overlaps and per-block feeds optimized for cycle time (a named extension): :func:`optimize_fir`;
  the filters' input pre-compensated by mirror passes so that their output keeps the programmed
  path at higher feeds (a named extension, Prevost 2012's mirror): :func:`plan_fir_mirror`.
- Jerk-limited S-curve with exact stops (the "linear interpolator"): :func:`scurve_interpolate`,
  and the time-optimal double-S move with boundary speeds :func:`double_s`.
- Geometric corner smoothing (Sencer 2015 Fig 6 baseline): :func:`blend_interpolate`.
- Sigmoid / exponential interpolators for modulated tool paths (DiMarco 2015): :func:`mtp_motion`.
"""

from research.interpolators._fir_chain import (
    acceleration_spectrum,
    delays_for_modes,
    frequency_response,
    kernel_second_integral,
    magnitude_response,
    total_delay,
)
from research.interpolators._fir_mirror import MirrorPlan, plan_fir_mirror
from research.interpolators._fir_optimize import optimize_fir
from research.interpolators._fir_overlap import cornering_error, overlap_time
from research.interpolators.blend import blend_interpolate, corner_blends
from research.interpolators._fir_candidates import FIRSweep
from research.interpolators._fir_convolution import fir_by_convolution
from research.interpolators.fir import FIRPlan, fir_interpolate, plan_fir, plan_fir_sweep
from research.interpolators.scurve import double_s, max_end_speed, scurve_interpolate, scurve_phases, scurve_profile
from research.interpolators.sigmoid import (
    SigmoidMotion,
    mtp_blending_baseline,
    mtp_linear_baseline,
    mtp_motion,
    sigmoid_trajectory,
    velocity_transition,
)

__all__ = [
    "FIRPlan",
    "FIRSweep",
    "MirrorPlan",
    "SigmoidMotion",
    "acceleration_spectrum",
    "blend_interpolate",
    "corner_blends",
    "cornering_error",
    "delays_for_modes",
    "double_s",
    "fir_by_convolution",
    "fir_interpolate",
    "frequency_response",
    "kernel_second_integral",
    "magnitude_response",
    "max_end_speed",
    "mtp_blending_baseline",
    "mtp_linear_baseline",
    "mtp_motion",
    "optimize_fir",
    "overlap_time",
    "plan_fir",
    "plan_fir_mirror",
    "plan_fir_sweep",
    "scurve_interpolate",
    "scurve_phases",
    "scurve_profile",
    "sigmoid_trajectory",
    "total_delay",
    "velocity_transition",
]
