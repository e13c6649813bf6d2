"""The ``[control]`` stage (issue 17: "Everything is reachable from an experiment config (controller kind
and gains, feed, path)"): validation, the thesis' default gains, and the Table 5.4 comparison run from
configs. Expected values are the thesis' printed tables (quoted) or properties it states."""

import numpy as np
import pytest

from research.errors import ConfigError, UnstableGainsError
from research.experiments.config import validate
from research.experiments.evaluate import evaluate
from research.experiments.stage_control import controller_from_config

#: a friction per axis [V], given so that the tests skip the Fig 5.7 identification (any value would do:
#: both controllers see the same disturbance)
COULOMB = [0.3, 0.3, 0.3, 0.02, 0.02]


def config(**control):
    return validate({"name": "t", "reproduces": "-", "control": control}, "t.toml")


@pytest.mark.parametrize("control, message", [
    ({"controler": "siso"}, r"key 'control.controler': unknown key \(typo\? did you mean 'controller'\?\)"),
    ({"controller": "pid"}, r"key 'control.controller'"),
    ({"controller": "siso", "tip_Ks": [1.0, 1.0, 1.0]}, r"key 'control.tip_Ks': .*tip_\* gains belong to controller = \"contour\" \(thesis Table 5.3"),
    ({"controller": "siso", "orientation_weights_per_s": [3.0, 3.0]}, r"orientation_weights_per_s belongs to"),
    ({"siso_Ks": [1.0, 2.0]}, r"key 'control.siso_Ks'"),
    ({"orientation_weights_per_s": [-1.0, 0.0]}, r"W must be >= 0"),
    ({"amplifier_limit_V": 10.0, "mirror_passes": 1}, r"amplifier_limit_V with mirror_passes > 0"),
    ({"feed_mm_per_s": "50 mm/s"}, r"key 'control.feed_mm_per_s'"),
    # the contour controller does not use the SISO X, Y, Z gains: setting siso_* with it names the key
    # (thesis Table 5.2 lists the SISO gains per axis X Y Z A C, Table 5.3 the contour controller's per Frenet direction and A, C)
    ({"siso_Ks": [7.0, 5.0, 5.0, 0.5, 1.0]}, r"key 'control.siso_Ks': .*controller = \"contour\" does not use the SISO gains \(thesis Table 5.2"),
    ({"controller": "contour", "siso_Gamma": [25.0, 30.0, 15.0, 3.0, 3.0]}, r"key 'control.siso_Gamma': .*rotary_Gamma"),
    ({"controller": "contour", "siso_bandwidth_rad_per_s": [200.0] * 5}, r"key 'control.siso_bandwidth_rad_per_s'"),
    ({"controller": "siso", "rotary_Ks": [0.5, 1.0]}, r"key 'control.rotary_Ks': .*rotary_\* gains belong to"),
    # cases: each merged with the table and validated again, the case and key named
    ({"cases": [{"label": "a"}, {"label": "a"}]}, r"key 'control.cases\[1\]'.*duplicate label"),
    ({"cases": [{"label": "a", "ratio_to": ["b"]}]}, r"ratio_to 'b' is not another case's label"),
    ({"cases": [{"label": "a", "controller": "siso", "siso_Ks": [1.0, 2.0]}]}, r"cases\[0\].*'a'.*key 'siso_Ks'"),
    ({"cases": [{"label": "a", "controller": "siso", "orientation_weights_per_s": [3.0, 3.0]}]},
     r"'a'.*orientation_weights_per_s belongs to"),
    ({"cases": [{"label": "a", "coulomb_V": COULOMB}]}, r"key 'control.cases\[0\].coulomb_V'"),
    ({"cases": [{"label": "Fast run"}]}, r"key 'control.cases\[0\].label'"),
])
def test_control_table_is_validated(control, message):
    with pytest.raises(ConfigError, match=message):
        config(**control)


def test_default_gains_are_the_thesis_tables():
    """Thesis Table 5.2: "omega_n 200 200 180 150 200 rad/s, Ks 7 5 5 0.5 1, Gamma 25 30 15 3 3";
    Table 5.3: tangent / normal / binormal wn 100 230 230 rad/s, Ks 2 4 4, Gamma 10 20 20; A, C 150 / 200
    rad/s, Ks 0.5 / 1, Gamma 3 / 3."""
    siso = controller_from_config(config(controller="siso").control)
    np.testing.assert_array_equal(np.asarray(siso.lam), [200, 200, 180, 150, 200])
    np.testing.assert_array_equal(np.asarray(siso.Ks), [7, 5, 5, 0.5, 1])
    np.testing.assert_array_equal(np.asarray(siso.Gamma), [25, 30, 15, 3, 3])
    cc = controller_from_config(config(orientation_weights_per_s=[3.0, 4.0]).control)
    np.testing.assert_array_equal(np.asarray(cc.tip.wn), [100, 230, 230])
    np.testing.assert_array_equal(np.asarray(cc.tip.Ks), [2, 4, 4])
    np.testing.assert_array_equal(np.asarray(cc.tip.Gamma), [10, 20, 20])
    np.testing.assert_array_equal(np.asarray(cc.rotary.lam), [150, 200])
    np.testing.assert_array_equal(np.asarray(cc.W), [3.0, 4.0])
    table_5_5 = controller_from_config(config(tip_bandwidth_rad_per_s=[70.0, 230.0, 230.0]).control)
    np.testing.assert_array_equal(np.asarray(table_5_5.tip.wn), [70, 230, 230])
    rotary = controller_from_config(config(rotary_Ks=[0.6, 1.2]).control)
    np.testing.assert_array_equal(np.asarray(rotary.rotary.Ks), [0.6, 1.2])
    np.testing.assert_array_equal(np.asarray(rotary.rotary.lam), [150, 200])


def test_cases_are_the_table_with_their_keys():
    """A case is the [control] table with the case's keys replaced (and only those)."""
    cc = config(feed_mm_per_s=60.0, cases=[{"label": "siso", "controller": "siso"},
                                            {"label": "slow", "tip_bandwidth_rad_per_s": [70.0, 230.0, 230.0],
                                             "feed_mm_per_s": 50.0}]).control
    runs = cc.case_configs()
    assert list(runs) == ["siso", "slow"]
    assert runs["siso"].controller == "siso" and runs["siso"].feed_mm_per_s == 60.0
    assert runs["slow"].controller == "contour" and runs["slow"].feed_mm_per_s == 50.0
    assert runs["slow"].tip_bandwidth_rad_per_s == [70.0, 230.0, 230.0] and runs["siso"].cases is None


def test_unstable_gains_from_a_config_name_the_eigenvalue():
    """Issue 17, bad input: "Unstable gain sets (state which eigenvalue)". Table 5.2's X gains are unstable
    at the thesis' 1 ms period (research.control._study docstring: |z| = 3.78 for X)."""
    cfg = config(controller="siso", control_period_ms=1.0, coulomb_V=COULOMB)
    with pytest.raises(UnstableGainsError, match=r"\|z\|"):
        evaluate(cfg, ".")


def test_contour_controller_beats_siso_from_configs():
    """Thesis Table 5.4 at 80 mm/s: max tool-tip contour error 0.101 mm with the proposed controller against
    0.412 mm with SISO SMC. From one config with two cases that differ only in ``controller``, the contour
    controller's maximum and mean tool-tip contour errors are below SISO's (the thesis' claim; the ratio itself
    is a model prediction, see the README's ch 5 section), both loops stay bounded, and each case's results
    equal a single-run config of the same keys (cases only name the runs)."""
    ev = evaluate(config(feed_mm_per_s=80.0, coulomb_V=COULOMB,
                         cases=[{"label": "siso", "controller": "siso"},
                                {"label": "contour", "controller": "contour", "ratio_to": ["siso"]}]), ".")
    s = ev.record["scalars"]
    for kind in ("siso", "contour"):
        assert s[f"{kind}.diverged"] == 0.0
        assert ev.arrays[f"control.{kind}.axis_error"].shape[1] == 5
        assert ev.record["details"]["control"]["cases"][kind]["controller"] == kind
    assert s["contour.tip_contour_error_max"] < s["siso.tip_contour_error_max"]
    assert s["contour.tip_contour_error_mean"] < s["siso.tip_contour_error_mean"]
    assert s["contour.tip_contour_error_max_ratio.siso"] == s["contour.tip_contour_error_max"] / s["siso.tip_contour_error_max"]
    assert s["contour.rotary_axis_error_max_ratio.siso.a"] == pytest.approx(1.0, abs=1e-12)  # W = 0: A, C as SISO
    assert "siso.tip_contour_error_max_ratio.contour" not in s  # only the ratios a case asks for
    assert ev.record["units"]["contour.axis_error_max_ratio.siso.x"] == "-"
    single = evaluate(config(controller="siso", feed_mm_per_s=80.0, coulomb_V=COULOMB), ".").record["scalars"]
    assert single["tip_contour_error_max"] == s["siso.tip_contour_error_max"]
