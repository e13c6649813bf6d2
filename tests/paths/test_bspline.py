"""B-spline tool paths: Prévost's example, derivatives, arc length, projection, bad input."""

import numpy as np
import pytest

from research.errors import PathError
from research.paths.bspline import BSplinePath, prevost2012_bspline


def test_prevost_example_endpoints_and_definition():
    c = prevost2012_bspline()
    assert c.degree == 3 and c.knots.tolist() == [0, 0, 0, 0, 1 / 3, 1 / 2, 2 / 3, 1, 1, 1, 1]
    # clamped cubic: interpolates the first and last control points (Prévost Fig 4)
    np.testing.assert_allclose(c(0.0)[0], [-100, 0], atol=1e-12)
    np.testing.assert_allclose(c(1.0)[0], [-100, -50], atol=1e-12)
    # end tangent along P1 - P0 with the clamped-spline factor p / (u_{p+1} - u_p) = 3 / (1/3)
    np.testing.assert_allclose(c(0.0, 1)[0], 9 * np.array([50.0, 0.0]), rtol=1e-12)


def test_derivatives_match_finite_differences():
    c = prevost2012_bspline()
    u = np.linspace(0.05, 0.95, 13)
    h = 1e-6
    np.testing.assert_allclose(c(u, 1), (c(u + h) - c(u - h)) / (2 * h), rtol=1e-6, atol=1e-5)
    np.testing.assert_allclose(c(u, 2), (c(u + h, 1) - c(u - h, 1)) / (2 * h), rtol=1e-5, atol=1e-3)


def test_arc_length_against_dense_chords_and_inverse():
    c = prevost2012_bspline()
    u = np.linspace(0, 1, 400001)
    chords = np.sum(np.linalg.norm(np.diff(c(u), axis=0), axis=1))
    assert abs(c.length - chords) < 1e-6  # chord sum converges from below as h^2
    # independent quadrature of the speed |C'(u)| over the knot spans (scipy.integrate.quad)
    from scipy.integrate import quad

    spans = [0.0, 1 / 3, 1 / 2, 2 / 3, 1.0]
    L = sum(quad(lambda x: float(np.linalg.norm(c(np.array([x]), 1))), a, b, epsabs=1e-12)[0] for a, b in zip(spans, spans[1:]))
    assert c.length == pytest.approx(L, abs=1e-8)
    s = np.linspace(0, c.length, 17)
    np.testing.assert_allclose(c.arc_length(c.parameter_at(s)), s, atol=1e-9)


def test_straight_spline_arc_length_is_exact():
    line = BSplinePath(np.array([[0.0, 0.0], [1.0, 2.0], [2.0, 4.0], [3.0, 6.0]]), np.array([0, 0, 0, 0, 1, 1, 1, 1.0]))
    assert line.length == pytest.approx(3 * np.sqrt(5), rel=1e-13)


def test_project_matches_dense_search():
    c = prevost2012_bspline()
    q = c(np.linspace(0, 1, 300)) + np.random.default_rng(1).normal(0, 0.3, (300, 2))
    d, u, foot = c.project(q)
    dense = c(np.linspace(0, 1, 2_000_001))
    from scipy.spatial import cKDTree
    brute, _ = cKDTree(dense).query(q)
    # the nearest of 2e6 curve points (spacing <= 4e-4 mm) is never closer than the exact foot, and
    # overestimates by at most (h/2)^2 / (2 d) ~ 1e-6 mm for these distances
    assert np.all(d <= brute + 1e-12)
    assert np.max(brute - d) < 1e-6
    np.testing.assert_allclose(np.linalg.norm(q - foot, axis=1), d)


def test_to_polyline_chord_error_bound():
    c = prevost2012_bspline()
    poly = c.to_polyline(1e-3)
    mid = 0.5 * (poly.points[1:] + poly.points[:-1])
    assert c.distance(mid).max() <= 1e-3


@pytest.mark.parametrize(
    "kwargs, match",
    [
        (dict(control_points=np.zeros((3, 2)), knots=np.zeros(7), degree=3), "n >= degree"),
        (dict(control_points=np.zeros((4, 2)), knots=np.zeros(7), degree=3), "knots needs"),
        (dict(control_points=np.zeros((4, 2)), knots=[0, 0, 0, 1, 0.5, 1, 1, 1], degree=3), "non-decreasing"),
        (dict(control_points=[[0, 0], [1, np.nan], [2, 0], [3, 0]], knots=[0, 0, 0, 0, 1, 1, 1, 1], degree=3), "NaN"),
        (dict(control_points=np.zeros((4, 2)), knots=np.zeros(8), degree=3), "empty parameter domain"),
    ],
)
def test_bad_input(kwargs, match):
    with pytest.raises(PathError, match=match):
        BSplinePath(**kwargs)


def test_bad_chord_error():
    with pytest.raises(PathError, match="chord_error"):
        prevost2012_bspline().to_polyline(0.0)
