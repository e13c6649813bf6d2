"""The ``[identified_contour]`` table (thesis §6.5.3 / Fig 6.13): validation and the thesis' defaults. The stage's
run and its thesis numbers are checked by tests/figures/test_paper_numbers.py (figure
sencer2009_fig6_13_identified_5axis), the package function by tests/contour/test_identified_machine.py."""

import pytest

from research.errors import ConfigError
from research.experiments.config import validate

BASE = {"name": "t", "reproduces": "-"}


def test_defaults_are_the_thesis_settings():
    """Thesis §6.5.3: "interpolated with tangential velocity of 75[mm/sec] and acceleration of 1500[mm/sec^2]";
    §6.5: PSO with 200 particles and 100 iterations."""
    ic = validate(BASE | {"identified_contour": {}}, "t.toml").identified_contour
    assert (ic.feed_mm_per_s, ic.acceleration_mm_per_s2, ic.pso_particles, ic.pso_iterations) == (75.0, 1500.0, 200, 100)


@pytest.mark.parametrize("table, message", [
    ({"feed_mm_per_s": 0.075}, r"key 'identified_contour.feed_mm_per_s'"),
    ({"pso_particle": 20}, r"did you mean 'pso_particles'"),
    ({"seed": -1}, r"key 'identified_contour.seed'"),
    ({"pso_iterations": 10.0}, r"give a whole number"),
])
def test_identified_contour_table_is_validated(table, message):
    with pytest.raises(ConfigError, match=message):
        validate(BASE | {"identified_contour": table}, "t.toml")
