"""Resonance tests: accelerometer logs -> structural modes -> FIR delays (Sencer 2015 eq 10).

- Logs: :func:`load_accel_log` (CSV ``#time,accel_x,accel_y,accel_z`` and named variants, ``.npz``,
  ``.mat``; mm/s^2, m/s^2 or g; clipping and unit checks; irregular sampling resampled and reported),
  :func:`accel_log`, :func:`save_accel_log`.
- Modes: :func:`estimate_modes` (PSD per axis, significant peaks, leakage-aware resonance fit with
  standard errors and flags).
- Delays: :func:`tune_delays` (eq 10), :func:`residual_ratio`, :func:`robustness_table`,
  :func:`robustness_margin`.
- Synthetic logs with known modes: :func:`synthetic_accel_log` (sine sweep or tone series, noise at
  a stated SNR, seeded).
"""

from research.vibration._accel_log import (
    ACCEL_UNITS,
    LAYOUTS,
    AccelLog,
    accel_log,
    load_accel_log,
    save_accel_log,
)
from research.vibration._modes_psd import (
    AxisSpectrum,
    Mode,
    ModeSurvey,
    bin_correlation,
    estimate_modes,
    transmissibility_sq,
    welch_dof,
)
from research.vibration._synthetic import TrueMode, sine_sweep, synthetic_accel_log, tip_acceleration, tone_series
from research.vibration._tuning import (
    FREQUENCY_ERRORS,
    MARGIN_TOLERANCE,
    TunedDelays,
    format_robustness,
    residual_ratio,
    robustness_margin,
    robustness_table,
    tune_delays,
)

__all__ = [
    "ACCEL_UNITS",
    "AccelLog",
    "AxisSpectrum",
    "FREQUENCY_ERRORS",
    "MARGIN_TOLERANCE",
    "LAYOUTS",
    "Mode",
    "ModeSurvey",
    "TrueMode",
    "TunedDelays",
    "accel_log",
    "bin_correlation",
    "estimate_modes",
    "format_robustness",
    "load_accel_log",
    "residual_ratio",
    "robustness_margin",
    "robustness_table",
    "save_accel_log",
    "sine_sweep",
    "synthetic_accel_log",
    "tip_acceleration",
    "tone_series",
    "transmissibility_sq",
    "tune_delays",
    "welch_dof",
]
