"""``plan_fir`` with a tolerance per block (``G64 P`` changed mid-program) and at exact stops.

Regressions found by a seeded stress sweep of random programs (issue "FIR cornering on real CAM
programs": ``G64 P<tol>`` as eps, per block, changeable mid-program):

* a path sample near a corner is held to the smaller of its block's and the vertex's tolerance;
  where a short block let a window centred on a tighter block reach the corner, the repair read
  the sample's distance against the (looser) vertex tolerance, a ratio above 1, and *sped up* the
  window: planned feeds of 816 mm/s at F = 50 mm/s (``_fir_verify._bound_waiting``);
* deviations charged to a corner that is already an exact stop could not be repaired there
  (``ConvergenceError`` after 36 rounds on 87 of 200 random programs with per-block tolerances;
  ``_fir_verify.charged_repairs``);
* the rounding of a long profile at its exact stops (nm after an hour of motion) broke a
  tolerance of 0, which no repair can reach (``_fir_verify.stop_rounding``);
* the corner search stayed at a grid point 63 um short of a collinear vertex passed while the
  motion accelerates (Newton's model has no minimum there), and the false error slowed a straight
  line 20x, or at tolerance 0 set its feed to 0: a plan that never left the start
  (``_fir_verify._corner_distances``' Gauss-Newton step, ``_fir_repair``'s exact stop at ratio 0).

Expected values are properties or independent closed forms (never the planner's earlier output).
"""

from __future__ import annotations

import numpy as np
import pytest

from research.interpolators import plan_fir
from research.interpolators._fir_kernels import verified_bound
from research.paths import Polyline
from research.paths.library import random_program
from research.paths.toolpath import ToolPath

TOLS = np.array([0.0, 1e-4, 1e-3, 0.01, 0.05, 0.5])  # [mm], G64 P values from exact path to coarse roughing


def _check(plan, feed, tol_block):
    """The properties every plan keeps: no block above the commanded feed, every corner within the
    smaller of its two blocks' tolerances, the sampled path within the loosest block tolerance."""
    tol_vertex = np.minimum(tol_block[:-1], tol_block[1:])
    assert np.all(np.asarray(plan.feeds) <= feed * (1 + 1e-12))
    assert np.all(np.asarray(plan.corner_errors) <= verified_bound(tol_vertex) + 1e-8)
    assert plan.path_deviation <= verified_bound(tol_block.max()) + 1e-8


def test_a_tight_block_next_to_a_short_one_never_speeds_the_plan_up():
    """Three lines (10 mm, a 0.02 mm jog, 0.5 mm) at F = 50 mm/s with tolerances 0.1 / 50 / 50 um:
    before the fix the repairs of the corner after the jog read a 0.1 um violation against its
    50 um tolerance and planned 816 mm/s. The trajectory's speed never exceeds F (sampled at
    0.1 ms; the FIR's output speed is a moving average of input speeds of at most F)."""
    path = Polyline([[0, 0], [10, 0], [10, 0.02], [10.5, 0.02]])
    tol = np.array([1e-4, 0.05, 0.05])
    plan = plan_fir(path, 50.0, [0.02, 0.01], tol)
    _check(plan, 50.0, tol)
    speed = np.linalg.norm(np.asarray(plan.trajectory(1e-4).v), axis=1)
    assert speed.max() <= 50.0 * (1 + 1e-9)
    assert float(plan.cycle_time) >= path.length / 50.0 + 0.03  # no faster than L / F + T_d


@pytest.mark.parametrize("tol", [[1.0, 1.0, 1e-4], [1e-4, 1.0, 1.0]])
def test_a_deviation_next_to_an_exact_stop_is_repaired_at_the_blend_that_makes_it(tol):
    """The same lines with 1 / 1 / 0.1 um (and reversed): the tight corner stops, the loose corner's
    blend stays within half a window of it; before the fix the deviation was charged to the stop
    and the plan raised ``ConvergenceError``."""
    path = Polyline([[0, 0], [10, 0], [10, 0.02], [10.5, 0.02]])
    tol = np.array(tol)
    _check(plan_fir(path, 50.0, [0.02, 0.01], tol), 50.0, tol)


@pytest.mark.parametrize("tol", [[1e-4, 0.01, 1e-4], [0.01, 0.01, 1e-4], [1e-4, 0.01, 0.01]])
def test_an_arc_looser_than_its_lines_is_slowed_where_its_stops_cannot_be_repaired(tol):
    """A 5 mm line, a quarter arc of R 5 mm and a 1.1 mm line at F = 300 mm/s: with the arc at
    10 um between 0.1 um lines both corners stop and the arc's start stays 3 um off within half a
    window of them; the arc is slowed instead (``ConvergenceError`` before the fix)."""
    tp = ToolPath.from_polyline(Polyline([[10.0, 0.0], [5.0, 0.0]])).then_arc([0.0, 5.0], [0.0, 0.0], ccw=True)
    tp = ToolPath(tp.start, np.vstack([tp.ends, [[-1.0, 5.5]]]), np.vstack([tp.centers, [[np.nan, np.nan]]]),
                  np.vstack([tp.normals, [[np.nan] * 3]]), np.concatenate([tp.sweeps, [0.0]]))
    tol = np.array(tol)
    _check(plan_fir(tp, 300.0, [0.02, 0.01], tol), 300.0, tol)


def test_exact_stops_of_an_hour_long_raster_accept_their_rounding():
    """300 lines alternating 1,000 mm and 1 mm at 50 mm/s with tolerance 0: every corner an exact
    stop, so each block runs alone, rest to rest, in ``L / F + T_d`` (Sencer 2015: a pulse of
    ``L / F`` through filters of ``T_d`` in total), and the cycle time is ``sum L / F + M T_d`` =
    3,003 + 27 s. The profile's rounding at the stops (nm) was taken for a violation of the
    tolerance 0 that no repair can reach (``ConvergenceError``)."""
    k = np.arange(301)
    path = Polyline(np.column_stack([np.where((k % 4 == 1) | (k % 4 == 2), 1000.0, 0.0), (k // 2) * 1.0]))
    plan = plan_fir(path, 50.0, [0.06, 0.03], 0.0)
    assert float(plan.cycle_time) == pytest.approx(path.length / 50.0 + 300 * 0.09, rel=1e-12)
    assert np.max(np.asarray(plan.corner_errors)) <= 1e-7  # rounding: 1e-10 of the 1 m coordinates


@pytest.mark.parametrize("seed", range(0, 200, 5))
def test_random_programs_with_a_tolerance_per_block_plan_within_them(seed):
    """Property over seeded random programs of lines (even seeds) and lines with arcs (odd), each
    block a tolerance drawn from 0 (lines only), 0.1 um ... 0.5 mm: the plan is found and keeps
    :func:`_check`. Before the fix 87 of seeds 0-199 raised ``ConvergenceError`` (this sample of
    40: 18)."""
    rng = np.random.default_rng(seed)
    tp = random_program(rng, arcs=seed % 2 == 1)
    feed = float(rng.uniform(20.0, 300.0))
    delays = (0.06, 0.03) if seed % 3 else (0.02, 0.01)
    tol = rng.choice(TOLS[1:] if tp.is_arc.any() else TOLS, tp.n_blocks)
    _check(plan_fir(tp, feed, delays, tol), feed, tol)


@pytest.mark.parametrize("delays", [(0.03, 0.02, 0.01), (0.06, 0.03)])
@pytest.mark.parametrize("tol", [0.0, 1e-4])
def test_a_straight_line_split_near_its_start_plans_as_one_block(delays, tol):
    """A 10 mm line split at 0.1 mm (or 1 mm) at F = 250 mm/s: the input is the same pulse as the
    unsplit line's, so the cycle time is ``L / F + T_d`` (Sencer 2015, one block). Before: the
    corner search kept its grid point 63 um short of the collinear vertex (Newton's curvature is
    negative while the motion accelerates), so tolerance 0 slowed the window to feed 0 (a plan that
    never left the start) and 1e-4 mm to 9.7 mm/s (1.12 s)."""
    split = 1.0 if len(delays) == 3 else 0.1
    plan = plan_fir(Polyline([[0, 0], [split, 0], [10, 0]]), 250.0, delays, tol)
    assert float(plan.cycle_time) == pytest.approx(10.0 / 250.0 + sum(delays), rel=1e-9)
    assert np.all(np.asarray(plan.feeds) == 250.0)


def test_the_corner_search_finds_a_vertex_passed_while_accelerating():
    """The corner-error search on the unverified plan of a line split 0.1 mm after its start: the
    trajectory runs along the line through the vertex, so its distance is 0; the search's grid
    alone finds 63 um (the nearest grid point) and Newton's steps cannot leave it (their model has
    no minimum there). Both forms, the compiled and the JAX one, find it within 10 nm."""
    from research.interpolators._fir_verify import corner_distances, vertex_distances
    from research.piecewise import NumpyPiecewise

    plan = plan_fir(Polyline([[0, 0], [0.1, 0], [10, 0]]), 250.0, (0.06, 0.03), 1e-4, refine=False)
    pos = NumpyPiecewise(np.asarray(plan.position.breaks), np.asarray(plan.position.coeffs))
    vertices, centre = np.asarray(plan.vertices), np.asarray(plan.corner_times)
    assert vertex_distances(pos, vertices, centre, 0.045)[0] <= 1e-8
    assert float(corner_distances(plan.position, vertices, centre, 0.045)[0]) <= 1e-8


@pytest.mark.parametrize("text", [
    "G21 G90 G17 F9000\nG61\nG1 X10\nG64 P0.01\nG2 X20 Y0 R5\nG1 X30\nM30\n",
    "G21 G90 G17 F6000\nG61\nG1 X10\nG1 X10.2 Y0.3\nG64 P0.01\nG3 X12 Y2 R2\nG61\nG1 X12 Y5\nM30\n",
])
def test_an_arc_after_g61_lines_is_held_to_its_own_tolerance(text):
    """``G61`` lines (tolerance 0), then ``G64 P0.01`` and an arc: the corner between them stops
    exactly, and the arc's start, just after the stop, was held to the tolerance of the block whose
    input the sampling window was centred on -- the line before the stop's gap, 0 -- so the arc was
    slowed 2 % a round without end (``ConvergenceError``; 3 of the sweep's G-code programs). By an
    exact stop a sample is on its block on that side of the corner instant (the motion on each side
    of a stop is that block's alone), and takes that block's tolerance."""
    from research.paths.gcode import parse_gcode

    prog = parse_gcode(text)
    tol = np.asarray(prog.block_tolerance)
    plan = plan_fir(prog.blocks, prog.block_feeds, [0.02, 0.01], tol, pauses=prog.block_pauses)
    _check(plan, float(np.max(prog.block_feeds)), tol)
