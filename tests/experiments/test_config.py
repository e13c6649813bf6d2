"""Experiment configs: schema errors name the file and the key; the runner writes its outputs."""

import json
from pathlib import Path

import numpy as np
import pytest

from research.errors import ConfigError
from research.experiments import load_config, run_experiment
from research.trajectory import Trajectory

REPO = Path(__file__).resolve().parents[2]
GOOD = """
name = "t"
reproduces = "test"
[path]
name = "corner90"
[interpolator]
feed_mm_per_s = 200.0
delays_ms = [50.0, 30.0]
tolerance_um = 100.0
"""


def write(tmp_path, text, name="exp.toml"):
    f = tmp_path / name
    f.write_text(text)
    return f


@pytest.mark.parametrize(
    "edit, match",
    [
        (("tolerance_um = 100.0", "tolerence_um = 100.0"), r"key 'interpolator.tolerence_um': unknown key \(typo\? did you mean 'tolerance_um'\?\)"),
        (("feed_mm_per_s = 200.0", 'feed_mm_per_s = "fast"'), r"key 'interpolator.feed_mm_per_s': .*number.*'fast'"),
        (("feed_mm_per_s = 200.0", "feed_mm_per_s = -1.0"), r"key 'interpolator.feed_mm_per_s': .*greater than 0"),
        (("delays_ms = [50.0, 30.0]", "delays_ms = [50.0, 0.0]"), r"delays_ms\[1\] must be > 0 ms"),
        (('name = "corner90"', 'name = "circle"'), r"key 'path': unknown path name 'circle'"),
        (('name = "corner90"', 'name = "corner90"\ngcode = "x.nc"'), r"exactly one of name, gcode, points_mm"),
        (('reproduces = "test"', ""), r"key 'reproduces': Field required"),
        (("[interpolator]", "[interpolator"), r"TOML syntax error"),
    ],
)
def test_config_errors_name_file_and_key(tmp_path, edit, match):
    f = write(tmp_path, GOOD.replace(*edit))
    with pytest.raises(ConfigError, match=match) as e:
        load_config(f)
    assert str(f) in str(e.value)


def test_shipped_configs_validate():
    files = sorted((REPO / "experiments").glob("*.toml"))
    assert files
    for f in files:
        cfg, _ = load_config(f)
        assert cfg.reproduces


def test_run_writes_results_and_figure(tmp_path):
    result = run_experiment(write(tmp_path, GOOD), cache_dir=tmp_path / "cache", figures_dir=tmp_path / "figs", log=lambda s: None)
    record = json.loads(result.results_file.read_text())
    assert record["metrics"]["max_corner_error"] == pytest.approx(0.1, rel=1e-6)
    assert record["config"]["interpolator"][0]["delays_ms"] == [50.0, 30.0]
    traj = Trajectory.load(tmp_path / "cache" / "t" / "trajectory.npz")
    assert np.max(np.abs(traj.q[-1] - np.array([0.0, 50.0]))) < 1e-9
    assert result.figure_file.exists() and result.figure_file.stat().st_size > 10_000


def test_gcode_path_uses_program_feeds(tmp_path):
    (tmp_path / "part.nc").write_text("G21 G90\nG1 X10 F1200\nG1 Y10 F600\n")
    text = GOOD.replace('name = "corner90"', 'gcode = "part.nc"').replace("feed_mm_per_s = 200.0\n", "")
    result = run_experiment(write(tmp_path, text), cache_dir=tmp_path / "c", figures_dir=tmp_path / "f", log=lambda s: None)
    np.testing.assert_allclose(result.record["details"]["fir"]["feeds"], [20.0, 10.0])  # mm/min -> mm/s
