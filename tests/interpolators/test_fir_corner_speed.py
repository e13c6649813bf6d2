"""The corner speed eq 13/14 rounds a corner between unequal feeds for (``_fir_overlap``,
"Unequal feeds"; ``plan_fir``'s ``corner_speed``), against an independent simulation: the two
blocks' velocity sampled every 10 us, each filter a discrete moving average (``np.convolve``),
the position its running sum."""

import jax.numpy as jnp
import numpy as np
import pytest

from research.errors import ParameterError
from research.interpolators import overlap_time, plan_fir
from research.interpolators._fir_overlap import corner_speed_change
from research.paths import Polyline

DT = 1e-5  # [s]


def simulated_corner(beta: float, f_out: float, f_in: float, overlap: float, delays) -> tuple[np.ndarray, ...]:
    """Output positions [mm] of a corner of turning angle ``beta`` [rad] at the origin: ``f_out``
    [mm/s] for 0.2 s along x, a gap of ``T_d - overlap`` [s] at rest, then ``f_in`` for 0.2 s
    along the turned direction; returns ``(positions (n, 2), u_out, u_in, L_out, L_in)``."""
    u_out, u_in = np.array([1.0, 0.0]), np.array([np.cos(beta), np.sin(beta)])
    Td = float(np.sum(delays))
    n1, n2 = round(0.2 / DT), round((Td - overlap) / DT)
    v = np.zeros((n1 + n2 + round(0.2 / DT) + round(Td / DT) + 10, 2))
    v[:n1] = f_out * u_out
    v[n1 + n2: n1 + n2 + round(0.2 / DT)] = f_in * u_in
    for T in delays:
        k = round(T / DT)
        v = np.stack([np.convolve(v[:, i], np.ones(k) / k)[: v.shape[0]] for i in range(2)], axis=1)
    L_out = f_out * n1 * DT
    return np.cumsum(v, axis=0) * DT - L_out * u_out, u_out, u_in, L_out, f_in * round(0.2 / DT) * DT


def segment_distance(q: np.ndarray, a: np.ndarray, u: np.ndarray, length: float) -> np.ndarray:
    """Distance [mm] of the rows of ``q`` to the segment from ``a`` along the unit ``u`` for ``length``."""
    s = np.clip((q - a) @ u, 0.0, length)
    return np.linalg.norm(q - a - s[:, None] * u, axis=1)


@pytest.mark.parametrize("delays", [(0.06, 0.03), (0.08,)])
def test_turn_speed_keeps_the_tolerance_at_unequal_feeds(delays):
    """Random corners (1-179 deg, feeds 20-300 mm/s either side, eps 10-200 um, seeded): at the
    overlap eq 13/14 gives for ``corner_speed_change(..., turn=True)`` the simulated output keeps
    eps both at the vertex (the distance to the polyline of samples) and along the two lines (the
    largest sample's distance), within 0.2 % of eps for the simulation's own discretization. The
    overlap is never shorter than the velocity step's, and where the turn bound is the smaller
    (small turns, unequal feeds) it is longer."""
    rng = np.random.default_rng(7)
    longer = 0
    for _ in range(24):
        beta = np.radians(rng.uniform(1.0, 179.0))
        f_out, f_in = rng.uniform(20.0, 300.0, 2)
        eps = rng.uniform(0.01, 0.2)
        u_out, u_in = np.array([[1.0, 0.0]]), np.array([[np.cos(beta), np.sin(beta)]])
        turn = corner_speed_change(jnp.array([f_out]), jnp.array([f_in]), u_out, u_in, True)
        step = corner_speed_change(jnp.array([f_out]), jnp.array([f_in]), u_out, u_in, False)
        Tk = float(overlap_time(eps, turn, jnp.array(delays))[0])
        Tk_step = float(overlap_time(eps, step, jnp.array(delays))[0])
        assert Tk >= Tk_step
        longer += Tk > Tk_step * (1 + 1e-9)
        q, uo, ui, Lo, Li = simulated_corner(beta, f_out, f_in, Tk, delays)
        chords = np.diff(q, axis=0)  # the vertex's distance to the polyline of samples
        s = np.clip(np.einsum("nd,nd->n", -q[:-1], chords) / np.maximum(np.sum(chords**2, axis=1), 1e-300), 0.0, 1.0)
        to_vertex = float(np.min(np.linalg.norm(q[:-1] + s[:, None] * chords, axis=1)))
        to_path = float(np.max(np.minimum(segment_distance(q, -Lo * uo, uo, Lo), segment_distance(q, np.zeros(2), ui, Li))))
        assert to_vertex <= eps * 1.002, (np.degrees(beta), f_out, f_in, eps, to_vertex)
        assert to_path <= eps * 1.002, (np.degrees(beta), f_out, f_in, eps, to_path)
    assert longer >= 5


def test_equal_feeds_give_eq_13_14_either_way():
    """At equal feeds both speeds are ``2 F sin(beta / 2)`` (eq 13/14's), at any turn."""
    beta = np.radians(np.array([0.5, 10.0, 90.0, 170.0]))
    u_out = np.tile([1.0, 0.0], (4, 1))
    u_in = np.stack([np.cos(beta), np.sin(beta)], axis=1)
    f = jnp.full(4, 150.0)
    want = 2 * 150.0 * np.sin(beta / 2)
    np.testing.assert_allclose(corner_speed_change(f, f, u_out, u_in, False), want, rtol=1e-13)
    np.testing.assert_allclose(corner_speed_change(f, f, u_out, u_in, True), want, rtol=1e-13)


def test_a_feed_step_on_a_slight_turn_keeps_full_overlap_with_turn():
    """Two 30 mm lines at a 0.5 deg turn, 100 then 200 mm/s, eps 20 um, eq 13/14 alone
    (``refine=False``): the velocity step (about 100 mm/s) makes the corner dwell, the turn at
    200 mm/s (1.75 mm/s) does not: ``T_d`` of overlap, and the plan is shorter by the dwell."""
    b = np.radians(0.5)
    path = Polyline([[0.0, 0.0], [30.0, 0.0], [30.0 + 30.0 * np.cos(b), 30.0 * np.sin(b)]])
    delays = (0.06, 0.03)
    step = plan_fir(path, [100.0, 200.0], delays, 0.02, refine=False)
    turn = plan_fir(path, [100.0, 200.0], delays, 0.02, refine=False, corner_speed="turn")
    assert float(turn.overlaps[0]) == pytest.approx(0.09, rel=1e-12)
    assert float(step.overlaps[0]) < 0.09 * 0.9
    assert float(turn.cycle_time) == pytest.approx(float(step.cycle_time) - (0.09 - float(step.overlaps[0])), rel=1e-9)


def test_unknown_corner_speed_is_refused():
    path = Polyline([[0.0, 0.0], [10.0, 0.0], [10.0, 10.0]])
    with pytest.raises(ParameterError, match="corner_speed"):
        plan_fir(path, 100.0, (0.06, 0.03), 0.05, corner_speed="normal")


def test_turn_plans_are_differentiable_in_the_feeds():
    """A traced ``plan_fir(..., corner_speed="turn")`` (the JAX timing kernel) gives the cycle
    time's gradient in the block feeds of a three-corner path with feed steps: central finite
    differences (h = 1e-4 mm/s) agree to 1e-6 relative, and the value is the untraced plan's."""
    import jax

    b = np.radians(0.5)
    path = Polyline([[0.0, 0.0], [30.0, 0.0], [30.0 + 30.0 * np.cos(b), 30.0 * np.sin(b)], [70.0, 10.0]])

    def cycle(F):
        return plan_fir(path, F, (0.06, 0.03), 0.02, corner_speed="turn").cycle_time

    F0 = jnp.array([100.0, 200.0, 150.0])
    value, grad = jax.value_and_grad(cycle)(F0)
    h = 1e-4
    fd = np.array([(float(cycle(F0.at[i].add(h))) - float(cycle(F0.at[i].add(-h)))) / (2 * h) for i in range(3)])
    np.testing.assert_allclose(np.asarray(grad), fd, rtol=1e-6, atol=1e-12)
    assert float(value) == pytest.approx(float(cycle(np.asarray(F0))), rel=1e-12)
