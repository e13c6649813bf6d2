"""Mode estimation on synthetic logs with known truth (issue 20: target <= 1 % frequency error at 20 dB)."""

import numpy as np
import pytest

from research.errors import DriveLogError, ParameterError
from research.vibration import (
    TrueMode,
    accel_log,
    bin_correlation,
    estimate_modes,
    synthetic_accel_log,
    welch_dof,
)
from tests.vibration.conftest import PAPER_MODES


@pytest.mark.parametrize("which", ["sweep_log", "tone_log"])
def test_recovers_the_paper_modes_at_20_db(which, request):
    """Issue 20 target: frequency error <= 1 % at SNR 20 dB. Truth: Sencer 2015 §4, 11.4 Hz (X), 6.8 Hz (Y).
    Damping is a model prediction (the paper prints none): checked within 10 % of the synthetic truth."""
    survey = estimate_modes(request.getfixturevalue(which))
    found = survey.dominant()
    for true in PAPER_MODES:
        m = found[true.axis]
        assert abs(m.frequency_hz / true.frequency_hz - 1) <= 0.01
        assert abs(m.damping / true.damping - 1) <= 0.10
        assert m.frequency_sd_hz > 0 and np.isfinite(m.damping_sd)
        assert m.flags == ()
    assert "z" not in found  # z is not excited: only noise and gravity


def test_frequency_error_within_its_standard_error():
    """The reported uncertainty is honest: over seeds at 10 dB the error of the X mode stays within 4 standard
    errors (a property; 4 sigma leaves room for the correlated bins)."""
    for seed in range(3):
        log = synthetic_accel_log([TrueMode("x", 30.0, 0.05)], direction=(1, 0, 0), f0=5, f1=60, rate=800.0,
                                  snr_db=10.0, seed=seed)
        m = estimate_modes(log).dominant()["x"]
        assert abs(m.frequency_hz - 30.0) <= 4 * m.frequency_sd_hz + 1e-3


def test_welch_hann_option_recovers_a_broad_mode():
    """The Welch (Hann) estimator with its leakage kernel on a mode wider than its bins."""
    log = synthetic_accel_log([TrueMode("x", 30.0, 0.05)], direction=(1, 0, 0), f0=5, f1=60, rate=800.0,
                              snr_db=20.0, seed=4)
    m = estimate_modes(log, window="hann", resolution_hz=0.5).dominant()["x"]
    assert abs(m.frequency_hz / 30.0 - 1) <= 0.01


def test_two_modes_closer_than_the_resolution_are_flagged():
    """Issue 20 bad input: two lightly damped modes 0.2 Hz apart (half-power bands 0.11 Hz, so a dip separates
    them) are reported flagged, under a 0.4 Hz Welch resolution and under the default whole-record spectrum."""
    log = synthetic_accel_log([TrueMode("x", 11.4, 0.005, 0.5), TrueMode("x", 11.6, 0.005, 0.5)], f1=60.0,
                              rate=800.0, snr_db=40.0, seed=1)
    for kw in ({"window": "hann", "resolution_hz": 0.4}, {}):
        modes = estimate_modes(log, **kw).spectra["x"].modes
        near = [m for m in modes if 11.0 < m.frequency_hz < 12.0]
        assert near and all("unresolved" in m.flags for m in near), kw


def test_no_motion_is_refused():
    """A log at rest (gravity and sensor noise only) has no significant peak: a DriveLogError saying so."""
    rng = np.random.default_rng(0)
    t = np.arange(8000) / 800.0
    a = rng.normal(0, 20.0, (t.size, 3)) + [0.0, 0.0, 9806.65]
    with pytest.raises(DriveLogError, match="no motion"):
        estimate_modes(accel_log(t, a, source="rest.csv"))


def test_mode_outside_the_band_is_refused_with_the_reason():
    """Only an 11.4 Hz mode, band searched up to 10.5 Hz: the PSD rises toward the upper edge (|T|^2 = 43 there,
    above the edge test's noise quantile ~10 for a 2-dof bin); the error says so."""
    log = synthetic_accel_log([TrueMode("x", 11.4, 0.02)], direction=(1, 0, 0), f1=20.0, rate=800.0, snr_db=30.0)
    with pytest.raises(DriveLogError, match="outside the measured band"):
        estimate_modes(log, band_hz=(2.0, 10.5))


def test_mode_near_the_band_edge_is_flagged():
    log = synthetic_accel_log([TrueMode("x", 11.4, 0.02)], direction=(1, 0, 0), f1=20.0, rate=800.0, snr_db=30.0)
    m = estimate_modes(log, band_hz=(2.0, 11.8)).dominant()["x"]
    assert "band_edge" in m.flags


def test_band_above_nyquist_is_a_parameter_error(sweep_log):
    with pytest.raises(ParameterError, match="Nyquist"):
        estimate_modes(sweep_log, band_hz=(1.0, 500.0))
    with pytest.raises(ParameterError, match="resolution"):
        estimate_modes(sweep_log, resolution_hz=1e-3)
    with pytest.raises(ParameterError, match="window"):
        estimate_modes(sweep_log, window="flattop")


def test_bin_correlation_and_dof_from_the_window():
    """Independent values: the periodic Hann window's DFT is [-1/4, 1/2, -1/4], so neighbouring periodogram
    bins correlate by (1/4 / (3/8))^2 = 4/9 and two apart by (1/16 / (3/8))^2 = 1/36; a boxcar's not at all.
    Non-overlapped boxcar segments give exactly 2 K degrees of freedom."""
    from scipy import signal

    assert bin_correlation(signal.get_window("hann", 256)) == pytest.approx(1 + 2 * (4 / 9 + 1 / 36), rel=1e-12)
    assert bin_correlation(np.ones(256)) == pytest.approx(1.0, abs=1e-12)
    assert welch_dof(np.ones(256), 256, 7) == pytest.approx(14.0)


def test_constant_column_is_skipped_not_an_error(sweep_log):
    """A column with no signal at all (exactly constant) yields no modes on it; the others are still analysed."""
    a = sweep_log.accel.copy()
    a[:, 2] = 9806.65
    survey = estimate_modes(accel_log(sweep_log.t, a, source="flat-z.csv"))
    assert survey.spectra["z"].modes == () and set(survey.dominant()) == {"x", "y"}


def test_recovers_modes_under_a_klipper_per_hz_sweep():
    """Klipper's resonance test raises the amplitude with frequency (accel_per_hz = 75 mm/s^2/Hz), a sloped
    excitation under the peak; the fitted power-law slope keeps the error within the 1 % target at 20 dB
    (printer-like modes, damping 5 % and 8 %)."""
    truth = (TrueMode("x", 42.0, 0.05), TrueMode("y", 33.0, 0.08))
    log = synthetic_accel_log(list(truth), f1=80.0, rate=800.0, snr_db=20.0, seed=5, per_hz=True, amplitude=75.0)
    found = estimate_modes(log).dominant()
    for m in truth:
        assert abs(found[m.axis].frequency_hz / m.frequency_hz - 1) <= 0.01
        assert abs(found[m.axis].damping / m.damping - 1) <= 0.10
