"""The B-spline path kind of ``[path]`` ([path.bspline]) and Prévost's e1 / e2 / eT stage helpers."""

import numpy as np
import pytest

from research.errors import ConfigError
from research.experiments.config import build_path, named_axes, validate
from research.experiments.stage_execution_errors import abscissa, axis_reversals
from research.paths.bspline import BSplinePath, prevost2012_bspline

FIG4 = {"control_points_mm": [[-100.0, 0.0], [-50.0, 0.0], [-50.0, 50.0], [0.0, 50.0], [50.0, 0.0], [50.0, -50.0],
                              [-100.0, -50.0]],
        "knots": [0, 0, 0, 0, 1 / 3, 0.5, 2 / 3, 1, 1, 1, 1]}


def _cfg(bspline, **path):
    return validate({"name": "t", "reproduces": "-", "path": {"bspline": bspline} | path}, "t.toml")


def test_bspline_path_is_the_paper_curve_and_its_polyline_holds_the_chord_error():
    cfg = _cfg(FIG4 | {"chord_error_um": 1.0})
    curve = cfg.path.bspline.curve()
    ref = prevost2012_bspline()
    u = np.linspace(0, 1, 101)
    assert np.allclose(curve(u), ref(u), atol=1e-12)
    poly, feeds = build_path(cfg.path, ".")
    assert feeds is None and named_axes(cfg) == ("x", "y")
    mid = 0.5 * (poly.points[:-1] + poly.points[1:])  # the sagitta is largest at a chord's middle
    assert np.max(curve.distance(mid)) <= 1e-3
    assert np.max(curve.distance(poly.points)) < 1e-9


@pytest.mark.parametrize("bad, match", [
    (FIG4 | {"knots": FIG4["knots"][:-1]}, r"path\.bspline.*knots needs n \+ p \+ 1 = 11"),
    (FIG4 | {"knots": [0, 0, 0, 0, 0.5, 1 / 3, 2 / 3, 1, 1, 1, 1]}, r"non-decreasing"),
    (FIG4 | {"control_points_mm": [[0.0, 0.0], [1.0, 0.0, 2.0]] + FIG4["control_points_mm"][2:]}, r"same number of coordinates"),
    (FIG4 | {"degree": 0}, r"path\.bspline\.degree"),
    (FIG4 | {"chord_error_um": 0.0}, r"chord_error_um"),
    (FIG4 | {"weights": [1.0]}, r"unknown key"),
])
def test_a_bad_bspline_is_refused_naming_the_key(bad, match):
    with pytest.raises(ConfigError, match=match):
        _cfg(bad)


def test_one_path_kind_only():
    with pytest.raises(ConfigError, match=r"exactly one of name, gcode, points_mm, bspline"):
        _cfg(FIG4, name="corner90")


def test_axis_reversals_of_a_parabola_arc_against_its_closed_form():
    """The quadratic Bezier (0,0), (1,2), (2,0): C(u) = (2u, 4u(1-u)); y' = 4 - 8u vanishes at u = 1/2, the apex,
    at arc length L/2 by symmetry; x never reverses. L = int_0^1 sqrt(4 + (4 - 8u)^2) du (closed form below)."""
    c = BSplinePath(np.array([[0.0, 0.0], [1.0, 2.0], [2.0, 0.0]]), np.array([0, 0, 0, 1, 1, 1.0]), 2)
    L = np.sqrt(5) + np.arcsinh(2) / 2  # w = 1 - 2u: L = int_{-1}^{1} sqrt(1 + 4 w^2) dw
    assert c.length == pytest.approx(L, rel=1e-12)
    found = axis_reversals(c)
    assert found["x"] == [] and found["y"] == [pytest.approx(L / 2, abs=1e-9)]


def test_abscissa_on_a_polyline_and_on_a_bspline():
    from research.paths import Polyline

    p = Polyline([[0.0, 0.0], [10.0, 0.0], [10.0, 5.0]])
    s = abscissa(p, np.array([[3.0, 0.2], [10.3, 2.0]]))
    assert s == pytest.approx([3.0, 12.0])
    c = prevost2012_bspline()
    u = np.array([0.1, 0.45, 0.9])
    assert abscissa(c, c(u)) == pytest.approx(c.arc_length(u), abs=1e-9)
