"""Vertices that do not turn, at tolerance 0 (``G61``, exact path): a line split at a point is the
same motion as the line (LinuxCNC's G61: "If two sequential moves are exactly co-linear movement
will not stop"; here also where the split point is rounded off the line by less than the
verification can see, ``VERIFY_ATOL``).

References: the unsplit program planned by the same planner (the FIR input of a line split at a
point, both halves at full overlap and one feed, is the line's input: one pulse, Sencer 2015 eq 5);
the window sum of ``_fir_feed``'s module docstring evaluated directly (``ChainError.displacement``).
Nothing is compared with the planner's earlier output."""

import numpy as np
import pytest

from research.interpolators import plan_fir
from research.interpolators._fir_feed import ChainError
from research.interpolators._fir_kernels import verified_bound
from research.paths import Polyline
from research.paths.gcode import parse_gcode


def _split_program(rng):
    """A random zigzag of 3-6 lines (0.2-5 mm) and the same path with one line split at a random
    point (computed in floating point: off the line by rounding), and a feed [mm/s]."""
    n = int(rng.integers(3, 7))
    pts = np.vstack([[0.0, 0.0], np.cumsum(np.column_stack([rng.uniform(0.2, 5.0, n), rng.uniform(-3.0, 3.0, n)]),
                                           axis=0)])
    i, u = int(rng.integers(0, n)), rng.uniform(0.05, 0.95)
    split = np.insert(pts, i + 1, pts[i] + u * (pts[i + 1] - pts[i]), axis=0)
    return Polyline(pts), Polyline(split), float(rng.uniform(50.0, 300.0))


@pytest.mark.parametrize("delays", [(0.06, 0.03), (0.05, 0.03, 0.02)])
def test_a_line_split_at_a_point_runs_as_the_line_at_tolerance_zero(delays):
    """Regression (measured: every one of 30 random programs +T_d, up to 30 % slower): the split
    point's rounding kink made it a turning vertex held to 0, and the look-ahead stopped it in
    every candidate. Now the split program's cycle time is the unsplit one's (1e-9 relative, 20
    programs) and every vertex error is within the verification's bound of 0."""
    rng = np.random.default_rng(3)
    for _ in range(20 if len(delays) == 2 else 6):
        whole, split, feed = _split_program(rng)
        a = plan_fir(whole, feed, delays, 0.0)
        b = plan_fir(split, feed, delays, 0.0)
        assert float(b.cycle_time) == pytest.approx(float(a.cycle_time), rel=1e-9)
        assert np.all(np.asarray(b.corner_errors) <= verified_bound(0.0))


def test_g61_program_with_collinear_moves_does_not_stop_between_them():
    """The same through G-code: under ``G61`` a square whose sides are each written as two
    collinear moves takes the time of the square of four moves (its corners stop, eq 13 at
    ``h = 0``; its split points do not)."""
    square = "G21 G90 G61\nG1 X20 Y0 F3000\nG1 X20 Y20\nG1 X0 Y20\nG1 X0 Y0\nM2\n"
    halves = "G21 G90 G61\nG1 X7 Y0 F3000\nG1 X20 Y0\nG1 X20 Y13\nG1 X20 Y20\nG1 X13 Y20\nG1 X0 Y20\nG1 X0 Y6\nG1 X0 Y0\nM2\n"
    times = []
    for text in (square, halves):
        prog = parse_gcode(text)
        times.append(float(plan_fir(prog.blocks, np.asarray(prog.block_feeds), (0.06, 0.03),
                                    np.asarray(prog.block_tolerance)).cycle_time))
    assert times[1] == pytest.approx(times[0], rel=1e-9)
    assert times[0] == pytest.approx(80.0 / 50.0 + 4 * 0.09, rel=1e-9)  # L / F + T_d per stop and at the end


def test_reach_free_feed_is_where_the_window_sum_leaves_zero():
    """``ChainError.reach_free_feed`` on random turn lists with straight (``du = 0``) entries:
    ``|d_j| = 0`` at the feed it returns (direct sum), ``> 0`` just above it (1e-6 relative),
    and 0 at a query on a turning entry."""
    rng = np.random.default_rng(8)
    delays = np.array([0.06, 0.03])
    for _ in range(10):
        s = np.sort(rng.uniform(0.0, 20.0, 12))
        du = rng.normal(size=(12, 2))
        straight = rng.random(12) < 0.4
        du[straight] = 0.0
        chain = ChainError(s, du, delays)
        j = np.flatnonzero(straight)
        if not j.size:
            continue
        q = s[j] - chain.origin
        f = chain.reach_free_feed(q, np.full(j.size, 1e6))
        assert np.all(f > 0)
        np.testing.assert_array_equal(chain(s[j], f), 0.0)
        assert np.all(chain(s[j], f * (1 + 1e-6)) > 0)
        turning = np.flatnonzero(~straight)
        np.testing.assert_array_equal(chain.reach_free_feed(s[turning] - chain.origin, np.full(turning.size, 1e6)), 0.0)


@pytest.mark.parametrize("gaps", [[0.0055], [0.0122, 0.0055], [0.0321, 0.0122, 0.0055]])
def test_split_points_microns_before_an_exact_stop_do_not_stop(gaps):
    """Regression (stress sweep, 2026-12-04): a line split 5.5-32 um before a corner that stops
    (tolerance 0, F 18.74 mm/s). The trajectory passes those points at a crawl into the stop, and
    the corner search's 6 Newton steps ended 0.37 um from one of them: the planner stopped it, then
    its neighbour (+0.09-0.18 s). Now a search above its tolerance goes on until it stops moving:
    the split program runs in the unsplit one's time and passes within the verification's 1 pm of
    every point."""
    A, B, C = np.array([0.3, -0.2]), np.array([6.5, 0.9]), np.array([6.9, 2.4])
    u = (B - A) / np.linalg.norm(B - A)
    whole = plan_fir(Polyline(np.array([A, B, C])), 18.74, (0.06, 0.03), 0.0)
    split = plan_fir(Polyline(np.array([A] + [B - g * u for g in gaps] + [B, C])), 18.74, (0.06, 0.03), 0.0)
    assert float(split.cycle_time) == pytest.approx(float(whole.cycle_time), rel=1e-9)
    assert np.all(np.asarray(split.corner_errors) <= verified_bound(0.0))
