"""Receding-window solution (Sencer 2009 thesis §3.5) against the whole-path NLP."""

from itertools import pairwise

import numpy as np
import pytest

from research.errors import ParameterError
from research.limits import AxisLimits
from research.optimal import time_optimal, window_schedule
from research.optimal._windowing import braking_distance
from research.paths import Polyline
from research.paths.library import zigzag

LIMITS = AxisLimits.fir_envelope(2, 250.0, (0.148, 0.089))
# The look-ahead (3 segments of 11.2 mm) exceeds the ~30 mm S-curve braking distance at 250 mm/s,
# so the terminal stop of each window does not reach back into the committed segments: the two
# solutions should agree to the NLP tolerance; the test allows 0.1 %.
WINDOW_RTOL = 1e-3


def test_schedule_covers_the_path_with_overlap():
    sched = window_schedule(11, 6, 3)
    assert sched == [(0, 6, 3), (3, 9, 6), (6, 11, 11)]
    assert window_schedule(11, None, 3) == [(0, 11, 11)]
    assert window_schedule(4, 6, 3) == [(0, 4, 4)]
    # committed parts tile the path
    for (_, _, commit), (first, _, _) in pairwise(sched):
        assert commit == first


@pytest.fixture(scope="module")
def whole_and_windowed():
    path = zigzag(12)  # 11 segments, 10 corners of 53 deg
    kw = {"feed": 250.0, "intervals_per_segment": 16}
    return path, time_optimal(path, LIMITS, 0.5, **kw), time_optimal(path, LIMITS, 0.5, window=6, overlap=3, **kw)


def test_windowed_matches_whole_path(whole_and_windowed):
    _, whole, windowed = whole_and_windowed
    assert len(whole.windows) == 1 and len(windowed.windows) == 3
    assert windowed.cycle_time == pytest.approx(whole.cycle_time, rel=WINDOW_RTOL)
    assert windowed.cycle_time >= whole.cycle_time * (1 - 1e-6)  # a window cannot beat the whole NLP
    np.testing.assert_allclose(windowed.phase_durations, whole.phase_durations, rtol=10 * WINDOW_RTOL)
    assert windowed.verification.worst_ratio <= 1.01


def test_state_is_continuous_at_window_joints(whole_and_windowed):
    path, _, windowed = whole_and_windowed
    pp = windowed.trajectory.exact
    N = windowed.intervals_per_segment
    joints = [w.committed_stop for w in windowed.windows[:-1]]
    t = np.concatenate([[0.0], np.cumsum(windowed.phase_durations)])[joints]
    for nu, scale in ((0, 100.0), (1, 250.0), (2, float(LIMITS.acceleration[0]))):
        jump = np.asarray(pp(t + 1e-10, nu) - pp(t - 1e-10, nu))
        assert np.max(np.abs(jump)) < 1e-6 * scale
    # the joints are mid-motion, not stops
    assert np.all(np.linalg.norm(np.asarray(pp(t, 1)), axis=1) > 10.0)
    assert pp.coeffs.shape[0] == N * path.n_segments


def test_lookahead_commits_only_where_that_much_path_is_left():
    """With a look-ahead length every window but the last keeps at least that much of its own path
    after what it commits, commits as much as that allows (one more segment would leave less, or
    the ``overlap`` rule binds), and the committed parts tile the path."""
    rng = np.random.default_rng(5)
    lengths = rng.choice([0.25, 0.5, 1.0, 4.0], size=200)
    cum = np.concatenate([[0.0], np.cumsum(lengths)])
    sched = window_schedule(200, 40, 4, lengths, 9.0)
    assert sched[0][0] == 0 and sched[-1][1:] == (200, 200)
    for (_, _, commit), (first, _, _) in pairwise(sched):
        assert commit == first
    for first, stop, commit in sched[:-1]:
        assert first < commit <= stop - 4
        assert cum[stop] - cum[commit] >= 9.0
        assert commit == stop - 4 or cum[stop] - cum[commit + 1] < 9.0
    assert window_schedule(11, 6, 3, np.ones(11), 0.0) == window_schedule(11, 6, 3)


def test_lookahead_longer_than_the_window_is_refused():
    with pytest.raises(ParameterError, match="window of 10 segments from segment 0"):
        window_schedule(100, 10, 2, np.full(100, 0.5), 9.0)


@pytest.mark.parametrize("V", [50.0, 200.0])
def test_braking_distance_is_the_double_s_stop(V):
    """``braking_distance`` against a stop integrated step by step: jerk -J until the deceleration
    reaches A (or half the speed is gone), hold, then +J to rest (Biagiotti & Melchiorri 2008
    §3.4's double S), Euler steps of 1e-7 s. The two branches: 200 mm/s reaches A = 3,333 mm/s^2
    at J = 111,111 mm/s^3 (A^2 / J = 100 mm/s), 50 mm/s does not."""
    lim = AxisLimits.fir_envelope(3, 200.0, (0.06, 0.03))
    A, J = float(lim.acceleration[0]), float(lim.jerk[0])
    ap = min(A, np.sqrt(V * J))  # the deceleration reached
    t1 = ap / J  # ramp time
    t2 = max(V / ap - t1, 0.0)  # hold time: the speed lost in the two ramps is ap t1
    dt = 1e-7
    t = np.arange(0.0, 2 * t1 + t2, dt)
    a = -np.where(t < t1, J * t, np.where(t < t1 + t2, ap, ap - J * (t - t1 - t2)))
    v = V + np.cumsum(a) * dt
    assert abs(v[-1]) < 1e-2
    assert braking_distance(lim, V) == pytest.approx(float(np.sum(v) * dt), rel=1e-4)


def test_braking_lookahead_commits_what_the_whole_path_nlp_does_before_its_last_window():
    """A 30-chord arc of 0.5 mm chords (R 10 mm) at F 200 mm/s under the 60/30 ms envelope, window 24
    with the 9 mm braking look-ahead: the windows commit 5 chords each, whose terminal stop lies past
    the braking distance, so up to the last window the motion is the whole-path NLP's (time at its
    start within 3 %; a model prediction of the windowing, not a paper number); the last window, warm
    started from the previous one's stop, is slower (module docstring), and no window beats the whole."""
    a = np.linspace(0.0, 1.5, 31)
    path = Polyline(np.stack([10 * np.cos(a), 10 * np.sin(a)], axis=1))
    lim = AxisLimits.fir_envelope(2, 200.0, (0.06, 0.03))
    kw = {"feed": 200.0, "intervals_per_segment": 8}
    whole = time_optimal(path, lim, 0.05, **kw)
    windowed = time_optimal(path, lim, 0.05, window=24, overlap=4, lookahead="braking", **kw)
    last = windowed.windows[-1].first_segment
    assert [w.committed_stop - w.first_segment for w in windowed.windows[:-1]] == [5, 5]
    np.testing.assert_allclose(np.sum(windowed.phase_durations[:last]), np.sum(whole.phase_durations[:last]), rtol=0.03)
    assert windowed.cycle_time >= whole.cycle_time * (1 - 1e-6)


@pytest.mark.parametrize("bad", ["brake", -1.0, np.nan])
def test_bad_lookahead_is_named(bad):
    with pytest.raises(ParameterError, match="lookahead"):
        time_optimal(zigzag(5), LIMITS, 0.5, window=2, overlap=1, lookahead=bad)
