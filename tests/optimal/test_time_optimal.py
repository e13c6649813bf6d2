"""Time-optimal reference (issue 6): it must beat the interpolators it measures, keep the tube and
the limits between grid points, start and end at rest, and reproduce the 1-D S-curve optimum."""

import dataclasses

import numpy as np
import pytest

from research import metrics
from research.errors import InfeasibleProblem, ParameterError
from research.interpolators import fir_interpolate, scurve_interpolate, scurve_profile
from research.limits import AxisLimits
from research.optimal import TimeOptimalResult, phase_boundaries, time_optimal
from research.paths.library import corner90, diamond
from research.paths.polyline import Polyline

# Sencer 2015 §4 / Fig 6: F = 250 mm/s, T1 = 148 ms, T2 = 89 ms, eps = 500 um
F, DELAYS, EPS = 250.0, (0.148, 0.089), 0.5
LIMITS = AxisLimits.fir_envelope(2, F, DELAYS)  # nominal envelope v = F, a = F/T1, j = F/(T1 T2)
PATHS = {"corner90": corner90(), "diamond": diamond()}


@pytest.fixture(scope="module")
def solutions() -> dict[str, TimeOptimalResult]:
    return {name: time_optimal(path, LIMITS, EPS, feed=F) for name, path in PATHS.items()}


@pytest.mark.parametrize("name", PATHS)
def test_ocp_beats_fir_overlap_and_scurve_exact_stop(solutions, name):
    path, res = PATHS[name], solutions[name]
    fir = float(fir_interpolate(path, F, DELAYS, EPS).duration)
    scurve = float(scurve_interpolate(path, F, LIMITS).duration)
    assert res.status == "Solve_Succeeded"
    assert res.cycle_time <= fir
    assert res.cycle_time <= scurve
    # the reference is not trivially slow either: it cuts the corners within the tube
    assert res.cycle_time < 0.99 * fir
    assert res.cycle_time == pytest.approx(float(res.trajectory.duration), rel=1e-12)
    assert res.phase_durations.shape == (path.n_segments,)


@pytest.mark.parametrize("name", PATHS)
def test_resampled_solution_keeps_tube_and_limits_within_one_percent(solutions, name):
    path, res = PATHS[name], solutions[name]
    traj = res.trajectory
    # independent check on the exact profile (metrics refine extrema between samples)
    assert metrics.max_contour_error(traj, path) <= 1.01 * EPS
    for kind, ratio in metrics.limit_ratios(traj, LIMITS).items():
        assert np.all(ratio <= 1.01), (kind, ratio)
    assert metrics.peak_feed(traj) <= 1.01 * F
    # the dense verification the result carries agrees, and the tube is actually used
    v = res.verification
    assert v.worst_ratio <= 1.01
    assert v.deviation_ratio > 0.9
    # corners: the trajectory passes each vertex within eps
    assert np.all(metrics.corner_errors(traj, path) <= 1.01 * EPS)


@pytest.mark.parametrize("name", PATHS)
def test_starts_and_ends_at_rest_on_the_path_ends(solutions, name):
    path, traj = PATHS[name], solutions[name].trajectory
    for t, point in ((0.0, path.points[0]), (float(traj.duration), path.points[-1])):
        np.testing.assert_allclose(traj.evaluate(np.array([t]))[0], point, atol=1e-6)
        for nu in (1, 2):
            np.testing.assert_allclose(traj.evaluate(np.array([t]), nu)[0], 0.0, atol=1e-6)
    np.testing.assert_allclose(np.asarray(traj.v[-1]), 0.0, atol=1e-9)


def test_profile_is_piecewise_cubic_with_continuous_state():
    res = time_optimal(corner90(), LIMITS, EPS, feed=F, intervals_per_segment=12)
    pp = res.trajectory.exact
    assert pp.coeffs.shape == (2 * 12, 4, 2)  # one cubic per interval: piecewise-constant jerk
    b = np.asarray(pp.breaks)[1:-1]
    for nu in range(3):  # position, velocity, acceleration continuous at every break
        left, right = pp(b - 1e-10, nu), pp(b + 1e-10, nu)
        scale = (100.0, F, LIMITS.acceleration[0])[nu]
        assert np.max(np.abs(np.asarray(left - right))) < 1e-6 * scale


def test_single_segment_reproduces_the_scurve_optimum():
    """1-D sanity: on a straight line the tube is irrelevant and the time-optimal rest-to-rest
    motion is the seven-phase S-curve; the OCP's switching times fall between grid points, so it
    is a little slower (by the discretisation)."""
    v, a, j = 250.0, F / DELAYS[0], F / (DELAYS[0] * DELAYS[1])
    line = Polyline([[0.0], [100.0]])
    optimum = float(scurve_profile(100.0, v, a, j).end)
    res = time_optimal(line, AxisLimits.uniform(1, v, a, j), EPS, intervals_per_segment=24)
    assert optimum <= res.cycle_time * (1 + 1e-6)
    assert res.cycle_time == pytest.approx(optimum, rel=0.01)
    # finer grid, closer to the continuous optimum
    finer = time_optimal(line, AxisLimits.uniform(1, v, a, j), EPS, intervals_per_segment=48)
    assert optimum <= finer.cycle_time * (1 + 1e-6) < res.cycle_time


def test_zero_tolerance_is_the_exact_stop_scurve():
    res = time_optimal(corner90(), LIMITS, 0.0, feed=F)
    scurve = scurve_interpolate(corner90(), F, LIMITS)
    assert res.status == "exact stop"
    assert res.cycle_time == pytest.approx(float(scurve.duration), rel=1e-12)
    np.testing.assert_allclose(np.cumsum(res.phase_durations)[:-1], phase_boundaries(scurve, corner90())[1:-1], atol=1e-9)


def test_fir_warm_start_reaches_the_same_optimum(solutions):
    fir = fir_interpolate(diamond(), F, DELAYS, EPS)
    res = time_optimal(diamond(), LIMITS, EPS, feed=F, warm_start=fir)
    assert res.status == "Solve_Succeeded"
    assert res.cycle_time == pytest.approx(solutions["diamond"].cycle_time, rel=1e-3)


def test_phase_boundaries_of_an_exact_stop_are_the_block_ends():
    path = diamond()
    scurve = scurve_interpolate(path, F, LIMITS)
    times = phase_boundaries(scurve, path)
    # each block is a rest-to-rest S-curve: the vertex is reached at the end of its block
    along = np.array([LIMITS.along(u) for u in path.directions])
    blocks = np.array([float(scurve_profile(L, min(F, va), aa, ja).end) for L, (va, aa, ja) in zip(path.lengths, along)])
    np.testing.assert_allclose(times, np.concatenate([[0.0], np.cumsum(blocks)]), atol=1e-9)


def test_three_axis_tube():
    path = Polyline([[0.0, 0.0, 0.0], [30.0, 0.0, 10.0], [30.0, 40.0, 0.0]])
    lim = AxisLimits.fir_envelope(3, F, DELAYS)
    res = time_optimal(path, lim, 0.2, feed=F, intervals_per_segment=16)
    assert res.status == "Solve_Succeeded"
    assert res.verification.worst_ratio <= 1.01
    assert metrics.max_contour_error(res.trajectory, path) <= 1.01 * 0.2
    assert res.cycle_time < float(scurve_interpolate(path, F, lim).duration)


def test_result_is_immutable(solutions):
    res = solutions["corner90"]
    with pytest.raises(dataclasses.FrozenInstanceError):
        res.status = "x"
    with pytest.raises(ValueError):
        res.phase_durations[0] = 0.0


# -- infeasible and malformed input ---------------------------------------------------------------
def test_negative_tolerance_is_infeasible():
    with pytest.raises(InfeasibleProblem, match="tolerance") as info:
        time_optimal(corner90(), LIMITS, -0.1, feed=F)
    assert info.value.constraint == "tolerance tube"
    assert info.value.status == "not solved"


def test_non_positive_feed_is_infeasible():
    with pytest.raises(InfeasibleProblem, match="feed") as info:
        time_optimal(corner90(), LIMITS, EPS, feed=0.0)
    assert info.value.constraint == "feed limit"


def test_ipopt_infeasibility_is_reported_with_diagnostics():
    """One constant-jerk interval per segment cannot bring a corner move to rest within 1 um of
    the vertices: IPOPT proves local infeasibility and the error says where."""
    with pytest.raises(InfeasibleProblem, match="Infeasible_Problem_Detected") as info:
        time_optimal(corner90(), LIMITS, 1e-3, feed=F, intervals_per_segment=1)
    err = info.value
    assert err.status == "Infeasible_Problem_Detected"
    assert err.segment in (0, 1)
    assert err.constraint and err.violation > 0
    assert "segment" in str(err)


@pytest.mark.parametrize(
    "kwargs, match",
    [
        ({"limits": AxisLimits.uniform(3, 1.0, 1.0, 1.0)}, "axes"),
        ({"limits": AxisLimits.uniform(2, 250.0, 1000.0)}, "finite jerk"),
        ({"tolerance": float("nan")}, "tolerance"),
        ({"intervals_per_segment": 0}, "intervals_per_segment"),
        ({"window": 2, "overlap": 2, "path": diamond()}, "overlap"),
        ({"warm_start": scurve_interpolate(Polyline([[0.0, 0.0], [1.0, 1.0]]), F, LIMITS)}, "warm_start"),
    ],
)
def test_bad_input_raises_parameter_error(kwargs, match):
    args = {"path": corner90(), "limits": LIMITS, "tolerance": EPS, **kwargs}
    with pytest.raises(ParameterError, match=match):
        time_optimal(args.pop("path"), args.pop("limits"), args.pop("tolerance"), feed=F, **args)
