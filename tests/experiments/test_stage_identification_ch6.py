"""The ``[identification_ch6]`` stage's helpers and schema (the stage runs in the figure's paper-number test)."""

import numpy as np
import pytest

from research.errors import ConfigError
from research.experiments.config import input_files, validate
from research.experiments.stage_identification_ch6 import settle_iteration


def test_settle_iteration_is_the_first_from_which_every_pole_stays_in_the_band():
    h = np.ones((10, 4))
    h[:, 1] = [2.0, 1.5, 1.2, 0.9, 1.005, 1.002, 0.999, 1.0, 1.0, 1.0]  # wn enters the 1 % band at iteration 5
    h[2, 3] = 1.5  # p leaves it only at iteration 3
    assert settle_iteration(h) == 5
    assert settle_iteration(np.ones((4, 4))) == 1


@pytest.mark.parametrize("table, match", [
    ({"agreement_hz": 200.0}, r"agreement_hz"),
    ({"methods": ["ls", "ls"]}, r"repeats"),
    ({"methods": ["gradient"]}, r"identification_ch6\.methods"),
    ({"n_moves": 0}, r"identification_ch6\.n_moves"),
])
def test_bad_tables_are_refused(table, match):
    with pytest.raises(ConfigError, match=match):
        validate({"name": "t", "reproduces": "-", "identification_ch6": table}, "t.toml")


def test_the_emps_log_is_an_input_file_checked_at_load(tmp_path):
    raw = {"name": "t", "reproduces": "-", "identification_ch6": {"emps_log_file": "missing.mat"}}
    with pytest.raises(ConfigError, match=r"identification_ch6\.emps_log_file.*file not found"):
        validate(raw, tmp_path / "t.toml")
    (tmp_path / "missing.mat").write_bytes(b"")
    assert input_files(validate(raw, tmp_path / "t.toml")) == {"identification_ch6.emps_log_file": "missing.mat"}
