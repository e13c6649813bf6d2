"""Exact contour error, tracking error, the e1/e2/eT decomposition and bad input."""

import numpy as np
import pytest

from research.contour import (
    brute_force_contour_error,
    check_same_grid,
    contour_error,
    execution_errors,
    tracking_error,
    trajectory_polyline,
)
from research.errors import ParameterError
from research.interpolators import fir_interpolate
from research.paths import Polyline, named_path
from research.paths.bspline import prevost2012_bspline
from research.trajectory import Trajectory


def test_matches_brute_force_on_long_random_path():
    rng = np.random.default_rng(0)
    path = Polyline(np.cumsum(rng.normal(0, 1, (2001, 2)), axis=0))
    pts = path.points[rng.integers(0, 2000, 5000)] + rng.normal(0, 2, (5000, 2))
    np.testing.assert_allclose(contour_error(path, pts).distance, brute_force_contour_error(path, pts), atol=1e-12)


def test_signed_error_left_positive_and_vector():
    path = Polyline([[0.0, 0.0], [10.0, 0.0]])
    c = contour_error(path, np.array([[5.0, 0.1], [5.0, -0.2], [12.0, 0.0]]))
    np.testing.assert_allclose(c.signed, [0.1, -0.2, 2.0])
    np.testing.assert_allclose(c.vector, [[0, 0.1], [0, -0.2], [2, 0]])


def test_bspline_reference_and_sampled_curve_agree():
    c = prevost2012_bspline()
    q = c(np.linspace(0, 1, 200)) + np.random.default_rng(2).normal(0, 0.05, (200, 2))
    exact = contour_error(c, q).distance
    # a densely sampled curve (chord error 1e-6 mm) as (M, d) points gives the same to 1e-6 mm
    dense = contour_error(c.to_polyline(1e-6).points, q).distance
    np.testing.assert_allclose(dense, exact, atol=1.1e-6)


def test_trajectory_as_reference_curve():
    tr = fir_interpolate(named_path("corner90"), 100.0, [0.02, 0.01], 0.05, 1e-3)
    # every setpoint sample lies on the curve the setpoint traces
    assert contour_error(tr, tr).max < 1e-9
    poly = trajectory_polyline(tr)
    assert poly.dim == 2 and poly.length == pytest.approx(100.0 - 0.0, abs=0.2)


def test_tracking_error_and_grid_checks():
    t = np.arange(5) * 1e-3
    R = Trajectory.from_positions(t, np.column_stack([t, 2 * t]), axes=("x", "y"))
    te = tracking_error(R, (t, np.column_stack([t - 1e-3, 2 * t])))
    np.testing.assert_allclose(te.norm, 1e-3)
    with pytest.raises(ParameterError, match="different lengths: 5 reference samples, 4 actual"):
        check_same_grid(R, (t[:4], np.zeros((4, 2))))
    with pytest.raises(ParameterError, match="different time grids: sample 0"):
        check_same_grid(R, (t + 0.5e-3, np.zeros((5, 2))))
    with pytest.raises(ParameterError, match="2 axes but actual has 1"):
        check_same_grid(R, (t, np.zeros((5, 1))))


def test_non_finite_actual_is_refused():
    with pytest.raises(ParameterError, match="non-finite position at sample 1"):
        contour_error(named_path("corner90"), np.array([[0.0, 0.0], [np.nan, 0.0]]))


def test_decomposition_on_a_known_offset():
    path = Polyline([[0.0, 0.0], [100.0, 0.0]])
    t = np.arange(11) * 1e-3
    q = np.column_stack([10 * np.arange(11.0), np.full(11, 0.003)])
    sp = Trajectory.from_positions(t, q, axes=("x", "y"))
    ex = execution_errors(path, sp, (t, q + [0.0, 0.002]))
    np.testing.assert_allclose(ex.e1, 0.003, atol=1e-12)
    np.testing.assert_allclose(ex.e2, 0.002, atol=1e-9)
    np.testing.assert_allclose(ex.eT, 0.005, atol=1e-12)
