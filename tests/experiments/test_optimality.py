"""Optimality study: both OCPs are lower bounds for every method held to the same limits, and the
vibration-aware one leaves the beams at rest."""

import numpy as np
import pytest

from research.experiments.optimality import PAPER, cam_like_path, format_table, run_path
from research.paths import named_path


@pytest.fixture(scope="module")
def corner90_study():
    # one grid (N = 12) keeps the test short; the study itself refines N until converged
    return run_path("corner90", named_path("corner90"), feed=PAPER["feed"], delays=PAPER["delays"],
                    tolerance=PAPER["tolerance"], start_intervals=12, max_intervals=12, log=lambda s: None)


def test_ocps_are_lower_bounds(corner90_study):
    rows, _ = corner90_study
    for r in rows:
        if r.method != "vibration-aware OCP":
            assert r.ratio_to_ocp >= 1 - 1e-3, r  # within the OCP's dense check
        if r.within_limits:
            assert r.max_corner_error <= PAPER["tolerance"] * 1.01
    by = {(r.convention, r.method): r for r in rows}
    for conv in ("a", "b"):
        # the vibration-aware OCP is the plain one plus constraints: never faster
        assert by[conv, "vibration-aware OCP"].ratio_to_ocp >= 1 - 1e-7
        # ... and leaves no residual vibration (re-simulated on its exact acceleration)
        assert max(by[conv, "vibration-aware OCP"].residual_vibration) < 1e-6
        assert max(by[conv, "time-optimal OCP"].residual_vibration) > 1e-3
        # the FIR's delays sit on the beams' spectral zeros (eq 10): little residual vibration
        assert max(by[conv, "FIR overlap (paper)"].residual_vibration) < 0.1 * max(by[conv, "time-optimal OCP"].residual_vibration)


def test_limit_conventions(corner90_study):
    rows, sticks = corner90_study
    by = {(r.convention, r.method): r for r in rows}
    # (a) the FIR's own peaks: everything holds them
    assert all(r.within_limits for (c, _), r in by.items() if c == "a")
    # (b) the nominal envelope: on corner90 the block is shorter than T1 + T2 in time, so even
    # alone plain overlap doubles the jerk of its axes
    assert by["b", "FIR overlap (paper)"].worst_limit_ratio == pytest.approx(2.0, rel=1e-6)
    assert not by["b", "FIR overlap (paper)"].within_limits
    assert by["b", "FIR overlap, limits held"].within_limits
    table = format_table(rows, sticks)
    assert "time-optimal OCP" in table and "vibration-aware OCP" in table and "T/T_vib" in table
    assert len(sticks) == 4 and all(not y.converged and y.history[-1][0] == 12 for y in sticks)


def test_cam_like_path_is_seeded():
    a, b = cam_like_path(12, seed=3), cam_like_path(12, seed=3)
    np.testing.assert_array_equal(a.points, b.points)
    assert a.n_segments == 12 and np.all((a.lengths >= 2.0) & (a.lengths <= 6.0))
