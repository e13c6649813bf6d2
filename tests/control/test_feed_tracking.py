"""Thesis Fig 3.13 (research.control._feed_tracking): feed schedules through the SISO SMC drives with the
amplifier limit read from Table 3.1. Model predictions (the thesis' curves are experimental, on a path
that is not public): tested as properties."""

import numpy as np
import pytest

from research.control import (
    CONTROL_PERIOD,
    amplifier_limits,
    feed_tracking,
    joint_reference,
    simulate_closed_loop,
    table_5_2,
    table_5_3,
    thesis_plant,
)
from research.control._study import step_disturbance_peak
from research.errors import ParameterError
from research.optimal import constant_feed, optimize_feedrate, table31_limits
from research.paths.five_axis_library import blade_flank_path

#: Fig 5.7 axis maxima -> isolated-reversal friction estimate (research.control.identify_coulomb's start);
#: the property tests below do not depend on the exact friction value
_PEAKS = np.array([0.015, 0.013, 0.007, 2.2e-3, 1.7e-3])


@pytest.fixture(scope="module")
def setup():
    p, g = thesis_plant(), table_5_2()
    dc = _PEAKS / (2 * np.array([step_disturbance_peak(float(p.m[i]), float(p.c[i]), g, i, CONTROL_PERIOD)
                                 for i in range(5)]))
    plant = thesis_plant(dc)
    limits = table31_limits()
    path = blade_flank_path()
    scheds = {"optimized": optimize_feedrate(path, limits, 150.0, control_points=40, refinements=1, sample_period=5e-3),
              "40": constant_feed(path, limits, 40.0), "150": constant_feed(path, limits, 150.0)}
    u_max = amplifier_limits(plant, limits)
    runs = {k: feed_tracking(s.trajectory, plant, u_max) for k, s in scheds.items()}
    return plant, u_max, scheds, runs


def _feedforward_demand(plant, traj):
    """max_t |m a_ref + c v_ref| + d_c per axis [V]: the voltage the reference alone asks for (eq 4.11)."""
    return np.abs(np.asarray(plant.m) * np.asarray(traj.a) + np.asarray(plant.c) * np.asarray(traj.v)).max(axis=0) \
        + np.asarray(plant.coulomb)


def test_amplifier_limit_is_table_3_1_acceleration_at_table_3_1_velocity(setup):
    """u_max = m A + c V + d_c with Table 3.1 (X: 2000 mm/s^2, 250 mm/s; A: 2500 deg/s^2, 166 deg/s), by hand."""
    plant, u_max, _, _ = setup
    m, c, d = (np.asarray(x) for x in (plant.m, plant.c, plant.coulomb))
    assert u_max[0] == pytest.approx(0.00162 * 2000 + 0.00681 * 250 + d[0], rel=1e-12)
    assert u_max[3] == pytest.approx(0.00682 * np.radians(2500) + 0.01964 * np.radians(166) + d[3], rel=1e-12)


def test_optimized_feed_never_saturates(setup):
    """Thesis §3.6: "when the feed is optimized ... the drive limits were never violated. The machine tool
    control was kept in a linear control region": no axis reaches its amplifier limit, no divergence."""
    _, _, _, runs = setup
    assert not runs["optimized"].diverged
    assert np.all(runs["optimized"].saturated_fraction == 0.0)


def test_saturating_axes_are_those_whose_feedforward_demand_exceeds_the_limit(setup):
    """Independent check of the simulated saturation: an axis saturates in the loop exactly where the
    reference alone already asks for more than its limit (on these runs the feedback does not move an
    axis across its limit). Constant 150 mm/s (thesis: "the drives would have become excessively
    saturated"): some axes do; 40 mm/s on this path: none (the thesis' impeller path did saturate at
    40 mm/s; on the public path 40 mm/s stays within the Table 3.1 accelerations)."""
    plant, u_max, scheds, runs = setup
    for case in ("optimized", "40", "150"):
        demand = _feedforward_demand(plant, scheds[case].trajectory)
        np.testing.assert_array_equal(runs[case].saturated_fraction > 0, demand > u_max, err_msg=case)
    assert np.any(runs["150"].saturated_fraction > 0)
    assert not np.any(runs["40"].saturated_fraction > 0)


def test_saturation_amplifies_tracking_errors(setup):
    """Thesis: "the tracking errors were amplified at the saturation regions": at 150 mm/s the largest
    Cartesian tracking error is more than 100x the optimized feed's (the unsaturated SMC error is the
    friction transient, tens of um; a saturated axis falls behind by millimetres)."""
    _, _, _, runs = setup
    assert runs["150"].max_error()[:3].max() > 100 * runs["optimized"].max_error()[:3].max()


def test_joint_reference_rejects_contour_controller_and_bad_limits(setup):
    """A joint-only reference has no Frenet frame: the contour controller refuses it (ParameterError),
    and u_max must be positive per axis."""
    plant, _, scheds, _ = setup
    ref = joint_reference(scheds["40"].trajectory, 1e-3)
    with pytest.raises(ParameterError, match="joint-only"):
        simulate_closed_loop(plant, ref, table_5_3())
    with pytest.raises(ParameterError, match="u_max"):
        simulate_closed_loop(plant, ref, table_5_2(), u_max=[1.0, 1.0, -1.0, 1.0, 1.0])
    with pytest.raises(ParameterError, match="one limit per axis"):
        simulate_closed_loop(plant, ref, table_5_2(), u_max=[1.0, 1.0])


def test_divergence_under_saturation_is_flagged_with_its_time(setup):
    """With a 1 mm divergence limit the saturated 150 mm/s run is flagged diverged, at a time inside a
    stretch where an axis is at its amplifier limit, and the log it returns (up to the flag) is finite."""
    plant, u_max, scheds, runs = setup
    r = feed_tracking(scheds["150"].trajectory, plant, u_max, divergence_limit=1.0)
    assert r.diverged and np.isfinite(r.diverged_at)
    assert np.all(np.isfinite(r.axis_error)) and np.all(np.isfinite(r.u))
    assert np.abs(r.axis_error).max() <= 1.0 + 1e-9
    sat_t = runs["150"].t[runs["150"].saturated.any(axis=1)]
    assert sat_t.min() <= r.diverged_at <= sat_t.max()


def test_non_finite_or_ragged_reference_raises(setup):
    """Bad reference rows raise ParameterError naming the field and the first bad sample."""
    import equinox as eqx
    import jax.numpy as jnp

    plant, _, scheds, _ = setup
    ref = joint_reference(scheds["40"].trajectory, 1e-3)
    bad = eqx.tree_at(lambda r: r.qd, ref, ref.qd.at[7, 2].set(jnp.nan))
    with pytest.raises(ParameterError, match=r"qd is not finite at sample 7"):
        simulate_closed_loop(plant, bad, table_5_2())
    short = eqx.tree_at(lambda r: r.qdd, ref, ref.qdd[:-1])
    with pytest.raises(ParameterError, match="qdd has"):
        simulate_closed_loop(plant, short, table_5_2())
