"""Jerk-limited S-curve baseline: time-optimal rest-to-rest (against ruckig), limits, exact stops."""

import numpy as np
import pytest

from research.errors import ParameterError
from research.interpolators import scurve_interpolate, scurve_phases, scurve_profile
from research.limits import AxisLimits
from research.metrics import corner_errors, limit_ratios
from research.paths import Polyline, named_path

CASES = [  # (L, V, A, J): V and A reached; A reached, V not; neither; V reached without A
    (100.0, 250.0, 2000.0, 3e4),
    (10.0, 250.0, 2000.0, 3e4),
    (0.01, 250.0, 2000.0, 3e4),
    (50.0, 1000.0, 100.0, 1e6),
    (100.0, 50.0, 2000.0, 3e4),
]


@pytest.mark.parametrize("L, V, A, J", CASES)
def test_duration_matches_ruckig(L, V, A, J):
    """The seven-phase profile is the time-optimal rest-to-rest move: same duration as ruckig."""
    ruckig = pytest.importorskip("ruckig")
    inp = ruckig.InputParameter(1)
    inp.current_position, inp.target_position = [0.0], [L]
    inp.max_velocity, inp.max_acceleration, inp.max_jerk = [V], [A], [J]
    out = ruckig.Trajectory(1)
    assert ruckig.Ruckig(1).calculate(inp, out) == ruckig.Result.Working
    s = scurve_profile(L, V, A, J)
    assert float(s.end) == pytest.approx(out.duration, rel=1e-9)


@pytest.mark.parametrize("L, V, A, J", CASES)
def test_profile_limits_and_end(L, V, A, J):
    s = scurve_profile(L, V, A, J)
    t = np.linspace(0.0, float(s.end), 4001)
    assert float(s.end_values()[0]) == pytest.approx(L, rel=1e-12)
    assert np.max(np.abs(np.asarray(s(t, 1)))) <= V * (1 + 1e-12)
    assert np.max(np.abs(np.asarray(s(t, 2)))) <= A * (1 + 1e-12)
    assert np.max(np.abs(np.asarray(s(t, 3)))) <= J * (1 + 1e-12)
    Tj, Ta, Tv = scurve_phases(L, V, A, J)
    assert float(2 * Ta + Tv) == pytest.approx(float(s.end), rel=1e-12)


def test_path_respects_axis_limits_and_stops_at_corners():
    path = named_path("zigzag")
    limits = AxisLimits([200.0, 100.0], [2000.0, 1000.0], [3e4, 2e4])
    traj = scurve_interpolate(path, 250.0, limits, sample_period=1e-3)
    assert all(np.all(r <= 1 + 1e-9) for r in limit_ratios(traj, limits).values())
    assert np.max(corner_errors(traj, path)) < 1e-9  # exact stop: passes through every vertex
    assert np.max(np.abs(traj.q[-1] - path.points[-1])) < 1e-9
    # time-optimal per block: on these 11.2 mm diagonals acceleration never saturates
    # (2 A^3 / J^2 = 19.9 mm > L), so X's jerk is the binding limit
    ratios = limit_ratios(traj, limits)
    assert ratios["jerk"][0] == pytest.approx(1.0, rel=1e-9)
    assert ratios["acceleration"].max() < 1.0


def test_bad_input():
    with pytest.raises(ParameterError, match="length must be finite and > 0"):
        scurve_profile(0.0, 1.0, 1.0, 1.0)
    with pytest.raises(ParameterError, match="finite jerk"):
        scurve_interpolate(named_path("corner90"), 100.0, AxisLimits.uniform(2, 100.0, 1000.0))
    with pytest.raises(ParameterError, match="limits have 3 axes"):
        scurve_interpolate(named_path("corner90"), 100.0, AxisLimits.uniform(3, 100.0, 1000.0, 1e4))
    with pytest.raises(ParameterError, match="feed must be finite"):
        scurve_interpolate(Polyline([[0.0, 0.0], [1.0, 0.0]]), -1.0, AxisLimits.uniform(2, 100.0, 1000.0, 1e4))


def test_pauses_hold_the_vertices_and_add_their_dwell():
    """Dwells of 0.5 s at the start, 0.25 s at vertex 2 and 1 s at the end: the motion is the same
    rest-to-rest moves (it already stops at every vertex), held still on each paused vertex, so the
    duration is the one without pauses plus 1.75 s and the samples in each hold sit on its vertex at
    rest. A negative dwell is refused by name."""
    path = Polyline([[0, 0], [10, 0], [10, 10], [0, 10]])
    limits = AxisLimits.uniform(2, 200.0, 2000.0, 1e5)
    base = scurve_interpolate(path, 100.0, limits)
    pauses = np.array([0.5, np.nan, 0.25, 1.0])
    tr = scurve_interpolate(path, 100.0, limits, pauses=pauses)
    assert float(tr.duration) == pytest.approx(float(base.duration) + 1.75, rel=1e-12)
    t, q, v = np.asarray(tr.t), np.asarray(tr.q), np.asarray(tr.v)
    first = t < 0.5 - 1e-9
    np.testing.assert_allclose(q[first], 0.0, atol=1e-12)
    # the second move ends at the base's second-move end, shifted by the start dwell
    t2 = 0.5 + float(base.t[np.argmin(np.linalg.norm(np.asarray(base.q) - [10, 10], axis=1))])
    hold = (t > t2 + 2e-3) & (t < t2 + 0.25 - 2e-3)
    assert hold.sum() >= 240
    np.testing.assert_allclose(q[hold], np.broadcast_to([10.0, 10.0], q[hold].shape), atol=1e-9)
    assert np.max(np.abs(v[hold])) <= 1e-9
    with pytest.raises(ParameterError, match=r"pauses\[1\] = -1.0"):
        scurve_interpolate(path, 100.0, limits, pauses=[np.nan, -1.0, np.nan, np.nan])
