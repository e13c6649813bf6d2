"""Programs that a seeded random search of the G-code reader and the FIR planner found breaking
them (2026-12-05: ~1,900 plans of generated programs, 10,000 mutated texts), cut down to a few
lines each, against independent computations: brute-force distances over dense samples, the
corner error of a densely sampled trajectory, sample counts from the tree itself, closed forms.
Each failed before its fix."""

import numpy as np
import pytest

from research.interpolators import plan_fir
from research.limits import AxisLimits
from research.metrics import limit_ratios, peak_axis_values, within_limits
from research.paths import Polyline
from research.paths.gcode import parse_gcode


@pytest.mark.parametrize("scale", [0.5, 0.54])
def test_a_short_line_cut_into_ramp_steps_from_both_ends_keeps_its_middle(scale):
    """Two inch lines (0.783 mm and 0.0127 mm) at F 1 in/min under limits at 0.5x the envelope:
    the ramp steps cut from the short line's two ends met at its middle, one point rounded twice,
    and the cut path had a block of zero length (``PathError``). Planned now, within the limits,
    on the blocks and on the polyline."""
    prog = parse_gcode("G20\nG1 F1\nY-0.0298 Z0.0079\nY-0.0303\n")
    F = float(prog.block_feeds[0])
    env = AxisLimits.fir_envelope(3, F, (0.02, 0.01))
    lim = AxisLimits(env.velocity, scale * env.acceleration, scale * env.jerk)
    for path, feed in ((prog.blocks, prog.block_feeds), (prog.polyline, F)):
        plan = plan_fir(path, feed, (0.02, 0.01), 0.006, limits=lim)
        assert within_limits(plan.trajectory(1e-3), lim)
        np.testing.assert_allclose(np.asarray(plan.trajectory(1e-3).q)[-1], prog.polyline.points[-1], atol=1e-9)


def test_one_long_line_among_micro_chords_samples_the_distance_tree_sparsely():
    """A 990 m line then 49 zigzag chords of 1 um: the distance tree cut every block into pieces of
    the median block length, 10^9 points (tens of GB) for the line. Its sample points are now at
    most ``TREE_SAMPLES`` per block on average (plus one a block), and distances still agree with
    the closed-form distance to the nearest segment."""
    from research.paths.toolpath import TREE_SAMPLES

    L = 990_000.0
    text = "G21 G90 F600\nG1 X%g\n" % L + "\n".join(f"X{L + 0.001 * i:.4f} Y{0.005 * (i % 2):.4f}" for i in range(1, 50)) + "\n"
    tp = parse_gcode(text).blocks
    tree, _, _ = tp._tree()
    assert tree.n <= (TREE_SAMPLES + 1) * tp.n_blocks
    rng = np.random.default_rng(0)
    q = np.column_stack([rng.uniform(-10.0, L + 1.0, 200), rng.uniform(-1.0, 1.0, 200), np.zeros(200)])
    a, b = tp.starts, tp.ends
    ab = b - a
    u = np.clip(np.einsum("qkd,kd->qk", q[:, None, :] - a[None], ab) / np.sum(ab * ab, axis=1), 0.0, 1.0)
    brute = np.linalg.norm(q[:, None, :] - (a[None] + u[..., None] * ab[None]), axis=2).min(axis=1)
    np.testing.assert_allclose(tp.distance(q), brute, rtol=1e-9, atol=1e-9)


def test_the_distance_to_a_steep_helix_is_found_near_the_end_its_angle_clamps_to():
    """A helix of 0.01 rad sweep (R 1 mm) over 10 mm of Z: the point (1, 0, -0.1) lies 1e-4 mm from
    it (at the angle where the helix reaches z = -0.1), but its projection angle (0) clamps to the
    start, and no Newton step started there: 0.1 mm, the distance to the start. Against dense
    samples of the helix itself (10^6 points, the closed form ``(cos phi, sin phi, -10 phi /
    0.01)``)."""
    tp = parse_gcode("G1 X1 F600\nG3 X0.99995 Y0.01 Z-10 I-1").blocks
    sweep = float(np.arctan2(0.01, 0.99995))
    phi = np.linspace(0.0, sweep, 1_000_001)
    helix = np.column_stack([np.cos(phi), np.sin(phi), -10.0 * phi / sweep])
    for q in ([1.0, 0.0, -0.1], [1.0, 0.0, -5.0], [0.9, 0.002, -2.0]):
        brute = float(np.min(np.linalg.norm(helix - np.asarray(q), axis=1)))
        got = float(tp.distance([q])[0])
        assert got <= brute + 1e-9 and got >= brute - 1e-6, (q, got, brute)
        assert float(tp.distance_bound([q])[0]) <= brute + 1e-6


def test_corner_errors_find_the_nearest_basin_among_micro_chords():
    """Seven inch chords of 3-9 um between two longer ones at F 60 in/min: the trajectory passes
    each vertex several times within its window, and the corner search refined only the best of
    its grid points: vertex 3 read 1.37 eps where the trajectory passes 0.12 eps from it. Every
    corner error now agrees with the least distance over a 10 us sampling of the trajectory
    (refined to 1e-3 eps: at 25 mm/s, 10 us is 0.25 um)."""
    text = ("G20\nG1 F60\nX-0.004998 Y-0.007004\nX-0.006089 Y-0.009099\nX-0.006242 Y-0.009419\n"
            "X-0.006292 Y-0.009526\nX-0.006392 Y-0.009740\nX-0.006441 Y-0.009847\nX0.009165 Y0.007565\n")
    prog = parse_gcode(text)
    eps = 0.0019104271133812908
    plan = plan_fir(prog.blocks, prog.block_feeds, (0.02, 0.01), eps)
    q = np.asarray(plan.trajectory(1e-5).q)
    brute = np.array([np.min(np.linalg.norm(q - v, axis=1)) for v in np.asarray(plan.vertices)])
    got = np.asarray(plan.corner_errors)
    assert np.all(got <= brute + 1e-12)
    np.testing.assert_allclose(got, brute, atol=1e-3 * eps)
    assert np.max(got) <= eps


def test_one_filter_motion_reads_no_nan_under_its_own_envelope():
    """One FIR filter: its jerk is unbounded (Dirac impulses where the acceleration steps) and its
    envelope sets no jerk limit (``inf``): ``inf / inf`` was NaN and ``within_limits`` False on a
    plan that keeps its limits. An infinite limit now reads 0 whatever the peak; the impulses are
    still reported against a finite limit."""
    path = Polyline([[0.0, 0.0], [10.0, 0.0], [10.0, 10.0]])
    lim = AxisLimits.fir_envelope(2, 100.0, (0.02,))
    tr = plan_fir(path, 100.0, (0.02,), 0.05, limits=lim).trajectory(1e-3)
    assert np.all(limit_ratios(tr, lim)["jerk"] == 0.0)
    assert within_limits(tr, lim)
    assert np.all(np.isinf(peak_axis_values(tr, 3)))
    finite = AxisLimits(lim.velocity, lim.acceleration, np.full(2, 1e9))
    assert not within_limits(tr, finite)


def test_an_axis_that_barely_moves_reads_no_impulse_from_rounding():
    """A 0.4 um helical arc then a rapid, two filters (60/30 ms): the acceleration is continuous,
    but Z (peak 0.06 mm/s^2 against X and Y's ~10^3) showed a rounding step of 1.2e-7 mm/s^2, 2e-6
    of its own peak, and read an infinite jerk. A step now counts as an impulse from 1e-6 of its
    axis's peak and 1e-9 of the largest axis's; the jerk of every axis is within its limit, as the
    planner holds it, and no axis reads infinite."""
    prog = parse_gcode("G1 F100000\nG3 X-0.000282 Y0.000282 Z-0.01 R-5\nG0 X0.000074 Y0.000138 Z-0.010109")
    delays = (0.06, 0.03)
    env = AxisLimits.fir_envelope(3, float(np.max(prog.block_feeds)), delays)
    lim = AxisLimits(env.velocity, 0.37 * env.acceleration, 0.37 * env.jerk)
    plan = plan_fir(prog.blocks, prog.block_feeds, delays, 0.004, limits=lim)
    tr = plan.trajectory(1e-3)
    assert np.all(np.isfinite(peak_axis_values(tr, 3)))
    assert within_limits(tr, lim)


_LONG_ARCS = """G1 F600
G2 X-5.7660 Y3.8023 Z0 I24.5768 J43.5429
G2 X-5.7650 Y3.8050 Z0 I-5.7642 J3.8031
G3 X-5.8125 Y3.7306 Z0 I-47.9241 J30.6864 P2
G1 X-25.3019 Y7.5389 Z4.8843
G64 P0.0001
G2 X-1384.1091 Y-999.2062 Z4.8843 I-997.2282 J-74.4036
G2 X-1374.3552 Y-1001.3521 Z4.8863 I4.8208 J-1.3266
G3 X-1925.1314 Y-933.5655 Z4.8863 I-158.0313 J987.4341
G1 X-1925.1255 Y-933.5647 Z4.8902
X-1925.6397 Y-933.2733 Z4.8902
X-1926.8451 Y-934.3803 Z4.8902
X-1926.8373 Y-934.4297
X-1926.7821 Y-934.6216
X-1926.7623 Y-934.6675 Z4.8902
X-1926.7403 Y-934.7124 Z4.8902
X-1926.2798 Y-935.1548
X-1926.2340 Y-935.1750 Z4.8902
"""


def test_a_ramp_plan_that_does_not_converge_leaves_the_others():
    """Arcs of R 5-1000 mm (one of two turns) and 1-50 um chords at 10 mm/s, eps 25.65 um then
    ``G64 P0.0001``, limits at 0.0536x the envelope (a 25 mm/s^2, j 2,500 mm/s^3): the plan of the
    path with its lines cut into ramp steps (one of the alternatives ``plan_fir`` compares under
    limits) ends with an exact stop above a limit and raised ``ConvergenceError``, which took the
    whole call down although the path as written plans. That alternative is now left out with a
    ``RuntimeWarning`` naming it, and the fastest of the others is returned, within the limits."""
    prog = parse_gcode(_LONG_ARCS)
    tol = np.where(np.isfinite(prog.block_tolerance), prog.block_tolerance, 0.02565240403135098)
    env = AxisLimits.fir_envelope(3, 10.0, (0.02, 0.01))
    lim = AxisLimits(env.velocity, 0.053576347506893156 * env.acceleration, 0.053576347506893156 * env.jerk)
    with pytest.warns(RuntimeWarning, match="ramp steps did not converge"):
        plan = plan_fir(prog.blocks, prog.block_feeds, (0.02, 0.01), tol, limits=lim)
    assert np.isfinite(float(plan.cycle_time))
    assert within_limits(plan.trajectory(0.05), lim)
    np.testing.assert_allclose(np.asarray(plan.trajectory(0.05).q)[-1], prog.polyline.points[-1], atol=1e-8)
