"""The 5-axis ``[path]`` kind and the ``[feedrate]`` stage (issue 16 item 1, thesis ch 3): validation of the tables,
the named 5-axis paths, and the stage's outputs against properties computed independently (the figure configs'
thesis numbers are checked by tests/figures/test_paper_numbers.py)."""

import numpy as np
import pytest

from research.errors import ConfigError
from research.experiments.config import named_axes, validate
from research.experiments.config_feedrate import FeedrateConfig, FeedrateDriveConfig, constant_label
from research.experiments.stage_feedrate import feedrate_stage
from research.paths.five_axis_library import helix_path

BASE = {"name": "t", "reproduces": "-"}
FIVE = {"kind": "five_axis"}


@pytest.mark.parametrize("table, message", [
    ({"path": FIVE}, r"a \[path\] with kind = \"five_axis\" and a \[feedrate\] table go together"),
    ({"path": {"name": "corner90"}, "feedrate": {}}, r"go together"),
    ({"path": FIVE | {"name": "impeller"}, "feedrate": {}}, r"key 'path.name': Input should be 'blade_flank' or 'eq436'"),
    ({"path": FIVE | {"lenght_mm": 300.0}, "feedrate": {}}, r"key 'path.lenght_mm': unknown key \(typo\? did you mean 'length_mm'\?\)"),
    ({"path": FIVE | {"name": "eq436", "length_mm": 300.0}, "feedrate": {}}, r"length_mm = 300 applies to name = \"blade_flank\" only"),
    ({"path": {"kind": "spline"}}, r"key 'path': Input tag 'spline'"),
    ({"path": FIVE, "feedrate": {}, "interpolator": {"kind": "fir"}}, r"a 5-axis \[path\] is scheduled by \[feedrate\] only"),
    ({"path": FIVE, "feedrate": {"constant_feeds_mm_per_s": [0.015]}},
     r"key 'feedrate.constant_feeds_mm_per_s\[0\]': constant_feeds_mm_per_s\[0\] = 0.015 mm/s is outside"),
    ({"path": FIVE, "feedrate": {"constant_feeds_mm_per_s": [15, 15.0]}}, r"repeats a feed"),
    ({"path": FIVE, "feedrate": {"feed_mm_per_s": 9000.0 * 60}}, r"key 'feedrate.feed_mm_per_s'"),
    ({"path": FIVE, "feedrate": {"drive": {"coulomb_V": [1.0, 1.0, 1.0, 0.1]}}}, r"key 'feedrate.drive.coulomb_V'"),
    ({"path": FIVE, "feedrate": {"drive": {"frictoin": "identified"}}}, r"did you mean 'friction'"),
])
def test_five_axis_path_and_feedrate_tables_are_validated(table, message):
    with pytest.raises(ConfigError, match=message):
        validate(BASE | table, "t.toml")


def test_defaults_are_the_thesis_settings_and_the_named_paths_build():
    """Thesis §3.6: "n=276 equally spread points", programmed feed 150 mm/s, the constant 15 mm/s comparison;
    §4.5: the eq 4.36 path's "total distance of travel along the workpiece is about 273.87 [mm]"; the blade stand-in
    is 300 mm like the thesis' impeller path. The axes of a 5-axis path are x, y, z, a, c."""
    cfg = validate(BASE | {"path": FIVE | {"name": "eq436"}, "feedrate": {}}, "t.toml")
    fc = cfg.feedrate
    assert (fc.control_points, fc.feed_mm_per_s, fc.constant_feeds_mm_per_s) == (276, 150.0, [15.0])
    assert named_axes(cfg) == ("x", "y", "z", "a", "c")
    assert abs(cfg.path.build().length - 273.87) < 0.01  # "about", to the last printed digit
    blade = validate(BASE | {"path": FIVE | {"length_mm": 120.0}, "feedrate": {}}, "t.toml").path.build()
    assert abs(blade.length - 120.0) < 1e-6
    assert constant_label(12.5) == "constant_12p5" and constant_label(15.0) == "constant_15"


@pytest.fixture(scope="module")
def stage():
    """A short helix (half a turn), a coarse schedule and two constant feeds: seconds, not the figure's minute."""
    fc = FeedrateConfig(control_points=12, refinements=1, constant_feeds_mm_per_s=[10.0, 150.0], envelope_points=50)
    path = helix_path(turns=0.5)
    return path, fc, feedrate_stage(fc, path)


def test_schedules_agree_with_their_own_definitions(stage):
    """The violation flag is ``limit_ratio > 1 + tolerance``; the time ratio is the constant-feed time over the
    optimized one; a constant feed F cannot cover L in less than L / F; the optimized schedule is no slower than
    the slowest constant feed that holds the limits and holds them itself; the arrays cover the schedules."""
    path, fc, (scalars, details, arrays) = stage
    L = path.length
    assert scalars["feedrate_path_length"] == pytest.approx(L)
    t_opt = scalars["optimized.feedrate_cycle_time"]
    for label in ("optimized", "constant_10", "constant_150"):
        ratio = scalars[f"{label}.feedrate_limit_ratio"]
        assert scalars[f"{label}.feedrate_limits_violated"] == float(ratio > 1 + fc.tolerance)
        assert ratio == pytest.approx(max(max(v) for v in details["schedules"][label]["limit_ratio"].values()))
        t = arrays[f"feedrate.{label}.t"]
        assert t[-1] == pytest.approx(scalars[f"{label}.feedrate_cycle_time"], abs=fc.sample_period_ms * 1e-3)
        assert arrays[f"feedrate.{label}.q"].shape == (t.size, 5)
    for f in (10.0, 150.0):
        label = constant_label(f)
        assert scalars[f"{label}.feedrate_cycle_time"] >= L / f
        assert scalars[f"{label}.feedrate_time_ratio"] == pytest.approx(scalars[f"{label}.feedrate_cycle_time"] / t_opt)
    assert scalars["optimized.feedrate_limits_violated"] == 0.0
    assert scalars["constant_10.feedrate_limits_violated"] == 0.0
    assert t_opt < scalars["constant_10.feedrate_cycle_time"]
    assert arrays["feedrate.envelope.velocity"].shape == (50, 5)


def test_amplifier_limit_is_table_3_1_through_the_plant(stage):
    """``u_max,i = m_i A_i + c_i V_i + d_c,i`` with the printed Table 3.1 velocity / acceleration (X-Z 250 mm/s,
    2000 mm/s^2; A 166 deg/s, 2500 deg/s^2; C 290 deg/s, 2000 deg/s^2) and the given friction; a run saturates
    where its saturated fraction is positive (one constant-feed schedule through the drives)."""
    from research.control import thesis_plant
    from research.experiments.stage_feedrate import _drive
    from research.optimal import constant_feed, table31_limits

    path, _, _ = stage
    dc = FeedrateDriveConfig(control_period_ms=0.25, coulomb_V=[1.0, 1.0, 1.0, 0.05, 0.05])
    limits = table31_limits()
    scalars, details, arrays = _drive(dc, limits, {"constant_150": constant_feed(path, limits, 150.0)})
    plant = thesis_plant()
    V = np.array([250.0, 250.0, 250.0, np.radians(166.0), np.radians(290.0)])
    A = np.array([2000.0, 2000.0, 2000.0, np.radians(2500.0), np.radians(2000.0)])
    expected = np.asarray(plant.m) * A + np.asarray(plant.c) * V + np.asarray(dc.coulomb_V)
    got = [scalars[f"amplifier_limit.{a}"] for a in "xyzac"]
    np.testing.assert_allclose(got, expected, rtol=1e-12)
    assert details["friction"] == "given" and details["u_max_V"] == pytest.approx(expected.tolist())
    for label in ("constant_150",):
        fractions = [scalars[f"{label}.drive_saturated_fraction.{a}"] for a in "xyzac"]
        assert scalars[f"{label}.drive_saturated"] == float(max(fractions) > 0)
        sat = arrays[f"feedrate.{label}.drive.saturated"]
        assert sat.shape == arrays[f"feedrate.{label}.drive.axis_error"].shape
