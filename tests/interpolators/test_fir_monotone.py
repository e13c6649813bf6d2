"""One ``plan_fir`` call against the tolerance (issue "FIR cornering on real CAM programs",
micro-segments: a rule that "gives a cycle time that never increases when eps grows (a property
test over random programs)").

Expected values are properties, never the planner's earlier output: a looser tolerance is not
slower, and the dwell sets a tighter tolerance decides are among the candidates of the looser one
(``_fir_lookahead`` module docstring: what is exact, what rests on verification). The programs
are ``research.paths.library.random_program`` with eps and F drawn after them from the same
seeded generator (the draws of ``benchmarks/bench_cam.py``'s random-monotone part).
"""

import numpy as np
import pytest

import research.interpolators._fir_lookahead as lookahead
from research.interpolators import plan_fir
from research.interpolators._fir_settle import _pulse_table
from research.interpolators.fir import _as_toolpath
from research.paths.library import random_program

DELAYS = (0.06, 0.03)
FACTORS = (1.0, 1.1, 1.25, 1.5, 2.0, 3.0)  # eps multiples of the property test (none a power of NEST_RATIO)

# (seed, arcs): programs where plan_fir(1.5 eps) was slower than plan_fir(eps) before the dwell
# sets of the tighter tolerances were offered (found by a scan of seeds 0-1599, lines and lines with
# arcs: 28 of 3200; the rise before is in the comment)
REGRESSIONS = [
    (11, False),  # +1.86 %
    (198, True),  # +3.81 %
    (225, True),  # +1.04 %
    (361, True),  # +6.35 %
    (370, True),  # +1.05 %
    (443, True),  # +5.97 %
    (538, True),  # +22.4 %
    (594, False),  # +3.32 %
    (705, False),  # +0.65 %
    (1020, True),  # +30.4 %
    (1509, False),  # +7.78 %
]


# (seed, arcs): programs whose cycle time rose somewhere on eps x FACTORS after the window-reach
# change (bench_cam's ladder, seeds 0-149: 8 of 300), where the dwell set that won at the lower eps
# was decided at eps q^4 (the deepest nesting level) and lay below the higher eps's levels; the rise
# before is in the comment
LADDER_REGRESSIONS = [
    (77, False),  # x1.1 -> x1.25: +2.09 %
    (107, False),  # x1.1 -> x1.25: +1.59 %
]


def _program(seed: int, arcs: bool):
    rng = np.random.default_rng(seed)
    tp = random_program(rng, arcs=arcs)
    eps, feed = float(np.exp(rng.uniform(np.log(0.005), np.log(0.5)))), float(rng.uniform(20.0, 300.0))
    return tp, eps, feed


@pytest.mark.parametrize("seed, arcs", REGRESSIONS)
def test_looser_tolerance_is_not_slower_regression(seed, arcs):
    """Regression: at 1.5 eps the dwell set that made eps fast was no longer offered (a vertex's
    dwell cost rose above its slow-down cost, or eq 13/14 allowed full overlap there while its
    window still needed a slow-down); now it is, and 1.5 eps is not slower."""
    tp, eps, feed = _program(seed, arcs)
    tight = float(plan_fir(tp, feed, DELAYS, eps).cycle_time)
    loose = float(plan_fir(tp, feed, DELAYS, 1.5 * eps).cycle_time)
    assert loose <= tight * (1 + 1e-9), (tight, loose)


@pytest.mark.parametrize("seed, arcs", LADDER_REGRESSIONS)
def test_cycle_time_along_the_eps_ladder_is_not_rising_regression(seed, arcs):
    """Regression: the "isolated" cost set of eps q^4 won at 1.1 eps and was not offered at 1.25 eps
    (whose levels stop at 1.25 eps q^4); the deeper levels on the fixed grid (``DEEP_STEPS``) offer
    it at both, and the cycle time does not rise along eps x FACTORS (to 1e-9 relative)."""
    tp, eps, feed = _program(seed, arcs)
    times = np.array([float(plan_fir(tp, feed, DELAYS, f * eps).cycle_time) for f in FACTORS])
    assert np.all(np.diff(times) <= 1e-9 * times[:-1]), times


def test_property_cycle_time_never_increases_with_eps():
    """The issue's property on one ``plan_fir`` call: over seeded random programs (seeds 0-14,
    lines and lines with arcs, 30 programs) the cycle time at eps x 1, 1.1, 1.25, 1.5, 2, 3 never
    rises (to 1e-9 relative). Not a proof: the nesting is exact for the dwell decisions only, the
    rest rests on verification, and over 600 programs (seeds 0-299) some still rise (measured
    rate in benchmarks/README.md, bench_cam section)."""
    for seed in range(15):
        for arcs in (False, True):
            tp, eps, feed = _program(seed, arcs)
            times = np.array([float(plan_fir(tp, feed, DELAYS, f * eps).cycle_time) for f in FACTORS])
            assert np.all(np.diff(times) <= 1e-9 * times[:-1]), (seed, arcs, times)


def _look_ahead(tp, feed, tol):
    """``look_ahead``'s candidates for a line program at one scalar tolerance (no arcs: base 1)."""
    t_in, t_out = tp.tangents()
    M = tp.n_blocks
    return [c() for c, _ in lookahead.look_ahead(tp, _pulse_table(tp), np.full(M, feed), np.ones(M), np.asarray(DELAYS),
                                                 np.full(M - 1, tol), t_in, t_out, False)]


def test_dwell_sets_of_tighter_tolerances_are_offered(monkeypatch):
    """The exact part of the nesting (``_fir_lookahead`` docstring, item 1): on line programs
    every candidate a call at eps q^k decides at its own tolerance alone (NEST_STEPS = 0 there) --
    its dwell vertices (full-overlap flags) and the tolerance its dwell corners leave to the other
    turns (a tolerance-free displacement, equal at both tolerances up to rounding) -- is among the
    candidates of the call at eps, for k = 1 .. NEST_STEPS (seeds 0-19)."""
    q, K = lookahead.NEST_RATIO, lookahead.NEST_STEPS
    assert K >= 1
    for seed in range(20):
        tp, eps, feed = _program(seed, False)
        tp = _as_toolpath(tp)
        offered = [(c[3], c[4]) for c in _look_ahead(tp, feed, eps)]
        with monkeypatch.context() as m:
            m.setattr(lookahead, "NEST_STEPS", 0)
            m.setattr(lookahead, "DEEP_STEPS", 0)
            for k in range(1, K + 1):
                for c in _look_ahead(tp, feed, eps * q**k):
                    assert any(np.array_equal(c[3], full) and np.allclose(c[4], others, rtol=1e-9, atol=1e-12 * eps)
                               for full, others in offered), (seed, k, ~c[3], c[4])


def test_deep_levels_are_the_grid_points_just_below():
    """``deep_levels``: the ``DEEP_STEPS`` largest powers ``q^m`` (``m`` integer) strictly below each
    tolerance, nearest first, found here by listing the powers; 0 for a tolerance of 0; the same
    points for two tolerances between the same grid points (why they nest across eps)."""
    q, D = lookahead.NEST_RATIO, lookahead.DEEP_STEPS
    tol = np.array([0.05, q**-3, 0.0625, 1.0, 0.33, 0.0])
    powers = q ** np.arange(-20.0, 60.0)
    expected = np.array([np.sort(powers[powers < t * (1 - 1e-12)])[::-1][:D] if t > 0 else np.zeros(D) for t in tol]).T
    np.testing.assert_allclose(lookahead.deep_levels(tol), expected, rtol=1e-12)
    np.testing.assert_array_equal(lookahead.deep_levels(np.array([0.045])), lookahead.deep_levels(np.array([0.05])))
