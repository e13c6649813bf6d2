"""The smooth fixed-order FIR formulation (``_fir_smooth``), its residual vibration and the lower
bound of ``_fir_bound``, each against an independent computation."""

import numpy as np
import pytest
from scipy.signal import lsim

from research.interpolators import plan_fir
from research.interpolators import _fir_smooth as sm
from research.interpolators._fir_bound import fir_cycle_lower_bound, fir_kernel, mean_distance
from research.interpolators._fir_reorder import profile_residuals
from research.optimal import StructuralMode, trajectory_vibration
from research.paths import named_path
from tests.interpolators.test_fir_optimize import random_path  # the same seeded paths

DELAYS = (0.06, 0.03)
F, EPS = 200.0, 0.1


@pytest.fixture(scope="module")
def plain():
    path = random_path(21)
    plan = plan_fir(path, F, DELAYS, EPS, refine=False)  # one feed per block: (S1) with one piece
    layout = sm.Layout.build(path.points, F, DELAYS, (1.0,))
    z = np.concatenate([np.asarray(plan.pulse_times), sum(DELAYS) - np.asarray(plan.overlaps),
                        np.asarray(plan.corner_times)])
    return path, plan, layout, z


def test_closed_form_matches_the_planner_profile(plain):
    """(S1), the B-spline form of filtered pulses, equals build_profile's piecewise polynomial
    (position, velocity, acceleration) and its cycle time."""
    path, plan, layout, z = plain
    t = np.linspace(0.0, float(plan.cycle_time), 1501)
    ref = plan.position.derivatives(t, 3)
    for nu in range(3):
        np.testing.assert_allclose(sm.position(layout, z, t, nu), np.asarray(ref[nu]), atol=1e-9 * max(1.0, np.abs(ref[nu]).max()))
    assert layout.end_row() @ z + layout.Td == pytest.approx(float(plan.cycle_time), rel=1e-12)


def test_fixed_order_nlp_reproduces_the_profile(plain):
    """At its own linearisation point the NLP's constraint rows agree with the profile: the
    corner rows equal |q(c_k) - V_k|^2 / eps^2 computed from the planner's position."""
    import casadi as ca

    path, plan, layout, z = plain
    nlp, lbg, ubg, fixed = sm.build_nlp(layout, z, None, EPS)
    g = ca.Function("g", [nlp["x"]], [nlp["g"]])(z).full().ravel()
    q = np.asarray(plan.position(np.asarray(plan.corner_times)))
    expect = np.sum((q - path.points[1:-1]) ** 2, axis=1) / (EPS * (1 - 1e-6)) ** 2
    np.testing.assert_allclose(g[-(path.n_segments - 1):], expect, rtol=1e-9)
    assert float(ca.Function("f", [nlp["x"]], [nlp["f"]])(z)) == pytest.approx(float(plan.cycle_time), rel=1e-12)


def test_residual_vibration_three_ways(plain):
    """Residual envelope of a mode: closed form (S2), Gauss-Legendre on the exact profile, and
    scipy.signal.lsim of eq V1 on the sampled acceleration followed by eq V3."""
    path, plan, layout, z = plain
    mode = StructuralMode(0, 11.4, 0.02)
    S = layout.starts_matrix()
    t_end = float(layout.end_row() @ z + layout.Td)
    closed = np.sqrt(sm.residual_squared(layout, z[: layout.n_pieces], S @ z, t_end, 0, 11.4, 0.02))
    exact = profile_residuals(plan.position, [(0, 11.4, 0.02)])[0]
    wn, zt = mode.wn, mode.damping
    t = np.linspace(0.0, t_end, 200001)
    a = np.asarray(plan.position.derivatives(t, 3)[2])[:, 0]
    _, y, x = lsim(([-1.0], [1.0, 2 * zt * wn, wn * wn]), a, t)
    dy = np.gradient(y, t)
    s, wd = zt * wn, wn * np.sqrt(1 - zt * zt)
    sim = np.hypot(y[-1], (dy[-1] + s * y[-1]) / wd)
    assert closed == pytest.approx(exact, rel=1e-8)
    assert exact == pytest.approx(sim, rel=2e-3)
    assert exact == pytest.approx(trajectory_vibration(plan.trajectory(1e-3), [mode])[0][0], rel=1e-6)


def test_mean_distance_of_one_box():
    """(B1) for a single box of width T and a centred dwell l: mean distance (T - l)^2 / (4 T)."""
    T = 0.1
    s, h = fir_kernel([T], ds=1e-5)
    for loss in (0.0, 0.03, 0.07):
        assert mean_distance(loss, np.inf, s, h) == pytest.approx((T - loss) ** 2 / (4 * T), rel=1e-3)


def test_bound_below_the_plans():
    """The bound lies below the plain look-ahead plan, which sits on it for this symmetric
    90-degree corner at feed F (the dwell at the vertex is (B1)'s extremal; the diamond is
    measured in bench_fir_optimal), and both move together with eps."""
    path = named_path("corner90")
    F2, D2, eps2 = 250.0, (0.148, 0.089), 0.5
    bound, ok = fir_cycle_lower_bound(path, F2, D2, eps2)
    assert ok
    plan = plan_fir(path, F2, D2, eps2)
    assert bound <= float(plan.cycle_time)
    assert bound == pytest.approx(float(plan.cycle_time), rel=1e-6)
    # smaller eps: the bound and the plan move together
    b_small, _ = fir_cycle_lower_bound(path, F2, D2, 0.1)
    assert b_small <= float(plan_fir(path, F2, D2, 0.1).cycle_time) and b_small > bound


def test_bound_is_trivial_for_short_blocks():
    bound, ok = fir_cycle_lower_bound(named_path("zigzag"), 250.0, (0.148, 0.089), 0.5)
    path = named_path("zigzag")
    assert not ok and bound == pytest.approx(path.lengths.sum() / 250.0 + 0.237)
