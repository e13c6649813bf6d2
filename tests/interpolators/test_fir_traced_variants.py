"""A traced ``plan_fir`` (``jax.grad``, ``jax.jvp``) is the traced form of the plan an untraced call
returns, also where that plan is not the path as written: straight runs of collinear lines planned
as one block, lines cut into ramp steps under axis limits (``_fir_straight``).

Regression (measured before the fix): a raster of lines split at their midpoints under limits below
the FIR envelope planned in 2.728 s untraced (ramp pieces) and 3.78 s traced (the path as written),
so ``jax.value_and_grad`` reported the value and the derivative of another plan. References: the
untraced plan's own arrays (values) and central differences of the untraced cycle time (derivatives,
where no decision changes over the step: no limits, so no ramp cut points move)."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from research.interpolators import fir, plan_fir
from research.limits import AxisLimits
from research.paths import Polyline

DELAYS = (0.02, 0.01)


def _split_raster(rng, rows=3):
    """A raster of ``rows`` lines (10-30 mm) joined by 1-3 mm steps, each line cut at 1-3 random
    points (computed in floating point: off the line by rounding only)."""
    pts, y = [np.zeros(2)], 0.0
    for r in range(rows):
        x0, x1 = pts[-1][0], (rng.uniform(10.0, 30.0) if r % 2 == 0 else 0.0)
        for u in np.sort(rng.uniform(0.1, 0.9, int(rng.integers(1, 4)))):
            pts.append(np.array([x0 + u * (x1 - x0), y]))
        pts.append(np.array([x1, y]))
        y += rng.uniform(1.0, 3.0)
        pts.append(np.array([x1, y]))
    return Polyline(np.array(pts[:-1]))


def _plan_arrays(plan):
    return (plan.cycle_time, plan.start_times, plan.pulse_times, plan.overlaps, plan.feeds, plan.corner_times)


@pytest.mark.parametrize("seed", range(4))
def test_traced_plan_is_the_untraced_plan_under_limits(seed):
    """Under limits below the envelope the untraced plan is a merged or ramp-cut one (checked: faster
    than the path as written); the primal outputs of ``jax.jvp`` through the feed, the tolerance and
    the delays equal its cycle time, pulse starts and lengths, overlaps, feeds and corner instants
    (1e-12 relative), and the tangents are finite."""
    rng = np.random.default_rng(seed)
    path = _split_raster(rng)
    feed, tol = float(rng.uniform(60.0, 120.0)), float(rng.uniform(0.01, 0.1))
    # jerk far below the envelope F / (T1 T2) >= 3e5 mm/s^3: ramp steps of dV = J T1 T2 = 4 or 12 mm/s
    lim = AxisLimits.uniform(2, 150.0, 3000.0, 2e4 if seed % 2 == 0 else 6e4)
    plain = plan_fir(path, feed, DELAYS, tol, limits=lim)
    as_written = fir._plan_blocks(fir._as_toolpath(path), feed, np.array(DELAYS), tol, True, lim, fir.CHECK_PERIOD,
                                  False, False)[0]
    assert float(plain.cycle_time) < float(as_written.cycle_time) * (1.0 - 1e-3)

    def arrays(F, eps, d):
        return _plan_arrays(plan_fir(path, F, d, eps, limits=lim))

    primals, tangents = jax.jvp(arrays, (feed, tol, jnp.array(DELAYS)), (1.0, 1.0, jnp.ones(2)))
    for got, want in zip(primals, _plan_arrays(plain)):
        np.testing.assert_allclose(np.asarray(got), np.asarray(want), rtol=1e-12, atol=1e-12)
    assert all(np.all(np.isfinite(np.asarray(t))) for t in tangents)


@pytest.mark.parametrize("seed", range(3))
def test_gradients_through_merged_runs_match_central_differences(seed):
    """Without limits the split raster plans as its merged runs. ``jax.grad`` of the cycle time with
    respect to a scalar feed, to per-block feeds (summed: the same direction) and to the delays
    matches central differences of the untraced plan (1e-6 relative), and the per-block gradient is
    spread evenly over the blocks of one run (each has its share of the merged block's sensitivity)."""
    rng = np.random.default_rng(10 + seed)
    path = _split_raster(rng)
    M = path.points.shape[0] - 1
    feed, tol = float(rng.uniform(60.0, 120.0)), float(rng.uniform(0.01, 0.1))
    d0 = jnp.array([0.02031, 0.01017])

    def cycle(F, d):
        return plan_fir(path, F, d, tol).cycle_time

    h = 1e-5
    fd_feed = (float(cycle(feed + h, d0)) - float(cycle(feed - h, d0))) / (2 * h)
    np.testing.assert_allclose(float(jax.grad(cycle)(feed, d0)), fd_feed, rtol=1e-6)
    per_block = np.asarray(jax.grad(cycle)(jnp.full(M, feed), d0))
    np.testing.assert_allclose(per_block.sum(), fd_feed, rtol=1e-6)
    run = fir.straight_runs(fir._as_toolpath(path), np.full(M, feed), np.full(M, tol))
    assert run is not None and run[-1] + 1 < M  # some blocks merge
    for r in range(int(run[-1]) + 1):
        np.testing.assert_allclose(per_block[run == r], per_block[run == r][0], rtol=1e-12)
    hd = 1e-7
    fd_d = [(float(cycle(feed, d0.at[i].add(hd))) - float(cycle(feed, d0.at[i].add(-hd)))) / (2 * hd) for i in range(2)]
    np.testing.assert_allclose(np.asarray(jax.grad(cycle, argnums=1)(feed, d0)), fd_d, rtol=1e-6)


def test_traced_plain_plan_first_under_loose_limits():
    """Where the plan without limits keeps the limits (a 2 deg chord circle, R 20 mm, at F 200 mm/s
    under its FIR envelope: every step alone within them), ``plan_fir(..., limits=...)`` returns that
    plan; traced, it is the same plan with the same derivatives: ``jax.jvp`` through the feed, the
    tolerance and the delays gives the primal outputs and tangents of the call without limits
    (T 60/30 ms: the plan is tolerance-bound, its peaks 0.36-0.37 of the envelope's)."""
    th = np.radians(np.arange(0.0, 360.0 + 1e-9, 2.0))
    circle = Polyline(20.0 * np.column_stack([np.cos(th), np.sin(th)]))
    delays = (0.06, 0.03)
    env = AxisLimits.fir_envelope(2, 200.0, delays)

    def arrays(F, eps, d, lim):
        return _plan_arrays(plan_fir(circle, F, d, eps, limits=lim))

    args, dirs = (200.0, 0.05, jnp.array(delays)), (1.0, 1.0, jnp.ones(2))
    (p0, t0), (p1, t1) = (jax.jvp(lambda *a: arrays(*a, lim), args, dirs) for lim in (None, env))
    for a, b in zip(p0 + t0, p1 + t1):
        np.testing.assert_array_equal(np.asarray(a), np.asarray(b))
