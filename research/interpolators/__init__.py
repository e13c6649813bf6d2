"""Interpolators: tool path -> :class:`~research.trajectory.Trajectory`."""

from research.interpolators._fir_chain import (
    acceleration_spectrum,
    delays_for_modes,
    frequency_response,
    kernel_second_integral,
    magnitude_response,
    total_delay,
)
from research.interpolators._fir_overlap import cornering_error, overlap_time
from research.interpolators.fir import (
    FIRPlan,
    fir_by_convolution,
    fir_interpolate,
    plan_fir,
)
from research.interpolators.scurve import (
    scurve_interpolate,
    scurve_phases,
    scurve_profile,
)
from research.interpolators.sigmoid import (
    SigmoidMotion,
    mtp_linear_baseline,
    mtp_motion,
    sigmoid_trajectory,
)

__all__ = [
    "FIRPlan",
    "acceleration_spectrum",
    "cornering_error",
    "delays_for_modes",
    "fir_by_convolution",
    "fir_interpolate",
    "frequency_response",
    "kernel_second_integral",
    "magnitude_response",
    "overlap_time",
    "plan_fir",
    "SigmoidMotion",
    "mtp_linear_baseline",
    "mtp_motion",
    "scurve_interpolate",
    "scurve_phases",
    "scurve_profile",
    "sigmoid_trajectory",
    "velocity_transition",
    "total_delay",
]
