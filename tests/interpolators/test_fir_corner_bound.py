"""The limit-aware lower bound on one corner's FIR cycle time (B3, ``_fir_corner_bound``).

References: a lower bound must lie below every plan of its family, so it is checked against
``plan_fir``'s verified plans under the same limits (an independent computation: the planner
knows nothing of the bound) on seeded random corners; the trivial bound of a block's length at
its feed plus the delays from below; and a tighter jerk limit never lowers it. The cycle times the
bound proves out of reach are the benchmark's (benchmarks/README.md), not asserted here."""

import numpy as np
import pytest

from research.errors import ParameterError
from research.interpolators import plan_fir
from research.interpolators._fir_corner_bound import corner_limit_bound
from research.interpolators._fir_window_bound import kernel_cdf
from research.limits import AxisLimits
from research.paths import Polyline

DELAYS = (0.02, 0.01)


def _corner(rng):
    turn = np.deg2rad(rng.uniform(20.0, 160.0))
    L1, L2 = rng.uniform(1.0, 6.0, 2)
    return Polyline([[-L1, 0.0], [0.0, 0.0], [L2 * np.cos(turn), L2 * np.sin(turn)]])


@pytest.mark.parametrize("seed", range(4))
def test_the_bound_lies_below_every_verified_plan_under_the_same_jerk_limits(seed):
    """Random corners (turn 20-160 deg, legs 1-6 mm) at F 150 mm/s, eps 10-50 um, under the FIR's
    envelope and under half its jerk: ``plan_fir``'s limit-holding plan, verified on its exact
    peaks and corner error, is never faster than the bound; and the bound is at least a leg's
    time at the feed plus the delays."""
    rng = np.random.default_rng(seed)
    path, eps = _corner(rng), rng.uniform(0.01, 0.05)
    envelope = AxisLimits.fir_envelope(2, 150.0, DELAYS)
    for scale in (1.0, 0.5):
        limits = AxisLimits(envelope.velocity, envelope.acceleration, envelope.jerk * scale)
        bound = corner_limit_bound(path, 150.0, DELAYS, eps, limits)
        plan = plan_fir(path, 150.0, DELAYS, eps, limits=limits)
        assert bound <= float(plan.cycle_time) * (1 + 1e-9)
        assert bound >= float(np.max(path.lengths)) / 150.0 + sum(DELAYS) - 1e-3 - 1e-12


def test_a_tighter_jerk_limit_never_lowers_the_bound():
    """The same corner under the envelope's jerk and a tenth of it: the relaxation's feasible set
    only shrinks, so the bound does not fall (and here rises: the jerk binds)."""
    path = Polyline([[-4.0, 0.0], [0.0, 0.0], [0.0, 4.0]])
    envelope = AxisLimits.fir_envelope(2, 150.0, DELAYS)
    loose = corner_limit_bound(path, 150.0, DELAYS, 0.02, envelope)
    tight = corner_limit_bound(path, 150.0, DELAYS, 0.02,
                               AxisLimits(envelope.velocity, envelope.acceleration, 0.1 * envelope.jerk))
    assert tight > loose


def test_step_response_is_the_distribution_of_two_uniform_delays():
    """``K(t)`` (``kernel_cdf``, B3's step response) against the sampled distribution of the sum of
    two uniform delays."""
    rng = np.random.default_rng(0)
    s = rng.uniform(0, 0.02, 400_000) + rng.uniform(0, 0.01, 400_000)
    t = np.linspace(-0.005, 0.035, 41)
    np.testing.assert_allclose(kernel_cdf(t, DELAYS), [np.mean(s <= x) for x in t], atol=3e-3)


@pytest.mark.parametrize("kw, match", [
    (dict(path=Polyline([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [2.0, 1.0]])), "two segments"),
    (dict(delays=(0.02,)), "two positive delays"),
    (dict(delays=(0.02, 0.0100003)), "no common cell"),
    (dict(feed=0.0), "positive"),
    (dict(limits=AxisLimits.fir_envelope(3, 100.0, DELAYS)), "3 axes on a path of 2"),
])
def test_bad_input_names_what_is_wrong(kw, match):
    args = dict(path=Polyline([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0]]), feed=100.0, delays=DELAYS, tolerance=0.01,
                limits=AxisLimits.fir_envelope(2, 100.0, DELAYS))
    args.update(kw)
    with pytest.raises(ParameterError, match=match):
        corner_limit_bound(**args)
