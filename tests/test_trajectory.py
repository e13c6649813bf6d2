"""Trajectory: validation, exact evaluation, resampling, storage."""

import numpy as np
import pytest

from research.errors import ParameterError
from research.interpolators import fir_interpolate
from research.paths import named_path
from research.trajectory import Trajectory


@pytest.fixture(scope="module")
def fir_traj():
    return fir_interpolate(named_path("corner90"), 200.0, [0.05, 0.03], 0.1, sample_period=2e-3)


def test_from_positions_finite_differences():
    t = np.arange(200) * 1e-3
    q = np.column_stack([np.sin(3 * t), t**2])
    tr = Trajectory.from_positions(t, q, axes=("x", "y"))
    np.testing.assert_allclose(tr.v[1:-1, 1], 2 * t[1:-1], atol=1e-9)
    assert tr.exact is None and tr.duration == pytest.approx(0.199)


@pytest.mark.parametrize(
    "t, q, match",
    [
        (np.array([0.0, 1e-3, 1e-3]), np.zeros((3, 1)), "strictly increasing"),
        (np.array([0.0, 1e-3, 3e-3]), np.zeros((3, 1)), "uniformly sampled"),
        (np.arange(3) * 1e-3, np.array([[0.0], [np.nan], [1.0]]), "not finite at sample 1"),
    ],
)
def test_bad_samples_rejected(t, q, match):
    with pytest.raises(ParameterError, match=match):
        Trajectory.from_positions(t, q, axes=("x",))


def test_shape_mismatch_rejected():
    z = np.zeros((4, 2))
    with pytest.raises(ParameterError, match="expected \\(N, A\\)"):
        Trajectory(np.arange(4.0), z, z, z, np.zeros((4, 3)), np.float64(3.0), None, ("x", "y"), 1.0)


def test_exact_evaluation_between_samples(fir_traj):
    t = np.array([0.0101, 0.25, 0.3337])
    # derivatives of the exact profile agree with a finite difference of its positions
    h = 1e-6
    fd = (fir_traj.evaluate(t + h) - fir_traj.evaluate(t - h)) / (2 * h)
    np.testing.assert_allclose(fir_traj.evaluate(t, 1), fd, atol=1e-5)


def test_resample_uses_exact_profile(fir_traj):
    fine = fir_traj.resample(1e-4)
    assert fine.sample_period == 1e-4 and fine.duration == fir_traj.duration
    np.testing.assert_allclose(fine.q[::20], fir_traj.q[: len(fine.q[::20])], atol=1e-12)


def test_resample_without_exact_profile_is_hermite(fir_traj):
    sampled = Trajectory(fir_traj.t, fir_traj.q, fir_traj.v, fir_traj.a, fir_traj.j, fir_traj.duration, None, fir_traj.axes, fir_traj.sample_period)
    fine = sampled.resample(5e-4)
    exact = fir_traj.evaluate(fine.t)
    assert np.max(np.abs(fine.q - exact)) < 1e-4  # cubic Hermite, O(Ts^4)


def test_save_load_roundtrip(tmp_path, fir_traj):
    fir_traj.save(tmp_path / "tr.npz")
    back = Trajectory.load(tmp_path / "tr.npz")
    assert back.axes == fir_traj.axes and back.sample_period == fir_traj.sample_period
    np.testing.assert_array_equal(back.q, fir_traj.q)
    np.testing.assert_allclose(back.evaluate(np.array([0.123])), fir_traj.evaluate(np.array([0.123])))


def test_axis_lookup(fir_traj):
    assert fir_traj.axis("y") == 1
    with pytest.raises(ParameterError, match="no axis 'z'"):
        fir_traj.axis("z")
