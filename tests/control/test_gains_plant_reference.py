"""research.control building blocks: gain tables, the sampled-loop stability check, the plant's
discretization, the eq 4.36 reference and its Frenet frame (Sencer 2009 thesis ch 5)."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest
import scipy.signal

from research.control import (
    AxisSMC,
    TipGains,
    check_axis_gains,
    check_tip_gains,
    direction_inertia,
    eq436_reference,
    parametric_reference,
    plant_step_matrices,
    step_disturbance_peak,
    table_5_2,
    table_5_3,
    thesis_plant,
)
from research.control._gains import _axis_map, closed_loop_eigenvalues
from research.errors import FrenetFrameError, ParameterError, UnstableGainsError
from research.paths.kinematics5 import TableTiltingAC


def test_tables_hold_the_printed_numbers():
    """Table 5.2: "omega_n 200 200 180 150 200, Ks 7 5 5 0.5 1, Gamma 25 30 15 3 3"; Table 5.3: tangent /
    normal / binormal "100 230 230", "2 4 4", "10 20 20", A / C "150 200", "0.5 1", "3 3", "wa, wc 0 0"."""
    g = table_5_2()
    np.testing.assert_array_equal(g.lam, [200, 200, 180, 150, 200])
    np.testing.assert_array_equal(g.Ks, [7, 5, 5, 0.5, 1])
    np.testing.assert_array_equal(g.Gamma, [25, 30, 15, 3, 3])
    c = table_5_3()
    np.testing.assert_array_equal(c.tip.wn, [100, 230, 230])
    np.testing.assert_array_equal(c.tip.Ks, [2, 4, 4])
    np.testing.assert_array_equal(c.tip.Gamma, [10, 20, 20])
    np.testing.assert_array_equal(c.rotary.lam, [150, 200])
    np.testing.assert_array_equal(c.W, [0, 0])
    p = thesis_plant()
    np.testing.assert_array_equal(p.m, [0.00162, 0.00174, 0.00296, 0.00682, 0.00054])  # Table 5.1
    np.testing.assert_array_equal(p.c, [0.00681, 0.00863, 0.01518, 0.01964, 0.00368])


def test_plant_discretization_matches_scipy():
    """Exact ZOH of m q'' + c q' = u (eq 4.11) against scipy.signal.cont2discrete."""
    m, c, T = 0.00682, 0.01964, 1e-3
    Ad, Bd = plant_step_matrices(m, c, T)
    A = np.array([[0, 1], [0, -c / m]])
    B = np.array([[0], [1 / m]])
    Ad_s, Bd_s, *_ = scipy.signal.cont2discrete((A, B, np.eye(2), np.zeros((2, 1))), T, method="zoh")
    np.testing.assert_allclose(np.asarray(Ad), Ad_s, rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(np.asarray(Bd), Bd_s[:, 0], rtol=1e-10)


def test_sampled_eigenvalues_tend_to_continuous_design():
    """For T -> 0, log(z)/T of the sampled SISO loop are the roots of (s + lam)(m s^2 + Ks s + Gamma),
    the continuous error dynamics of eq 5.23-5.28 (c is cancelled by the law's c q' term)."""
    m, c, lam, Ks, G, T = 0.00682, 0.01964, 150.0, 0.5, 3.0, 1e-7
    z = closed_loop_eigenvalues(_axis_map(m, c, lam, Ks, G, T), 3)
    s = np.sort_complex(np.log(z.astype(complex)) / T)
    expected = np.sort_complex(np.roots(np.polymul([1, lam], [m, Ks, G])).astype(complex))
    np.testing.assert_allclose(s, expected, rtol=2e-3)


def test_table_5_2_at_1khz_is_unstable_and_names_the_eigenvalue():
    """With the printed units, X's loop has (lam + Ks/m) T = 4.5 > 2 at T = 1 ms: a double integrator
    with that velocity gain under ZOH has a real eigenvalue below -1 (the reason the study runs at 0.1 ms)."""
    p = thesis_plant()
    with pytest.raises(UnstableGainsError) as info:
        check_axis_gains(table_5_2(), p.m, p.c, 1e-3)
    assert info.value.where == "x"
    assert info.value.eigenvalue.real < -1.0 and abs(info.value.eigenvalue) >= 1.0
    assert "eigenvalue" in str(info.value) and "'x'" in str(info.value)
    check_axis_gains(table_5_2(), p.m, p.c, 1e-4)  # stable at 0.1 ms
    check_tip_gains(table_5_3().tip, direction_inertia(p), 1e-4)


def test_bad_gains_and_axis_counts_raise():
    p = thesis_plant()
    with pytest.raises(ParameterError, match="Ks > 0"):
        check_axis_gains(AxisSMC([200] * 5, [7, 5, -5, 0.5, 1], [25] * 5), p.m, p.c, 1e-4)
    with pytest.raises(ParameterError, match="mismatched axis counts"):
        check_axis_gains(AxisSMC([200] * 4, [1] * 4, [1] * 4, n=4), p.m, p.c, 1e-4)
    with pytest.raises(ParameterError, match="5 entries"):
        AxisSMC([200] * 4, [1] * 5, [1] * 5)
    with pytest.raises(ParameterError, match="positive semi-definite"):
        table_5_3().with_weights(-1.0, 0.0)
    with pytest.raises(UnstableGainsError) as info:
        check_tip_gains(TipGains([100, 230, 230], [2, 40, 4], [10, 20, 20]), direction_inertia(p), 1e-4)
    assert info.value.where == "normal"


def test_step_disturbance_peak_matches_continuous_response():
    """Peak error after a 1 V step disturbance: m S' = -Ks S - d_hat + d, d_hat' = Gamma S, e = S/(s + lam),
    so for d = 1/s, e(s) = 1 / ((s + lam)(m s^2 + Ks s + Gamma)): the impulse response of that system
    (scipy.signal.impulse). The sampled loop at 10 us agrees within 1 %."""
    g = table_5_2()
    m, c = 0.00682, 0.01964
    t = np.linspace(0, 3, 300001)
    _, y = scipy.signal.impulse(scipy.signal.lti([1.0], np.polymul([1, 150.0], [m, 0.5, 3.0])), T=t)
    peak = step_disturbance_peak(m, c, g, 3, 1e-5, duration=3.0)
    assert peak == pytest.approx(np.abs(y).max(), rel=1e-2)


@pytest.fixture(scope="module")
def ref():
    return eq436_reference(sample_period=1e-3)


def test_eq436_reference_frame_is_the_helix_frenet_frame(ref):
    """eq 4.36 tip: helix of radius sqrt(250) mm and pitch 15 mm/rad, curvature r / (r^2 + 15^2) = sqrt(250)/475;
    Frenet-Serret t' = |P'| kappa n; F orthonormal; the reference tip is the forward kinematics of q_ref."""
    r, _ = ref
    F = np.asarray(r.F)
    np.testing.assert_allclose(np.einsum("nji,njk->nik", F, F), np.broadcast_to(np.eye(3), F.shape), atol=1e-12)
    kappa = np.sqrt(250.0) / 475.0
    speed = np.linalg.norm(np.asarray(r.Pd), axis=1)
    np.testing.assert_allclose(np.asarray(r.Fd)[:, :, 0], (speed * kappa)[:, None] * F[:, :, 1], atol=1e-10)
    P = np.asarray(TableTiltingAC().forward(r.q)[0])
    np.testing.assert_allclose(P, np.asarray(r.P), atol=1e-9)
    assert float(np.linalg.norm(np.diff(np.asarray(r.P), axis=0), axis=1).sum()) == pytest.approx(273.87, abs=0.01)
    assert speed.max() == pytest.approx(50.0, rel=1e-6)  # §5.4 cruise feed
    assert np.all(np.isfinite(np.asarray(r.F)))  # defined at rest too (geometric frame)


def test_straight_stretch_raises_frenet_frame_error():
    """A straight tip path has no Frenet normal: the error names the parameter and time stretch."""
    l = np.linspace(0, 1, 11)
    with pytest.raises(FrenetFrameError, match=r"first at l = 0 \(t = 0 s\)"):
        parametric_reference(lambda s: jnp.stack([s, 0 * s, 0 * s]), lambda s: 0.5 + 0 * s, lambda s: 0 * s,
                             l, np.ones(11), np.zeros(11), np.zeros(11), l, TableTiltingAC(), 0.1)


def test_cartesian_jacobian_is_orthogonal_and_matches_kinematics():
    """The tip law inverts J_xyz by its transpose: J_xyz = R^T diag(-1, -1, 1) (eq 4.6) is orthogonal and
    equals the closed-form dP/dq of research.paths.kinematics5 for any offsets (J^T read column by
    column from the law's J_xyz^T v)."""
    from research.control._loop import _J_xyz_T

    q = jnp.array([12.0, -3.0, 40.0, 1.3, -0.4])
    m = TableTiltingAC(L_ya=10.0, L_ac=25.0, L_t=5.0)
    JT = np.column_stack([np.asarray(_J_xyz_T(q, jnp.asarray(e))) for e in np.eye(3)])
    J = JT.T
    np.testing.assert_allclose(J, np.asarray(m.tip_jacobian(q))[:, :3], atol=1e-14)
    np.testing.assert_allclose(J.T @ J, np.eye(3), atol=1e-14)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_closed_form_tip_motion_equals_taylor_mode_kinematics(seed):
    """The law's scalar closed form of P, P' and P''_rest (the part of P'' not made by the Cartesian
    accelerations, eq 4.10) equals an independent computation: jax.experimental.jet (Taylor mode) of
    research.paths.kinematics5's forward map (eq 4.5) with the Cartesian accelerations set to zero,
    for random poses, rates and rotary accelerations and non-zero offsets, to 1e-12 relative."""
    from jax.experimental.jet import jet

    from research.control._loop import _tip_motion

    rng = np.random.default_rng(seed)
    m = TableTiltingAC(L_ya=10.0, L_ac=25.0, L_t=5.0)
    q = jnp.asarray(rng.normal(size=5) * [50, 50, 50, 1, 3])
    qd = jnp.asarray(rng.normal(size=5) * [50, 50, 50, 1, 1])
    alpha = jnp.asarray(rng.normal(size=2) * 10)
    P, (Pd, P2) = jet(lambda x: m.forward(x)[0], (q,), ((qd, jnp.concatenate([jnp.zeros(3), alpha])),))
    for mine, ref in zip(_tip_motion(m, q, qd, alpha), (P, Pd, P2)):
        np.testing.assert_allclose(np.asarray(mine), np.asarray(ref), rtol=1e-12, atol=1e-12 * float(jnp.max(jnp.abs(ref))))


def test_lyapunov_function_decreases_for_a_constant_disturbance():
    """Eq 5.25-5.26 for one axis: with a constant disturbance d, V = 1/2 m S^2 + 1/2 (d - d_hat)^2 / Gamma
    has V' = -Ks S^2 <= 0. Sampled at 1 us, from a 1 V step (A axis, Table 5.2), the sequence V(k) never
    rises by more than 1e-6 of V(0), and the total drop over 0.2 s equals the dissipation sum T Ks S^2
    within 1 %."""
    m, c, lam, Ks, G, T = 0.00682, 0.01964, 150.0, 0.5, 3.0, 1e-6
    step = _axis_map(m, c, lam, Ks, G, T, d=1.0)
    A = np.asarray(jax.jacfwd(_axis_map(m, c, lam, Ks, G, T))(jnp.zeros(3)))
    b = np.asarray(step(jnp.zeros(3)))
    z = np.zeros(3)
    V, dissipated = [], []
    for _ in range(200000):  # 0.2 s
        q, v, dh = z
        S = -(lam * q + v)
        V.append(0.5 * m * S**2 + 0.5 * (1.0 - dh) ** 2 / G)
        dissipated.append(T * Ks * S**2)
        z = A @ z + b
    V, dissipated = np.array(V), np.array(dissipated)
    assert np.max(np.diff(V)) <= 1e-6 * V[0]
    assert V[0] - V[-1] == pytest.approx(np.sum(0.5 * (dissipated[1:] + dissipated[:-1])), rel=1e-2)
