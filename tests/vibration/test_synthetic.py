"""Synthetic resonance logs: seeded, stated SNR, the mode model's resonance."""

import numpy as np
import pytest

from research.errors import ParameterError
from research.vibration import TrueMode, synthetic_accel_log, tip_acceleration, transmissibility_sq


def test_seeded_and_snr_as_stated():
    kw = dict(rate=800.0, duration=5.0, f1=30.0, gravity=False)
    a = synthetic_accel_log([TrueMode("x", 11.4, 0.02)], snr_db=20.0, seed=3, **kw)
    b = synthetic_accel_log([TrueMode("x", 11.4, 0.02)], snr_db=20.0, seed=3, **kw)
    clean = synthetic_accel_log([TrueMode("x", 11.4, 0.02)], snr_db=None, **kw)
    np.testing.assert_array_equal(a.accel, b.accel)
    noise = a.accel - clean.accel
    snr = 10 * np.log10(np.mean(clean.accel[:, 0] ** 2) / np.var(noise))
    assert snr == pytest.approx(20.0, abs=0.1)


def test_tone_response_follows_the_transmissibility():
    """Independent check of the simulated tool head: the steady amplitude under a pure tone is |T(f)| of the
    base-excited mode (closed form in the estimator's module)."""
    rate, f, fn, z = 2000.0, 9.0, 11.4, 0.05
    t = np.arange(int(8.0 * rate)) / rate
    y = tip_acceleration(t, np.sin(2 * np.pi * f * t), [TrueMode("x", fn, z)])
    tail = t > 4.0  # transients gone (time constant 1 / (zeta wn) = 0.28 s)
    amp = np.sqrt(2 * np.mean(y[tail] ** 2))
    assert amp == pytest.approx(np.sqrt(transmissibility_sq(f, fn, z)), rel=2e-3)


def test_bad_synthesis_input():
    with pytest.raises(ParameterError):
        synthetic_accel_log([TrueMode("x", 11.4, 0.02)], f1=500.0, rate=800.0)
    with pytest.raises(ParameterError):
        synthetic_accel_log([TrueMode("w", 11.4, 0.02)])
    with pytest.raises(ParameterError):
        synthetic_accel_log([TrueMode("x", 11.4, 0.02)], excitation="noise")
