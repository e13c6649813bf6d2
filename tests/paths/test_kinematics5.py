"""A/C table-tilting 5-axis kinematics (thesis eq 3.18, 3.21, 4.2-4.6, 4.8-4.10) and the eq 4.36 path."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import research  # noqa: F401  (x64)
from research.errors import ParameterError, PathError
from research.paths.kinematics5 import (
    TableTiltingAC,
    five_axis_path,
    orientation_jacobian,
    rotary_angles,
    sencer2009_eq436,
    tool_orientation,
)

MACHINE = TableTiltingAC(L_ya=120.0, L_ac=-35.0, L_t=80.0)


def _random_q(n, seed=0):
    rng = np.random.default_rng(seed)
    return np.column_stack([rng.uniform(-100, 100, (n, 3)), rng.uniform(0.05, np.pi - 0.05, n),
                            rng.uniform(-np.pi + 0.01, np.pi - 0.01, n)])


def test_round_trip_axis_to_pose_to_axis():
    q = _random_q(500)
    P, O = MACHINE.forward(q)
    np.testing.assert_allclose(MACHINE.inverse(P, O), q, rtol=0, atol=1e-9)


def test_round_trip_pose_to_axis_to_pose():
    rng = np.random.default_rng(1)
    P = rng.uniform(-50, 50, (300, 3))
    O = rng.normal(size=(300, 3))
    O /= np.linalg.norm(O, axis=1, keepdims=True)
    P2, O2 = MACHINE.forward(MACHINE.inverse(P, O))
    np.testing.assert_allclose(P2, P, atol=1e-9)
    np.testing.assert_allclose(O2, O, atol=1e-12)


def test_orientation_eq_3_18_and_3_21():
    a, c = 0.3, 1.1
    np.testing.assert_allclose(tool_orientation(a, c), [np.sin(c) * np.sin(a), -np.cos(c) * np.sin(a), np.cos(a)])
    np.testing.assert_allclose(rotary_angles(tool_orientation(a, c)), (a, c), atol=1e-14)
    # vertical tool at a = c = 0; the home pose maps P to x = -Px, y = -Py (table moves against the tool)
    P, O = MACHINE.forward(jnp.array([1.0, 2.0, 3.0, 0.0, 0.0]))
    np.testing.assert_allclose(O, [0, 0, 1], atol=1e-15)
    np.testing.assert_allclose(P, [-1.0, -2.0, 3.0 - (-35.0 + 120.0 - 80.0)], atol=1e-12)


def test_tool_axis_moves_tip_along_orientation():
    """Moving the Z axis moves the tip along the tool axis O (eq 4.5 vs eq 4.2)."""
    q = _random_q(20, seed=3)
    Jt = MACHINE.tip_jacobian(q)
    _, O = MACHINE.forward(q)
    np.testing.assert_allclose(Jt[:, :, 2], O, atol=1e-14)


def test_jacobian_eq_4_8_4_9_matches_autodiff():
    q = _random_q(10, seed=2)
    auto = jax.vmap(jax.jacfwd(lambda qq: MACHINE.forward(qq)[0]))(jnp.asarray(q))
    np.testing.assert_allclose(MACHINE.tip_jacobian(q), auto, atol=1e-10)
    J = MACHINE.jacobian(q)
    assert J.shape == (10, 5, 5)
    np.testing.assert_array_equal(J[:, 3:], np.broadcast_to([[0, 0, 0, 1, 0], [0, 0, 0, 0, 1]], (10, 2, 5)))
    Jo = jax.vmap(jax.jacfwd(lambda ac: tool_orientation(ac[0], ac[1])))(jnp.asarray(q[:, 3:]))
    np.testing.assert_allclose(orientation_jacobian(q[:, 3], q[:, 4]), Jo, atol=1e-14)


def test_jacobian_maps_axis_velocity_to_pose_velocity_eq_4_10():
    q0, qd = _random_q(1, seed=5)[0], np.array([3.0, -2.0, 1.0, 0.4, -0.7])
    h = 1e-6
    Pp, _ = MACHINE.forward(q0 + h * qd)
    Pm, _ = MACHINE.forward(q0 - h * qd)
    np.testing.assert_allclose(MACHINE.jacobian(q0)[:3] @ qd, (Pp - Pm) / (2 * h), rtol=1e-7)


def test_eq_4_36_test_path():
    path = sencer2009_eq436(20001)
    assert path.tip_length() == pytest.approx(273.87, abs=0.01)  # thesis §4.5: "about 273.87 [mm]"
    np.testing.assert_allclose(path.tip[0], [15.0, -5.0, 0.0], atol=1e-12)
    np.testing.assert_allclose(np.cos(path.a), np.sin(path.l) / 5, atol=1e-14)
    q = path.axis_positions(MACHINE)
    P, O = MACHINE.forward(q)
    np.testing.assert_allclose(P, path.tip, atol=1e-9)
    np.testing.assert_allclose(O, path.orientation, atol=1e-14)
    # the A axis reverses four times (thesis §4.5 / Fig 4.7a)
    assert np.sum(np.diff(np.sign(np.diff(np.asarray(path.a)))) != 0) == 4
    assert five_axis_path("sencer2009_eq436", n_samples=11).tip.shape == (11, 3)


def test_bad_input():
    with pytest.raises(PathError, match="unknown 5-axis path"):
        five_axis_path("spiral")
    with pytest.raises(PathError, match="n_samples"):
        sencer2009_eq436(1)
    with pytest.raises(ParameterError, match="TableTiltingAC.L_ac"):
        TableTiltingAC(L_ac=float("nan"))
