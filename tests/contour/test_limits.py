"""Limit check of a setpoint (Prévost §3: "must be checked")."""

import numpy as np
import pytest

from research.contour import check_setpoint
from research.errors import ParameterError
from research.limits import AxisLimits
from research.trajectory import Trajectory


def _setpoint():
    t = np.arange(101) * 1e-3
    q = np.column_stack([50 * t**2, np.zeros_like(t)])  # a = 100 mm/s^2 on x
    return Trajectory.from_positions(t, q, axes=("x", "y"))


def test_ratios_and_violations():
    chk = check_setpoint(_setpoint(), None, AxisLimits.uniform(2, 20.0, 50.0, 1e6))
    np.testing.assert_allclose(chk.ratios["acceleration"][0], 2.0, rtol=1e-9)
    assert not chk.ok and any(v.startswith("acceleration on x") for v in chk.violations)
    assert check_setpoint(_setpoint(), None, AxisLimits.uniform(2, 20.0, 150.0, 1e6)).ok


def test_bad_limits():
    with pytest.raises(ParameterError, match="limits are for 3 axes"):
        check_setpoint(_setpoint(), None, AxisLimits.uniform(3, 1.0, 1.0))
    with pytest.raises(ParameterError, match="control_limit must be > 0"):
        check_setpoint(_setpoint(), None, AxisLimits.uniform(2, 1.0, 1.0), control_limit=[1.0, 0.0])
