"""Discrete simulation against scipy.signal and analytic results."""

import numpy as np
import pytest
from scipy import signal
from scipy.integrate import solve_ivp

from research.drives import (
    ClosedLoopModel,
    RigidBodyAxis,
    simulate,
    table_6_1_closed_loop,
    table_6_1_ppi,
    table_6_2_pid,
)
from tests.drives._helpers import make_trajectory, polynomial_trajectory, sine_trajectory

Ts = 1e-3


def _linear(model):
    """Table 6.1 model without friction (for comparisons with linear scipy simulations)."""
    return ClosedLoopModel(model.a1, model.a2, model.a3, model.b0, model.b1, model.b2, 0.0)


def _scipy_system(model):
    r = model.realization()
    return np.asarray(r.A), np.asarray(r.B), np.asarray(r.C[:2]), np.zeros((2, 3))


def _rel(a, b):
    return np.max(np.abs(np.asarray(a) - np.asarray(b))) / np.max(np.abs(np.asarray(b)))


def test_step_response_matches_cont2discrete_zoh():
    model = _linear(table_6_1_closed_loop())
    n = 800
    q = np.ones(n)
    q[0] = 0.0  # step after the first sample
    res = simulate(model, make_trajectory(q, Ts), hold="zoh")
    Ad, Bd, Cd, Dd, _ = signal.cont2discrete(_scipy_system(model), Ts, method="zoh")
    u = np.column_stack([q, np.zeros(n), np.zeros(n)])
    _, y, _ = signal.dlsim((Ad, Bd, Cd, Dd, Ts), u, x0=np.zeros(3))
    assert _rel(res.position[:, 0], y[:, 0]) < 1e-9
    assert _rel(res.velocity[:, 0], y[:, 1]) < 1e-9
    # the step settles at unity DC gain
    assert abs(float(res.position[-1, 0]) - 1.0) < 1e-3


@pytest.mark.parametrize("model", [table_6_1_closed_loop(), table_6_1_ppi(), table_6_2_pid()], ids=["eq6.3", "P-PI", "PID"])
def test_response_is_translation_invariant(model):
    """The loop starts at its rest state at the first reference sample (integrators loaded), so a
    stroke 50 mm away from the origin gives the same motion, shifted. Tolerance: 1e-5 mm, the
    Coulomb sign chattering on round-off velocities (~1e-12 mm/s) at rest; before the rest state was
    used, a constant reference at 50 mm made eq 6.3 dip by ~10 mm."""
    n = 600
    q = polynomial_trajectory([0.0, 0.0, 0.0, 2000.0], n, Ts)  # cubic rise from rest
    shifted = make_trajectory(np.asarray(q.q)[:, 0] + 50.0, Ts, np.asarray(q.v)[:, 0], np.asarray(q.a)[:, 0], np.asarray(q.j)[:, 0])
    base, moved = simulate(model, q), simulate(model, shifted)
    assert np.max(np.abs(np.asarray(moved.position) - 50.0 - np.asarray(base.position))) < 1e-5
    still = simulate(model, make_trajectory(np.full(200, 50.0), Ts))
    assert np.max(np.abs(np.asarray(still.position) - 50.0)) < 1e-5


@pytest.mark.parametrize("hold", ["foh", "cubic"])
def test_ramp_response_matches_lsim(hold):
    model = _linear(table_6_1_closed_loop())
    n, V = 1500, 80.0
    t = np.arange(n) * Ts
    tr = make_trajectory(V * t, Ts, v=np.full(n, V))
    res = simulate(model, tr, hold=hold)
    _, y, _ = signal.lsim(_scipy_system(model), np.column_stack([V * t, np.full(n, V), np.zeros(n)]), t,
                          X0=[0.0, 0.0, V], interp=True)
    assert _rel(res.position[:, 0], y[:, 0]) < 1e-9


def test_cubic_hold_is_exact_for_cubic_reference():
    """A reference cubic in time is reproduced exactly by the cubic (Taylor) hold: compare with a
    tight-tolerance ODE solution of eq 6.3."""
    model = _linear(table_6_1_closed_loop())
    coeffs = [0.0, 0.0, 300.0, -150.0]
    n = 400
    res = simulate(model, polynomial_trajectory(coeffs, n, Ts), hold="cubic")
    p = np.polynomial.Polynomial(coeffs)
    r = model.realization()
    A, B = np.asarray(r.A), np.asarray(r.B)

    def rhs(t, z):
        return A @ z + B @ np.array([p(t), p.deriv(1)(t), p.deriv(2)(t)])

    t = np.arange(n) * Ts
    sol = solve_ivp(rhs, (0, t[-1]), [0.0, 0.0, 0.0], t_eval=t, method="DOP853", rtol=1e-13, atol=1e-15)
    assert _rel(res.position[:, 0], sol.y[1]) < 1e-9


def test_ppi_physical_model_equals_eq_6_4_closed_loop():
    """Fig 6.1b simulated in its own states == eq 6.3 with the eq 6.4 map (friction included).

    Two different realizations, each exact in exact arithmetic; their matrix exponentials round
    differently (entries from 1 to a3 Ts = 2.5e3), hence 1e-8 rather than 1e-9."""
    ppi = table_6_1_ppi()
    tr = sine_trajectory(5.0, 2.0, 1500, Ts)
    a = simulate(ppi, tr)
    b = simulate(ppi.closed_loop_model(), tr)
    assert _rel(a.position, b.position) < 1e-8
    np.testing.assert_allclose(np.asarray(a.friction) * float(ppi.plant.rg / ppi.plant.J), b.friction, rtol=1e-12)
    assert a.control is not None and b.control is None


def test_pid_physical_model_equals_eq_6_5_closed_loop():
    pid = table_6_2_pid()
    plant = pid.plant
    pid = type(pid)(RigidBodyAxis(plant.J, plant.B, plant.Ka, plant.Kt, plant.rg, 0.0), pid.Kp, pid.Ki, pid.Kd,
                    pid.Bff, pid.Jff, pid.friction_ff, pid.wp, pid.wd)
    tr = sine_trajectory(5.0, 3.0, 1200, Ts)
    a = simulate(pid, tr)
    b = simulate(pid.closed_loop_model(), tr)
    assert _rel(a.position, b.position) < 1e-8


def test_ppi_steady_state_ramp_error_is_analytic_despite_friction():
    """P-PI at constant velocity: e = V (1 - Vff)/(Kv rg); the PI velocity loop absorbs the friction."""
    ppi = table_6_1_ppi()
    n, V = 3000, 50.0
    t = np.arange(n) * Ts
    res = simulate(ppi, make_trajectory(V * t, Ts, v=np.full(n, V)))
    e = float(res.tracking_error[-1, 0])
    assert float(ppi.plant.coulomb) > 0
    assert e == pytest.approx(float(ppi.steady_state_ramp_error(V)), rel=1e-9)
    assert e == pytest.approx(V * 0.5 / 111.4049996, rel=1e-9)
    # and the same number from the closed-loop form (final value theorem)
    assert e == pytest.approx(float(ppi.closed_loop_model().steady_state_ramp_error(V)), rel=1e-6)


def test_control_signal_balances_viscous_and_coulomb_at_constant_velocity():
    ppi = table_6_1_ppi()
    n, V = 3000, 50.0
    t = np.arange(n) * Ts
    res = simulate(ppi, make_trajectory(V * t, Ts, v=np.full(n, V)))
    P = ppi.plant
    expected = float(P.c * V + P.coulomb / (P.Ka * P.Kt))  # m x'' + c x' = u - d/(Ka Kt), x'' = 0
    assert float(res.control[-1, 0]) == pytest.approx(expected, rel=1e-9)


def test_multi_axis_equals_single_axis_runs():
    m1 = table_6_1_closed_loop()
    m2 = ClosedLoopModel.from_poles(2 * np.pi * 40, 0.6, 2 * np.pi * 15, 0.2, 150.0, 50000.0, 5.0)
    tr = sine_trajectory(3.0, 1.5, 900, Ts, axes=("x", "y"))
    both = simulate((m1, m2), tr)
    for k, m in enumerate((m1, m2)):
        single = simulate(m, make_trajectory(tr.q[:, k], Ts, tr.v[:, k], tr.a[:, k], tr.j[:, k]))
        np.testing.assert_allclose(both.position[:, k], single.position[:, 0], rtol=0, atol=1e-12)
    assert both.position.shape == (900, 2)
