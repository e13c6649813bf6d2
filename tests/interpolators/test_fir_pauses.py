"""Pauses in ``plan_fir`` (G4 dwells, M0/M1 stops): exact stops held for their duration.

Expected values are independent of the joining code: the plans of the program's parts, each
planned alone by ``plan_fir`` without pauses (a stop decouples the two sides: eq 11 with
``T_k = 0``, each block's filtered pulse lasting ``T_v + T_d``, eq 6), plus the dwells; and
properties of the sampled trajectory (at rest on the vertex during a hold, within eps of every
other vertex).
"""

import jax
import numpy as np
import pytest

from research.errors import ParameterError
from research.interpolators import plan_fir
from research.paths import Polyline
from research.paths.library import random_program
from research.paths.toolpath import ToolPath

DELAYS = (0.06, 0.03)
EPS = 0.05
ZIGZAG = Polyline([[0, 0], [10, 0], [20, 5], [20, 15], [30, 15], [30.5, 15.2]])


def _nan(n, **at):
    p = np.full(n, np.nan)
    for k, v in at.items():
        p[int(k[1:])] = v
    return p


def test_no_pauses_is_the_plan_without_them():
    """All-NaN pauses give the very same plan as ``pauses=None``."""
    a = plan_fir(ZIGZAG, 100.0, DELAYS, EPS)
    b = plan_fir(ZIGZAG, 100.0, DELAYS, EPS, pauses=np.full(6, np.nan))
    for name in ("start_times", "overlaps", "feeds", "corner_times"):
        np.testing.assert_array_equal(getattr(b, name), getattr(a, name))
    assert float(b.cycle_time) == float(a.cycle_time)


def test_interior_pause_is_the_parts_planned_alone_plus_the_dwell():
    """A 0.5 s dwell at vertex 2 and an M0-like 0 s stop at vertex 4: the cycle time is the sum of the
    three parts' own plans (planned separately here) plus 0.5 s; the stops have T_k = 0 and zero corner
    error; the trajectory rests on vertex 2 for 0.5 s (speed 0, position the vertex)."""
    pauses = _nan(6, v2=0.5, v4=0.0)
    plan = plan_fir(ZIGZAG, 100.0, DELAYS, EPS, pauses=pauses)
    pts = ZIGZAG.points
    parts = [plan_fir(Polyline(pts[a:b + 1]), 100.0, DELAYS, EPS) for a, b in ((0, 2), (2, 4), (4, 5))]
    assert float(plan.cycle_time) == pytest.approx(sum(float(p.cycle_time) for p in parts) + 0.5, rel=1e-13)
    np.testing.assert_array_equal(np.asarray(plan.overlaps)[[1, 3]], 0.0)
    err = np.asarray(plan.corner_errors)
    assert err[1] <= 1e-9 and err[3] <= 1e-9
    assert np.all(err <= EPS * (1 + 1e-9) + 1e-9)
    np.testing.assert_array_equal(np.asarray(plan.feeds), np.concatenate([np.asarray(p.feeds) for p in parts]))
    tr = plan.trajectory(1e-3)
    t, q, v = np.asarray(tr.t), np.asarray(tr.q), np.asarray(tr.v)
    reach = float(plan.corner_times[1])
    hold = (t > reach + 1e-9) & (t < reach + 0.5 - 1e-9)
    assert hold.sum() >= 498
    np.testing.assert_allclose(q[hold], np.broadcast_to(pts[2], q[hold].shape), atol=1e-9)
    assert np.max(np.abs(v[hold])) <= 1e-9


def test_start_and_end_pauses_hold_the_end_points():
    """1 s before the first move and 2 s after the last: the cycle time grows by 3 s, the trajectory
    holds the start point for the first second and the end point for the last two."""
    base = plan_fir(ZIGZAG, 100.0, DELAYS, EPS)
    plan = plan_fir(ZIGZAG, 100.0, DELAYS, EPS, pauses=_nan(6, v0=1.0, v5=2.0))
    assert float(plan.cycle_time) == pytest.approx(float(base.cycle_time) + 3.0, rel=1e-13)
    tr = plan.trajectory(1e-3)
    t, q = np.asarray(tr.t), np.asarray(tr.q)
    np.testing.assert_allclose(q[t <= 1.0], np.broadcast_to(ZIGZAG.points[0], q[t <= 1.0].shape), atol=1e-12)
    tail = t >= float(plan.cycle_time) - 2.0
    np.testing.assert_allclose(q[tail], np.broadcast_to(ZIGZAG.points[-1], q[tail].shape), atol=1e-9)


@pytest.mark.parametrize("seed", range(12))
def test_property_random_programs_with_pauses(seed):
    """Seeded random programs (lines and arcs) with pauses at random vertices: the cycle time is the
    parts' own plans plus the dwells, every other corner and the sampled path stay within eps, and
    the trajectory ends on the program's end point."""
    rng = np.random.default_rng(1000 + seed)
    tp = random_program(rng, arcs=bool(seed % 2))
    M = tp.n_blocks
    pauses = np.where(rng.random(M + 1) < 0.4, rng.choice([0.0, 0.1, 1.0], M + 1), np.nan)
    feed = float(rng.uniform(20.0, 300.0))
    plan = plan_fir(tp, feed, DELAYS, EPS, pauses=pauses)
    cuts = [0, *[k for k in range(1, M) if not np.isnan(pauses[k])], M]
    parts = [plan_fir(tp.part(a, b), feed, DELAYS, EPS) for a, b in zip(cuts[:-1], cuts[1:])]
    dwell = float(np.nansum(pauses))
    assert float(plan.cycle_time) == pytest.approx(sum(float(p.cycle_time) for p in parts) + dwell, rel=1e-12)
    assert np.all(np.asarray(plan.corner_errors) <= EPS * (1 + 1e-9) + 1e-9)
    assert plan.path_deviation <= EPS * (1 + 1e-9) + 1e-9
    tr = plan.trajectory(1e-3)
    np.testing.assert_allclose(np.asarray(tr.q)[-1], tp.ends[-1], atol=1e-9)


def test_gradient_is_the_sum_of_the_parts_gradients():
    """d(cycle time)/dF through a paused plan: the parts' gradients summed (the dwell is constant)."""
    pts = ZIGZAG.points
    pauses = _nan(6, v3=0.25)
    g = jax.grad(lambda F: plan_fir(ZIGZAG, F, DELAYS, EPS, pauses=pauses).cycle_time)(100.0)
    parts = lambda F: (plan_fir(Polyline(pts[:4]), F, DELAYS, EPS).cycle_time  # noqa: E731
                       + plan_fir(Polyline(pts[3:]), F, DELAYS, EPS).cycle_time)
    assert float(g) == pytest.approx(float(jax.grad(parts)(100.0)), rel=1e-12)


def test_per_block_feeds_and_tolerances_are_cut_with_the_program():
    """Per-block feeds and tolerances go to their parts: the same as planning each part with its
    own slice."""
    feeds = np.array([50.0, 80.0, 120.0, 60.0, 90.0])
    tols = np.array([0.01, 0.05, 0.02, 0.1, 0.03])
    plan = plan_fir(ZIGZAG, feeds, DELAYS, tols, pauses=_nan(6, v2=0.0))
    tp = ToolPath.from_polyline(ZIGZAG)
    a = plan_fir(tp.part(0, 2), feeds[:2], DELAYS, tols[:2])
    b = plan_fir(tp.part(2, 5), feeds[2:], DELAYS, tols[2:])
    assert float(plan.cycle_time) == pytest.approx(float(a.cycle_time) + float(b.cycle_time), rel=1e-13)


@pytest.mark.parametrize("pauses, match", [
    (np.full(5, np.nan), r"pauses must have shape \(M \+ 1,\) = \(6,\)"),
    (_nan(6, v2=-1.0), r"pauses\[2\] = -1.0: expected NaN \(no pause\) or a finite dwell >= 0 s"),
    (_nan(6, v0=np.inf), r"pauses\[0\] = inf"),
])
def test_bad_pauses_are_refused(pauses, match):
    with pytest.raises(ParameterError, match=match):
        plan_fir(ZIGZAG, 100.0, DELAYS, EPS, pauses=pauses)
