"""Issue 14 item 8 (part): a config identifies a drive and runs its path through it in the same run."""

import pytest

from research.errors import ConfigError
from research.experiments.config import load_config
from research.experiments.evaluate import evaluate

CONFIG = '''
name = "identified_diamond"
reproduces = "beyond the papers: diamond through the drive identified from a synthetic Table 6.1 log"
metrics = ["max_tracking_error", "wn_error", "zeta_error", "p_error"]

[path]
name = "diamond"

[interpolator]
kind = "fir"
feed_mm_per_s = 250.0
delays_ms = [148.0, 89.0]
tolerance_um = 500.0

[drive]
model = "{model}"
settle_time_s = 0.3

[identification]
method = "{method}"
n_moves = 25
noise_um = 2.0
seed = 1
'''


def _run(tmp_path, model, method="simulation_error"):
    f = tmp_path / f"{model}.toml"
    f.write_text(CONFIG.format(model=model, method=method))
    cfg, base = load_config(f)
    return evaluate(cfg, base).record["scalars"]


def test_path_through_the_identified_drive_matches_the_true_drive(tmp_path):
    """Independent check: the same diamond through the true catalog drive (Table 6.1, the synthetic log's
    source) gives the same max tracking error within 1 %; the identified poles are within 1 %."""
    ident = _run(tmp_path, "identified")
    truth = _run(tmp_path, "sencer2009_table6_1")
    assert ident["max_tracking_error"] == pytest.approx(truth["max_tracking_error"], rel=0.01)
    assert max(ident["wn_error"], ident["zeta_error"], ident["p_error"]) < 0.01


def test_identified_drive_needs_the_simulation_error_fit(tmp_path):
    f = tmp_path / "bad.toml"
    f.write_text(CONFIG.format(model="identified", method="ls"))
    with pytest.raises(ConfigError, match="identified"):
        load_config(f)
