"""Thesis §4.3-4.5: Frenet-frame contour error estimators and the orientation contour error."""

import numpy as np
import pytest

from research.contour import (
    five_axis_contour_study,
    frenet_contour_estimates,
    frenet_frame,
    orientation_contour_error,
)
from research.errors import ParameterError


def _circle(R=20.0, w=5.0):
    def ref(t):
        t = np.atleast_1d(t)
        c, s = np.cos(w * t), np.sin(w * t)
        z = np.zeros_like(t)
        return (np.column_stack([R * c, R * s, z]), np.column_stack([-R * w * s, R * w * c, z]),
                np.column_stack([-R * w * w * c, -R * w * w * s, z]))
    return ref


def test_estimators_on_a_lagging_circle():
    # actual = reference delayed by 5 ms and pushed 10 um outward: exact contour error 10 um.
    R, w, lag, off = 20.0, 5.0, 0.005, 0.01
    ref = _circle(R, w)
    t = np.linspace(0.1, 1.0, 50)
    P = ref(t - lag)[0] * (R + off) / R
    est = frenet_contour_estimates(ref, t, P)
    np.testing.assert_allclose(est.delay, lag, rtol=1e-3)  # eq 4.21: t_d = e_t / |P'|
    np.testing.assert_allclose(est.compensated, off, atol=1e-9)  # eq 4.27 exact on a circle
    # basic (too small) and shifted (too large) both miss by the sagitta of the 0.5 mm lag,
    # R (1 - cos(w lag)) = 6.25 um: the offset h of eq 4.23 "must be compensated"
    sagitta = R * (1 - np.cos(w * lag))
    np.testing.assert_allclose(off - est.basic, sagitta, atol=1e-5)  # + off (1 - cos) terms
    np.testing.assert_allclose(est.shifted - off, sagitta, atol=1e-5)  # t_d = lag to 1e-3 (eq 4.21)


def test_frenet_frame_orthonormal_and_straight_line_fallback():
    t, n, b = frenet_frame(np.array([[1.0, 0, 0], [0, 2.0, 0]]), np.array([[0.0, 3, 0], [0, 5.0, 0]]))
    np.testing.assert_allclose(np.sum(t * n, 1), 0, atol=1e-15)
    np.testing.assert_allclose(np.linalg.norm(b, axis=1), 1)


@pytest.fixture(scope="module")
def study():
    return five_axis_contour_study()


def test_fig_4_6_ordering(study):
    moving = np.linalg.norm(study.reference.v[:, :3], axis=1) > 0.01 * 50.0
    mean = {k: float(study.discrepancy(k)[moving].mean()) for k in ("basic", "shifted", "compensated")}
    # thesis §4.5: average discrepancy 0.01-0.05 um; ours 0.029 um for basic and shifted
    assert 0.01e-3 < mean["basic"] < 0.05e-3
    # compensated Frenet closest to the exact error (thesis Fig 4.6b): 0.0002 um here, 1% of basic
    assert mean["compensated"] < 0.02 * mean["basic"]
    # thesis text: "the delayed Frenet Frame shows the worst performance": shifted >= basic, but by
    # 0.1 % only: a tie, so this confirms the thesis' ordering weakly (README: a tie)
    assert mean["basic"] <= mean["shifted"]
    # contour errors of ~140 um at the A-axis reversals (thesis Fig 4.6a: ~300 um with its SMC drives)
    assert 0.1 < study.exact.max() < 0.2


def test_orientation_contour_error(study):
    moving = np.linalg.norm(study.reference.v[:, 3:], axis=1) > 0.05
    est = np.linalg.norm(study.orientation.workpiece, axis=1)[moving]
    exact = study.orientation_exact[moving]
    # eq 4.34/4.35 against the nearest reference orientation: within 1 urad (median 0.3 % of the error)
    big = exact > 0.02e-3
    assert np.median(np.abs(est[big] - exact[big]) / exact[big]) < 0.01
    # the contour error removes the tangential part: never larger than the tracking error (eq 4.35)
    assert np.all(np.linalg.norm(study.orientation.rotary, axis=1) <= np.linalg.norm(study.orientation.tracking, axis=1) + 1e-15)


def test_orientation_bad_shapes():
    with pytest.raises(ParameterError, match=r"\(N, 5\)"):
        orientation_contour_error(np.zeros((3, 5)), np.zeros((3, 4)), np.zeros((3, 5)))
