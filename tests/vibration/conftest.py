"""Shared synthetic resonance logs (built once per session; 800 Hz keeps them fast)."""

import pytest

from research.vibration import TrueMode, synthetic_accel_log

#: the beams of Sencer 2015 §4: "first bending modes are at w_n,X = 11.4 [Hz] and w_n,Y = 6.8 [Hz]";
#: the paper gives no damping, 2 % as in the config default
PAPER_MODES = (TrueMode("x", 11.4, 0.02), TrueMode("y", 6.8, 0.02))


@pytest.fixture(scope="session")
def sweep_log():
    return synthetic_accel_log(list(PAPER_MODES), excitation="sweep", rate=800.0, snr_db=20.0, seed=1)


@pytest.fixture(scope="session")
def tone_log():
    return synthetic_accel_log(list(PAPER_MODES), excitation="tones", rate=800.0, snr_db=20.0, seed=2)
