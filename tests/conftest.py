"""Shared fixtures. Matplotlib draws off-screen, and its global style is restored after each test."""

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
import pytest  # noqa: E402

import research  # noqa: E402,F401  (sets jax_enable_x64)


@pytest.fixture(autouse=True)
def _restore_matplotlib():
    """Figures a test opens are closed and rcParams restored, whatever the test changed."""
    with matplotlib.rc_context():
        yield
    plt.close("all")
