"""Feed-drive models (Sencer 2009 thesis ch 6, Sencer et al. 2015 §4): rigid-body axis, P-PI and PID
control, the general 3-pole/3-zero closed-loop model with Coulomb friction, structural modes, encoder
models, exact discrete-time simulation with ``jax.lax.scan``, frequency responses and the thesis'
virtual drives. Units: mm, s, rad (rotary axes in rad); frequencies in rad/s unless a name says Hz.
"""

from research.drives._catalog import (
    TABLE_4_1,
    TABLE_6_3,
    VIRTUAL_DRIVES,
    table_4_1_axis,
    table_6_1_closed_loop,
    table_6_1_ppi,
    table_6_2_closed_loop,
    table_6_2_pid,
    table_6_3_closed_loop,
    table_6_3_ppi,
    virtual_drive,
)
from research.drives._closed_loop import ClosedLoopModel, denominator_from_poles
from research.drives._controllers import PIDController, PPICascade
from research.drives._frequency import FrequencyResponse, PoleZeroReport, frequency_response, pole_zero_report
from research.drives._friction import coulomb_sign, smooth_sign
from research.drives._modes import FlexibleMode
from research.drives._residual_vibration import fir_pulse_residual, residual_vibration_sampled
from research.drives._rigid_body import RigidBodyAxis
from research.drives._sensors import THESIS_LINEAR_ENCODER, THESIS_ROTARY_ENCODER, Encoder, measure
from research.drives._simulate import DriveResponse, discretize, simulate

__all__ = [
    "ClosedLoopModel",
    "DriveResponse",
    "Encoder",
    "FlexibleMode",
    "FrequencyResponse",
    "PIDController",
    "PPICascade",
    "PoleZeroReport",
    "RigidBodyAxis",
    "TABLE_4_1",
    "TABLE_6_3",
    "THESIS_LINEAR_ENCODER",
    "THESIS_ROTARY_ENCODER",
    "coulomb_sign",
    "denominator_from_poles",
    "discretize",
    "fir_pulse_residual",
    "frequency_response",
    "measure",
    "pole_zero_report",
    "residual_vibration_sampled",
    "simulate",
    "smooth_sign",
    "table_4_1_axis",
    "table_6_1_closed_loop",
    "table_6_1_ppi",
    "table_6_2_closed_loop",
    "table_6_2_pid",
    "table_6_3_closed_loop",
    "table_6_3_ppi",
    "virtual_drive",
    "VIRTUAL_DRIVES",
]
