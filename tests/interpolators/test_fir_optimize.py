"""Optimized FIR (``optimize_fir``, a named extension): its constraints on seeded random paths.

Every check is independent of the optimizer's own constraint functions: corner errors and path
deviation from the sampled trajectory (``research.metrics``), peaks sampled and refined
(``metrics.limit_ratios``), end points from the path, and the exact per-piece peaks of the NLP
against the planner's NumPy root finder (``_fir_piece_peaks.corner_peak_ratios``)."""

import jax.numpy as jnp
import numpy as np
import pytest

from research.errors import ParameterError, PathError
from research.interpolators import optimize_fir, plan_fir
from research.interpolators._fir_piece_peaks import corner_peak_ratios
from research.interpolators._fir_optimize import _piece_peak_ratios
from research.limits import AxisLimits
from research.metrics import corner_errors, limit_ratios, max_contour_error
from research.paths import Polyline
from research.paths.toolpath import ToolPath
from research.piecewise import NumpyPiecewise

from ._paths import turning_path

DELAYS = (0.06, 0.03)
F, EPS = 200.0, 0.1


def random_path(seed: int, n: int = 4) -> Polyline:
    """Seeded 2-D path of ``n`` segments of 4-15 mm turning by up to +-110 deg."""
    return turning_path(seed, n, (4.0, 15.0), 110.0)


@pytest.mark.parametrize("seed,starts", [(12, ("paper",)), (13, ("paper",)), (12, ("smooth",))])
def test_tolerance_limits_and_end_points_hold(seed, starts):
    """On random paths under limits below the FIR envelope, for the SLSQP and the smooth
    fixed-order search: every vertex and every sample within eps, every peak within its limit,
    start and end at the path's ends at rest, and never slower than the limit-holding plan_fir."""
    path = random_path(seed)
    rng = np.random.default_rng(seed)
    limits = AxisLimits(rng.uniform(0.7, 1.0, 2) * F, rng.uniform(0.7, 1.0, 2) * F / DELAYS[0],
                        rng.uniform(0.7, 1.0, 2) * F / (DELAYS[0] * DELAYS[1]))
    plan = optimize_fir(path, F, DELAYS, EPS, limits, max_iter=25, starts=starts, rounds=2)
    tr = plan.trajectory(1e-3)
    assert np.max(corner_errors(tr, path)) <= EPS * (1 + 1e-6)
    assert max_contour_error(tr, path) <= EPS * (1 + 1e-6)
    assert all(np.all(r <= 1 + 1e-6) for r in limit_ratios(tr, limits).values())
    q, v = np.asarray(tr.q), np.asarray(tr.v)
    np.testing.assert_allclose(q[0], path.points[0], atol=1e-9)
    np.testing.assert_allclose(q[-1], path.points[-1], atol=1e-9)
    np.testing.assert_allclose(v[[0, -1]], 0.0, atol=1e-9)
    held = plan_fir(path, F, DELAYS, EPS, limits=limits)
    assert float(plan.cycle_time) <= float(held.cycle_time) * (1 + 1e-12)


def test_smooth_search_keeps_the_beams_quiet():
    """With structural modes, the smooth search's plan leaves each mode's residual vibration at
    most the plain FIR's (re-simulated by ``optimal.trajectory_vibration`` on the sampled exact
    profile, independently of the search's closed form), holds the envelope and the tolerance."""
    from research.optimal import StructuralMode, trajectory_vibration

    path = random_path(15, n=3)
    limits = AxisLimits.fir_envelope(2, F, DELAYS)
    modes = (StructuralMode(0, 11.4, 0.02), StructuralMode(1, 6.8, 0.02))
    plan, info = optimize_fir(path, F, DELAYS, EPS, limits, starts=("smooth",), rounds=2, modes=modes, full_output=True)
    plain = plan_fir(path, F, DELAYS, EPS)
    left = trajectory_vibration(plan.trajectory(1e-3), modes)[0]
    ref = trajectory_vibration(plain.trajectory(1e-3), modes)[0]
    assert info["quiet"] and np.all(left <= ref * (1 + 1e-5) + 1e-9)
    tr = plan.trajectory(1e-3)
    assert np.max(corner_errors(tr, path)) <= EPS * (1 + 1e-6)
    assert all(np.all(r <= 1 + 1e-6) for r in limit_ratios(tr, limits).values())
    assert info["runs"][0]["start"] == "smooth" and info["runs"][0]["rounds"]


def test_never_slower_than_the_plain_plan_where_it_holds_the_limits_and_the_residual():
    """The optimality study's convention (a): limits are the plain FIR's own peaks and the residual
    bound its own residual (Sencer 2015 beams), so the plain ``plan_fir`` plan is admissible. On
    the 6-block ``cam_like_path(6, seed=1)`` at the study's setting the smooth search verified only
    a slower plan (0.6936 s) and the limit-holding plan (0.6268 s) rings more on Y (20.5 against
    15.7 um), so 0.6936 s came back against the plain plan's 0.6146 s (bench_fir_optimal's cam30
    (a): 3.5051 against 2.4942 s). The result is now never slower
    than the plain plan there, and holds the limits and the residual (re-simulated)."""
    from research.experiments.optimality import BEAMS, PAPER, cam_like_path
    from research.metrics import peak_axis_values
    from research.optimal import trajectory_vibration

    path = cam_like_path(6, seed=1)
    F_s, D_s, eps = PAPER["feed"], PAPER["delays"], PAPER["tolerance"]
    plain = plan_fir(path, F_s, D_s, eps)
    ref = plain.trajectory(1e-3)
    limits = AxisLimits(*(peak_axis_values(ref, nu) for nu in (1, 2, 3)))
    plan, info = optimize_fir(path, F_s, D_s, eps, limits, starts=("smooth",), rounds=2, modes=BEAMS, full_output=True)
    assert float(plan.cycle_time) <= float(plain.cycle_time) * (1 + 1e-12)
    tr = plan.trajectory(1e-3)
    assert all(np.all(r <= 1 + 1e-6) for r in limit_ratios(tr, limits).values())
    left, bound = trajectory_vibration(tr, BEAMS)[0], trajectory_vibration(ref, BEAMS)[0]
    assert info["quiet"] and np.all(left <= bound * (1 + 1e-5) + 1e-9)


def test_piece_peaks_match_the_planner_root_finder():
    """The NLP's closed-form per-piece peaks equal the exact check's (companion-matrix roots)."""
    path = random_path(13)
    limits = AxisLimits.fir_envelope(2, F, DELAYS)
    plan = plan_fir(path, F, DELAYS, EPS)
    pos = plan.position
    ours = float(jnp.max(_piece_peak_ratios(pos, jnp.asarray(np.stack([limits.velocity, limits.acceleration, limits.jerk])))))
    pos_np = NumpyPiecewise(np.asarray(pos.breaks), np.asarray(pos.coeffs))
    theirs = float(corner_peak_ratios(pos_np, np.array([0.0]), np.array([float(pos.end)]), limits)[0])
    assert ours == pytest.approx(theirs, rel=1e-9)


def test_bad_input():
    path = random_path(14)
    with pytest.raises(PathError, match="Polyline"):
        optimize_fir(ToolPath.from_polyline(path), F, DELAYS, EPS)
    with pytest.raises(ParameterError, match="tolerance"):
        optimize_fir(path, F, DELAYS, 0.0)
    with pytest.raises(ParameterError, match="axes"):
        optimize_fir(path, F, DELAYS, EPS, AxisLimits.uniform(3, 1.0, 1.0, 1.0))
    with pytest.raises(ParameterError, match="mode"):
        optimize_fir(path, F, DELAYS, EPS, modes=[(0, -1.0, 0.02)])
    with pytest.raises(ParameterError, match="starts"):
        optimize_fir(path, F, DELAYS, EPS, starts=("nowhere",))


def test_polish_reaches_the_paper_overlaps_from_exact_stops():
    """_fir_polish from exact stops on three corners (90, 45, 120 deg) of 50 mm legs (longer than
    F T_d: the corners do not interact) at feed F, no limits: the overlaps it finds are eq 14's
    (``overlap_time``, Sencer 2015: the largest overlap whose corner error is eps) to the
    bisection's resolution; the plan it returns verifies exactly and is faster than the start."""
    from research.interpolators._fir_optimize import _Problem
    from research.interpolators._fir_overlap import overlap_time
    from research.interpolators._fir_polish import polish
    from research.interpolators.fir import CHECK_PERIOD

    heading = np.radians(np.cumsum([0.0, 90.0, 45.0, 120.0]))
    steps = 50.0 * np.column_stack([np.cos(heading), np.sin(heading)])
    path = Polyline(np.vstack([[0.0, 0.0], np.cumsum(steps, axis=0)]))
    d = np.asarray(DELAYS)
    problem = _Problem(path, F, d, EPS, None, 2e-3)
    x0 = np.concatenate([np.zeros(3), np.ones(12), np.full(8, 0.25)])
    assert problem.feasible(x0, CHECK_PERIOD)
    x, checks = polish(problem, x0, lambda y: problem.feasible(y, CHECK_PERIOD))
    expect = np.asarray(overlap_time(EPS, 2 * F * np.sin(np.radians([45.0, 22.5, 60.0])), d))
    assert checks > 0 and problem.feasible(x, CHECK_PERIOD) and problem.time(x) < problem.time(x0)
    np.testing.assert_allclose(x[:3] * d.sum(), expect, atol=d.sum() / 64)
    np.testing.assert_array_equal(x[3:], x0[3:])  # feeds already at F, shares untouched
