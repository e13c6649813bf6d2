"""An identified drive in configs (issue 14 item 8, issue 16 item 1): the identification stage stores its model
(``save_identified``) as ``results/<name>/drive_model.json``; a later config runs a path, its contour error and
CEC through that file (``[drive] model = "identified"``, ``identified_file``); a missing or corrupt file is a
``ConfigError`` naming the key and the file."""

import json

import numpy as np
import pytest

from research.drives import virtual_drive
from research.errors import ConfigError
from research.experiments.config import validate
from research.experiments.runner import run_experiment
from research.identification import load_identified

#: a short synthetic log: 4 moves of the thesis §6.5 program through the Table 6.1 drive, noise-free encoder
IDENTIFY = """name = "ident"
reproduces = "-"
[path]
name = "corner90"
[interpolator]
feed_mm_per_s = 100.0
[identification]
method = "simulation_error"
n_moves = 4
[drive]
model = "identified"
[compensation]
[output]
figure = false
"""

USE = """name = "use"
reproduces = "-"
[path]
name = "corner90"
[interpolator]
feed_mm_per_s = 100.0
[drive]
model = "identified"
identified_file = "results/ident/drive_model.json"
[compensation]
[output]
figure = false
"""


def quiet(_):
    pass


def test_identified_model_file_drives_a_later_config(tmp_path):
    """The stored model is the Table 6.1 drive (poles within 1 %: a noise-free log, the thesis' 0.05 um encoder);
    the later config through the file gives the same tracking error and CEC as the identifying run (the file
    holds the exact float64 parameters), is cached, and a changed file changes its key."""
    (tmp_path / "ident.toml").write_text(IDENTIFY)
    first = run_experiment(tmp_path / "ident.toml", cache_dir=tmp_path / "c", results_dir=tmp_path / "results", log=quiet)
    model_file = tmp_path / "results" / "ident" / "drive_model.json"
    fit = load_identified(model_file)
    got = fit.closed_loop_model().pole_parameters()
    true = virtual_drive("sencer2009_table6_1").pole_parameters()
    assert np.allclose(got, true, rtol=1e-2)
    (tmp_path / "use.toml").write_text(USE)
    later = run_experiment(tmp_path / "use.toml", cache_dir=tmp_path / "c", results_dir=tmp_path / "results", log=quiet)
    for k in ("max_tracking_error", "cec_error_before", "cec_error_after"):
        assert later.record["scalars"][k] == pytest.approx(first.record["scalars"][k], rel=1e-12, abs=0)
    assert later.record["inputs"]["drive.identified_file"] == json.loads((tmp_path / "results" / "use" / "results.json")
                                                                          .read_text())["inputs"]["drive.identified_file"]
    again = run_experiment(tmp_path / "use.toml", cache_dir=tmp_path / "c", results_dir=tmp_path / "results", log=quiet)
    assert again.cached and again.key == later.key
    model_file.write_text(model_file.read_text()[:-40])  # truncated: a corrupt file
    with pytest.raises(ConfigError, match=r"key 'drive.identified_file' = 'results/ident/drive_model.json' \(.*drive_model.json\)"
                                          r".*not valid JSON"):
        run_experiment(tmp_path / "use.toml", cache_dir=tmp_path / "c", results_dir=tmp_path / "results", log=quiet)


@pytest.mark.parametrize("drive, extra, message", [
    ({"model": "identified", "identified_file": "none.json"}, {}, r"t.toml: key 'drive.identified_file': file not found: .*none.json"),
    ({"model": "sencer2009_table6_1", "identified_file": "m.json"}, {}, r"identified_file goes with model = \"identified\""),
    ({"model": "identified", "identified_file": "m.json"}, {"identification": {"method": "simulation_error"}},
     r"two sources: drive.identified_file and this config's \[identification\]"),
    ({"model": "identified"}, {}, r"give drive.identified_file"),
])
def test_identified_file_is_validated(tmp_path, drive, extra, message):
    (tmp_path / "m.json").write_text("{}")
    with pytest.raises(ConfigError, match=message):
        validate({"name": "t", "reproduces": "-", "path": {"name": "corner90"}, "drive": drive} | extra, tmp_path / "t.toml")


def test_a_model_that_cannot_drive_the_simulator_names_the_key(tmp_path):
    """A stored file of another format is refused by the loader; the message names the config key and file."""
    (tmp_path / "m.json").write_text(json.dumps({"format": "something else"}))
    cfg = validate({"name": "t", "reproduces": "-", "path": {"name": "corner90"},
                    "drive": {"model": "identified", "identified_file": "m.json"}}, tmp_path / "t.toml")
    from research.experiments.evaluate import evaluate

    with pytest.raises(ConfigError, match=r"key 'drive.identified_file' = 'm.json' \(.*m.json\): .*key 'format'"):
        evaluate(cfg, tmp_path)
