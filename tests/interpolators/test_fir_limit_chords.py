"""Chord chains under axis limits well below the FIR envelope: corners whose exact stop lowers
nothing are slowed, not stopped (``_fir_limits.futile_stops``, ``plan_fir``'s settle).

Regression (measured before the fix): circles of chords at 0.1-0.2x the envelope's acceleration and
jerk planned 1.7-2.0x slower than the whole circle run at one feed that keeps the limits, with
corners bisected into exact stops (the chord corners of bench_cam's quick file: 1.02-1.08 of a limit
at full overlap, up to 2.0 at half overlap, 118 exact stops). Reference, independent of the
limit-holding planner: the largest uniform commanded feed whose plain plan (no limits) keeps the
limits on its sampled trajectory (``metrics.limit_ratios``), found by bisection."""

import numpy as np
import pytest

from research.interpolators import plan_fir
from research.limits import AxisLimits
from research.metrics import corner_errors, limit_ratios
from research.paths import Polyline

DELAYS, FEED, EPS = (0.06, 0.03), 200.0, 0.05


def _circle(radius: float, step_deg: float) -> Polyline:
    th = np.radians(np.arange(0.0, 360.0 + 1e-9, step_deg))
    return Polyline(np.column_stack([radius * np.cos(th), radius * np.sin(th)]))


def _worst(plan, limits) -> float:
    return max(float(np.max(v)) for v in limit_ratios(plan.trajectory(1e-3), limits).values())


@pytest.mark.parametrize("radius,step_deg,scale", [(20.0, 1.5, 0.2), (10.0, 2.0, 0.2), (10.0, 2.0, 0.1), (40.0, 1.0, 0.2),
                                                    (40.0, 1.0, 0.1), (40.0, 1.0, 0.05)])
def test_chord_circle_no_slower_than_one_uniform_feed_that_keeps_the_limits(radius, step_deg, scale):
    """Limits held on the sampled trajectory (1e-6), corner errors within eps, no exact stop, and a
    cycle time no longer than the uniform-feed reference (before: 3.159 / 2.987 / 5.856 / 8.036 s
    against 3.261 / 1.712 / 3.261 / 6.388 s; the last two, before the candidates at the feeds of
    ``_fir_limits.end_ramp_scale``: 20.126 / 32.490 s against 12.689 / 25.253 s)."""
    path = _circle(radius, step_deg)
    env = AxisLimits.fir_envelope(2, FEED, DELAYS)
    limits = AxisLimits(env.velocity, scale * env.acceleration, scale * env.jerk)
    lo, hi = 1.0, FEED  # lo keeps the limits (a feed 200x below the envelope's), hi breaks them
    assert _worst(plan_fir(path, lo, DELAYS, EPS), limits) <= 1.0 < _worst(plan_fir(path, hi, DELAYS, EPS), limits)
    for _ in range(12):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if _worst(plan_fir(path, mid, DELAYS, EPS), limits) <= 1.0 else (lo, mid)
    uniform = float(plan_fir(path, lo, DELAYS, EPS).cycle_time)

    held = plan_fir(path, FEED, DELAYS, EPS, limits=limits)
    assert _worst(held, limits) <= 1.0 + 1e-6
    assert np.all(np.asarray(corner_errors(held.trajectory(1e-3), path)) <= EPS * (1 + 1e-6))
    assert np.all(np.asarray(held.overlaps) > 0.0)
    assert float(held.cycle_time) <= uniform
