"""FIR-overlap interpolator against Sencer 2015 (eq 4, 9, 10, 13, 14, Fig 4) and an independent
discrete-convolution simulation."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from research.errors import ParameterError, PathError
from research.interpolators import (
    cornering_error,
    delays_for_modes,
    fir_by_convolution,
    fir_interpolate,
    magnitude_response,
    overlap_time,
    plan_fir,
)
from research.metrics import corner_errors, peak_axis_values
from research.paths import Polyline, named_path

PAPER_DELAYS = [0.148, 0.089]  # Sencer 2015 §4: T1 = 148 ms, T2 = 89 ms


def corner_path(beta_deg: float, length: float = 60.0) -> Polyline:
    """Two ``length`` mm lines with turning angle ``beta`` at the origin."""
    b = np.radians(beta_deg)
    return Polyline([[-length, 0.0], [0.0, 0.0], [length * np.cos(b), length * np.sin(b)]])


def simulated_corner_error(plan, path, Ts):
    """Corner error of the discrete-convolution simulation: the closest sample, refined by a
    parabola through the squared distances of its neighbours."""
    _, q = fir_by_convolution(plan, path, Ts)
    d2 = np.sum((q - path.points[1]) ** 2, axis=1)
    i = int(np.argmin(d2))
    a, b, c = d2[i - 1], d2[i], d2[i + 1]
    curvature = a - 2 * b + c
    return float(np.sqrt(max(b - (a - c) ** 2 / (8 * curvature), 0.0))) if curvature > 0 else float(np.sqrt(b))


# -- eq 13 / eq 14 ------------------------------------------------------------------------------
@pytest.mark.parametrize("beta", [30.0, 90.0, 135.0, 170.0])
@pytest.mark.parametrize("eps_um", [5.0, 50.0, 500.0])
@pytest.mark.parametrize("delays", [[0.1], PAPER_DELAYS], ids=["eq13_one_filter", "eq14_two_filters"])
def test_corner_error_matches_simulation(beta, eps_um, delays):
    """eq 13 (one filter) and eq 14 (two filters, both branches) give overlaps whose simulated
    corner error equals the tolerance within 1 %."""
    path, eps, F, Ts = corner_path(beta), eps_um * 1e-3, 250.0, 1e-4
    plan = plan_fir(path, F, delays, eps)
    Tk = float(plan.overlaps[0])
    assert 0 < Tk < sum(delays)  # the formula regime, not the full-overlap cap
    assert simulated_corner_error(plan, path, Ts) == pytest.approx(eps, rel=0.01)
    traj = plan.trajectory(1e-3)
    assert corner_errors(traj, path)[0] == pytest.approx(eps, rel=1e-6)  # exact profile


def test_eq13_closed_form():
    """eq 13: eps = sqrt(F^2 T_k^4 (1 - cos beta) / (32 T_1^2)), here at F = 250 mm/s, T_1 = 0.1 s."""
    F, T1, beta, Tk = 250.0, 0.1, np.radians(60.0), 0.04
    eq13 = np.sqrt(F**2 * Tk**4 * (1 - np.cos(beta)) / (32 * T1**2))
    dF = jnp.array([2 * F * np.sin(beta / 2)])
    assert float(cornering_error(Tk, dF, jnp.array([T1]))[0]) == pytest.approx(eq13, rel=1e-12)
    assert float(overlap_time(eq13, dF, jnp.array([T1]))[0]) == pytest.approx(Tk, rel=1e-12)


@pytest.mark.parametrize("Tk", [0.05, 0.17, 0.2])  # below and above the branch point 2 T_2 = 0.178 s
def test_eq14_both_branches(Tk):
    """eq 14 is the inverse of the cornering error on both of its branches (to 1e-12)."""
    T1, T2 = PAPER_DELAYS
    F, beta = 250.0, np.radians(90.0)
    s = np.sin(beta / 2)
    dF = jnp.array([2 * F * s])
    eps = float(cornering_error(Tk, dF, jnp.array(PAPER_DELAYS))[0])
    expected = np.cbrt(24 * T1 * T2 * eps / (F * s)) if Tk <= 2 * T2 else T2 + np.sqrt(4 * T1 * eps / (F * s) - T2**2 / 3)
    assert expected == pytest.approx(Tk, rel=1e-12)
    assert float(overlap_time(eps, dF, jnp.array(PAPER_DELAYS))[0]) == pytest.approx(Tk, rel=1e-12)


def test_three_filters_numeric_overlap():
    """n = 3: the bisection inverse reproduces the tolerance on the exact profile."""
    path = corner_path(90.0)
    plan = plan_fir(path, 200.0, [0.06, 0.04, 0.02], 0.02)
    assert float(plan.corner_errors[0]) == pytest.approx(0.02, rel=1e-6)
    assert corner_errors(plan.trajectory(1e-3), path)[0] == pytest.approx(0.02, rel=1e-6)


@pytest.mark.parametrize("beta", [0.0, 1e-6, 45.0, 179.9, 180.0])
def test_any_turning_angle(beta):
    """0 deg (collinear: full overlap, no slow-down) to 180 deg (reversal) all hold the tolerance."""
    path = corner_path(beta) if beta < 180 else Polyline([[-60.0, 0.0], [0.0, 0.0], [-30.0, 0.0]])
    plan = plan_fir(path, 250.0, PAPER_DELAYS, 0.05)
    err = corner_errors(plan.trajectory(1e-3), path)[0]
    assert err <= 0.05 * (1 + 1e-6)
    if beta == 0.0:
        assert float(plan.overlaps[0]) == pytest.approx(sum(PAPER_DELAYS))


# -- Fig 4 example --------------------------------------------------------------------------------
def test_fig4_sharp_cornering_cycle_time():
    """Fig 4b: F = 50 mm/s on two 2.5 mm lines, T_1 = 20 ms: each block takes T_v + T_1 = 70 ms."""
    plan = plan_fir(named_path("sencer2015_fig4"), 50.0, [0.020], 0.0)
    assert float(plan.start_times[1]) == pytest.approx(0.070, abs=1e-12)
    assert float(plan.cycle_time) == pytest.approx(0.140, abs=1e-12)


def test_fig4_full_overlap_peak_acceleration():
    """Fig 4c: full overlap; Y reverses from F sin 45 to -F sin 45 in T_1: 3535 mm/s^2 (paper, rounded)."""
    path = named_path("sencer2015_fig4")
    plan = plan_fir(path, 50.0, [0.020], 1.0)  # tolerance above the full-overlap error
    assert float(plan.overlaps[0]) == pytest.approx(0.020)
    peak = peak_axis_values(plan.trajectory(1e-3), 2)
    assert peak[1] == pytest.approx(3535.0, abs=1.0)
    assert peak[0] == pytest.approx(50 * np.sin(np.pi / 4) / 0.020, rel=1e-9)  # X: start/stop only
    assert float(plan.cycle_time) == pytest.approx(0.120, abs=1e-12)  # 2 T_v + T_1


def test_fig4_half_overlap():
    """Fig 4d: T_k = T_d / 2 = 10 ms; the drives slow down for T_d - T_k before the corner."""
    path = named_path("sencer2015_fig4")
    dF = jnp.array([2 * 50.0 * np.sin(np.pi / 4)])
    eps = float(cornering_error(0.010, dF, jnp.array([0.020]))[0])
    plan = plan_fir(path, 50.0, [0.020], eps)
    assert float(plan.overlaps[0]) == pytest.approx(0.010, rel=1e-9)
    assert float(plan.cycle_time) == pytest.approx(0.130, abs=1e-12)


# -- exactness ------------------------------------------------------------------------------------
@pytest.mark.parametrize("name", ["corner90", "diamond", "zigzag", "sencer2015_fig4"])
def test_endpoint_reached(name):
    """The last sample is at rest on the end point within 1e-9 mm."""
    path = named_path(name)
    traj = fir_interpolate(path, 250.0, PAPER_DELAYS, 0.05)
    assert np.max(np.abs(np.asarray(traj.q[-1]) - path.points[-1])) < 1e-9
    assert np.max(np.abs(np.asarray(traj.v[-1]))) < 1e-9
    assert float(traj.duration) <= traj.t[-1] < float(traj.duration) + traj.sample_period


def test_exact_profile_matches_convolution_at_second_order():
    """The exact piecewise-polynomial profile and the discrete convolution agree to O(Ts^2)."""
    path = named_path("diamond")
    plan = plan_fir(path, 250.0, PAPER_DELAYS, 0.5)
    errs = []
    for Ts in (1e-3, 1e-4):
        t, q = fir_by_convolution(plan, path, Ts)
        n = min(len(t), plan.trajectory(Ts).n_samples)
        errs.append(np.max(np.abs(q[:n] - np.asarray(plan.trajectory(Ts).q[:n]))))
    assert errs[1] < errs[0] / 50  # second order: 100x for 10x finer
    assert errs[1] < 1e-5


def test_kinematics_of_one_filter_pulse():
    """eq 4: one filter turns a velocity pulse into a trapezoid with a_max = v / T_1."""
    path = Polyline([[0.0], [100.0]], axes=("x",))
    traj = fir_interpolate(path, 200.0, [0.05], 0.0, sample_period=1e-3)
    assert float(traj.duration) == pytest.approx(0.5 + 0.05)  # T_v + T_1
    assert np.max(np.asarray(traj.a)) == pytest.approx(200.0 / 0.05)
    assert float(traj.evaluate(np.array([0.025]), 1)[0, 0]) == pytest.approx(100.0)  # (v/T1) t


def test_cycle_time_continuous_and_differentiable_in_delays():
    """Cycle time is smooth in T_i off the sample grid; jax.grad matches central differences."""
    path = named_path("diamond")

    def cycle(d):
        return plan_fir(path, 250.0, d, 0.5).cycle_time

    d0 = jnp.array([0.14831, 0.08917])  # not multiples of Ts
    grad = jax.grad(cycle)(d0)
    h = 1e-7
    fd = [(cycle(d0.at[i].add(h)) - cycle(d0.at[i].add(-h))) / (2 * h) for i in range(2)]
    np.testing.assert_allclose(grad, fd, rtol=1e-6)
    fine = [float(cycle(d0.at[0].add(k * 1e-6))) for k in range(5)]
    assert np.all(np.abs(np.diff(fine, 2)) < 1e-9)  # no sample-grid steps


def test_corner_error_gradient_off_tolerance():
    """Where the overlap is capped at T_d, the corner error depends on T_i and grad matches FD."""
    path = corner_path(20.0)

    def err(d):
        return plan_fir(path, 100.0, d, 5.0).corner_errors[0]

    d0 = jnp.array([0.05, 0.03])
    h = 1e-7
    fd = [(err(d0.at[i].add(h)) - err(d0.at[i].add(-h))) / (2 * h) for i in range(2)]
    np.testing.assert_allclose(jax.grad(err)(d0), fd, rtol=1e-5)
    assert float(err(d0)) < 5.0


# -- short segments: the verified-overlap rule ----------------------------------------------------
def test_short_segments_hold_tolerance_where_eq13_alone_fails():
    """A cluster of sub-millimetre segments (as CAM output has) after a long line: with one 20 ms
    filter at 88.5 mm/s the averaging window spans several corners, eq 13 alone breaks the
    tolerance at corner 4 by 7 %, and the verified overlap brings every corner within it."""
    path = Polyline(
        [[0.0, 0.0], [35.88, 0.0], [35.8363, -0.0242], [35.4872, 0.439], [35.4243, 0.4697],
         [35.047, -3.1206], [34.977, -3.1206]]
    )
    eps = 0.3
    naive = plan_fir(path, 88.5, [0.02], eps, refine=False)
    assert np.max(corner_errors(naive.trajectory(1e-3), path)) > 1.05 * eps
    plan = plan_fir(path, 88.5, [0.02], eps)
    assert np.max(corner_errors(plan.trajectory(1e-3), path)) <= eps * (1 + 1e-3)
    assert np.all(np.asarray(plan.overlaps) <= np.asarray(naive.overlaps) + 1e-15)
    assert float(plan.cycle_time) > float(naive.cycle_time)  # the price: less overlap


@st.composite
def random_polylines(draw):
    n = draw(st.integers(3, 10))
    lengths = draw(st.lists(st.floats(0.05, 40.0), min_size=n - 1, max_size=n - 1))
    turns = draw(st.lists(st.floats(-np.pi, np.pi), min_size=n - 1, max_size=n - 1))
    heading = np.cumsum(turns)
    steps = np.column_stack([np.cos(heading), np.sin(heading)]) * np.asarray(lengths)[:, None]
    return Polyline(np.vstack([[0.0, 0.0], np.cumsum(steps, axis=0)]))


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    path=random_polylines(),
    feed=st.floats(5.0, 300.0),
    delays=st.sampled_from([[0.02], [0.148, 0.089], [0.05, 0.03, 0.01]]),
    eps=st.floats(1e-3, 1.0),
)
def test_property_every_corner_within_tolerance(path, feed, delays, eps):
    """Random polylines, short segments included: every corner error <= eps (1 + 1e-3), measured on
    the sampled trajectory refined with its exact profile, and the end point is reached."""
    traj = fir_interpolate(path, feed, delays, eps)
    assert np.all(corner_errors(traj, path) <= eps * (1 + 1e-3))
    assert np.max(np.abs(np.asarray(traj.q[-1]) - path.points[-1])) < 1e-9


# -- frequency shaping ----------------------------------------------------------------------------
def test_eq10_delays_null_the_modes():
    """eq 9/10: T_i = k / f_r puts a zero of the acceleration spectrum on each mode."""
    delays = delays_for_modes([6.8, 11.4])
    assert delays == pytest.approx([1 / 6.8, 1 / 11.4])
    for f in (6.8, 11.4, 2 * 6.8):
        assert float(magnitude_response(2 * np.pi * f, delays)) < 1e-12
    assert delays_for_modes([10.0], k=3) == pytest.approx([0.3])
    with pytest.raises(ParameterError, match="positive integer"):
        delays_for_modes([10.0], k=0)


def test_eq9_sinc_magnitude():
    """eq 9: |M(jw)| = prod |sin(w T_i / 2) / (w T_i / 2)|."""
    w = np.linspace(0.1, 300.0, 50)
    T = np.array(PAPER_DELAYS)
    expected = np.prod(np.abs(np.sin(w[:, None] * T / 2) / (w[:, None] * T / 2)), axis=1)
    np.testing.assert_allclose(magnitude_response(w, T), expected, rtol=1e-12)


# -- bad input ------------------------------------------------------------------------------------
@pytest.mark.parametrize(
    "feed, delays, eps, match",
    [
        (0.0, [0.1], 0.1, "feed F must be finite and > 0"),
        (-5.0, [0.1], 0.1, "feed F must be finite and > 0"),
        (float("nan"), [0.1], 0.1, "feed F must be finite and > 0"),
        (100.0, [0.1, 0.0], 0.1, "T_2 must be finite and > 0"),
        (100.0, [-0.1], 0.1, "T_1 must be finite and > 0"),
        (100.0, [], 0.1, "non-empty"),
        (100.0, [0.1], -0.01, "tolerance epsilon must be a finite scalar >= 0"),
        (100.0, [0.1], float("nan"), "tolerance epsilon"),
        ([100.0, 50.0], [0.1], 0.1, "one value per segment"),
    ],
)
def test_bad_parameters(feed, delays, eps, match):
    with pytest.raises(ParameterError, match=match):
        plan_fir(named_path("zigzag"), feed, delays, eps)


@pytest.mark.parametrize(
    "points, match",
    [
        ([], "shape"),
        ([[0.0, 0.0]], "shape"),
        ([[0.0, 0.0], [float("nan"), 1.0]], "non-finite"),
        ([[0.0, 0.0], [1.0, 1.0], [1.0, 1.0], [2.0, 0.0]], "segment 1 .* zero length"),
    ],
)
def test_bad_paths(points, match):
    with pytest.raises(PathError, match=match):
        Polyline(points)


def test_zero_length_segments_merged_on_request():
    path = Polyline.from_points([[0.0, 0.0], [1.0, 1.0], [1.0, 1.0], [2.0, 0.0]], merge_duplicates=True)
    assert path.n_segments == 2
    traj = fir_interpolate(path, 100.0, [0.02], 0.01)
    assert np.all(np.isfinite(np.asarray(traj.q)))


def test_eq7_acceleration_spectrum_of_a_filtered_pulse():
    """eq 7: |a'(jw)| = |v(jw)| w |M_1 ... M_n(jw)|, checked by a Fourier integral of the exact
    acceleration of one straight move (pulse F for T_v) through the paper's two filters."""
    from research.interpolators import acceleration_spectrum

    F, L = 100.0, 20.0
    traj = fir_interpolate(Polyline([[0.0], [L]], axes=("x",)), F, PAPER_DELAYS, 0.0, sample_period=1e-4)
    t, a = np.asarray(traj.t), np.asarray(traj.a)[:, 0]
    w = 2 * np.pi * np.array([0.5, 3.0, 6.8, 9.0, 11.4])
    numeric = np.abs(np.trapezoid(a[None, :] * np.exp(-1j * w[:, None] * t[None, :]), t, axis=1))
    Tv = L / F
    pulse = np.abs(F * (1 - np.exp(-1j * w * Tv)) / (1j * w))  # spectrum of the velocity pulse
    np.testing.assert_allclose(numeric, acceleration_spectrum(w, PAPER_DELAYS, pulse), rtol=1e-3, atol=1e-3)


# -- beyond the paper: holding per-axis limits ----------------------------------------------------
@pytest.mark.parametrize("name", ["corner90", "diamond", "zigzag"])
def test_plain_overlap_breaks_the_nominal_jerk_and_limited_variant_holds_it(name):
    """Plain FIR overlap exceeds its own nominal envelope (v = F, a = F/T1, j = F/(T1 T2)) at
    corners; with ``limits`` every axis stays within it and the tolerance still holds."""
    from research.limits import AxisLimits
    from research.metrics import limit_ratios

    path = named_path(name)
    limits = AxisLimits.fir_envelope(2, 250.0, PAPER_DELAYS)
    plain = fir_interpolate(path, 250.0, PAPER_DELAYS, 0.5)
    held = plan_fir(path, 250.0, PAPER_DELAYS, 0.5, limits=limits).trajectory(1e-3)
    if name == "diamond":
        assert limit_ratios(plain, limits)["jerk"].max() == pytest.approx(np.sqrt(2), rel=1e-6)
    ratios = limit_ratios(held, limits)
    assert all(np.all(r <= 1 + 1e-6) for r in ratios.values())
    assert np.max(corner_errors(held, path)) <= 0.5 * (1 + 1e-6)
    assert float(held.duration) >= float(plain.duration) - 1e-12  # holding the limits costs time


def test_feed_caps_for_short_blocks():
    """A block shorter than T1 + T2 in time doubles its jerk, so its feed cap halves (or the
    block is slowed until it is long enough, whichever is faster)."""
    from research.interpolators._fir_limits import feed_caps
    from research.limits import AxisLimits

    T1, T2 = PAPER_DELAYS
    limits = AxisLimits.uniform(1, 1e9, 1e9, 1000.0)
    long_cap = 1000.0 * T1 * T2
    caps = feed_caps(np.array([100.0, 2.0]), np.array([[1.0], [1.0]]), PAPER_DELAYS, limits)
    assert caps[0] == pytest.approx(long_cap)  # 100 mm: long at this feed
    assert caps[1] == pytest.approx(max(0.5 * long_cap, 2.0 / (T1 + T2)))
    with pytest.raises(ParameterError, match="needs at least two FIR filters"):
        feed_caps(np.array([1.0]), np.array([[1.0]]), [0.1], limits)
