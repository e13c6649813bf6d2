"""The ``[optimality]`` stage's independent checks and schema (the OCP solves themselves run in the figure's
paper-number test, tests/figures/test_paper_numbers.py)."""

import numpy as np
import pytest

from research.errors import ConfigError
from research.experiments.config import validate
from research.experiments.stage_optimality import cut_length, fir_closed_form
from research.paths import Polyline, named_path


def test_cut_length_of_a_right_angle_by_hand():
    """corner90: two 50 mm lines at 90 deg; interior angle 90 deg, r = eps / sin(45 deg) = eps sqrt 2, so
    L_cut = 2 (50 - eps sqrt 2)."""
    eps = 0.5
    assert cut_length(named_path("corner90"), eps) == pytest.approx(2 * (50 - eps * np.sqrt(2)), rel=1e-12)


def test_cut_length_at_a_straight_vertex_and_a_hairpin():
    """A straight-through vertex (interior angle 180 deg): the crossing may lie eps either side, r = eps, so
    L_cut = 10 - 2 eps (a valid, not tight, bound); a hairpin: r exceeds the segments, nothing below zero."""
    assert cut_length(Polyline([[0.0, 0.0], [3.0, 4.0], [6.0, 8.0]]), 0.5) == pytest.approx(9.0)
    hairpin = Polyline([[0.0, 0.0], [1.0, 0.0], [0.0, 0.01]])  # interior angle ~0.6 deg: r >> the segments
    assert cut_length(hairpin, 0.5) == 0.0


def test_fir_closed_form_on_the_sencer2015_fig4_corner():
    """Sencer 2015 Fig 4: 2.5 mm lines at 90 deg, F = 50 mm/s, T1 = 20 ms, stopping at the corner (tolerance 0):
    T_k = 0, so T = 2 (2.5 / 50) + 20 ms + 20 ms = 140 ms, the paper's 'cycle 140 ms'."""
    from research.interpolators import plan_fir

    path = Polyline([[0.0, 0.0], [2.5, 0.0], [2.5, 2.5]])
    plan = plan_fir(path, 50.0, np.array([0.02]), 0.0)
    assert fir_closed_form(path, plan) == pytest.approx(0.140, abs=1e-12)
    assert float(plan.cycle_time) == pytest.approx(0.140, abs=1e-9)


@pytest.mark.parametrize("table, match", [
    ({"paths": ["corner90", "corner90"]}, r"repeats"),
    ({"paths": ["square"]}, r"optimality\.paths"),
    ({"conventions": ["c"]}, r"optimality\.conventions"),
    ({"delays_ms": [0.148, 0.089]}, r"sample_period_ms"),
])
def test_bad_optimality_tables_are_refused(table, match):
    with pytest.raises(ConfigError, match=match):
        validate({"name": "t", "reproduces": "-", "optimality": table}, "t.toml")
