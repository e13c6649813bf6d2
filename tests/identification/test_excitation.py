"""The §6.5 identification program: seeded, G-code and Trajectory agree, trapezoidal velocity."""

import numpy as np
import pytest

from research.identification import THESIS_PROGRAM, identification_program
from research.paths import parse_gcode


def test_program_matches_thesis_section_6_5(program, reference):
    # thesis §6.5: 70 random moves within +-50 mm, 250 mm/s, 2500 mm/s^2, Ts = 1 ms
    assert program.n_moves == THESIS_PROGRAM["n_moves"] == 70
    assert np.max(np.abs(program.targets)) <= 50.0
    v, a = np.asarray(reference.v[:, 0]), np.asarray(reference.a[:, 0])
    assert np.max(np.abs(v)) == pytest.approx(250.0, rel=1e-12)
    # trapezoidal velocity: acceleration only takes the values 0 and +-2500 mm/s^2 (jerk unbounded)
    levels = np.unique(np.round(np.abs(a), 6))
    assert set(levels) <= {0.0, 2500.0}
    # every vertex is reached at rest
    idx = np.searchsorted(reference.t, 0.0)
    assert reference.q[idx, 0] == 0.0 and reference.q[-1, 0] == pytest.approx(program.targets[-1], abs=1e-9)
    assert identification_program(0).targets == program.targets  # seeded
    assert identification_program(1).targets != program.targets


def test_gcode_reads_back_as_the_same_moves(program):
    text = program.gcode()
    prog = parse_gcode(text, start=(program.targets[0], 0.0, 0.0))
    np.testing.assert_allclose(prog.polyline.points[:, 0], program.targets, atol=1e-12)
    np.testing.assert_allclose(prog.feeds, 250.0)
