"""Content-addressed store and the runner on top of it: keys, atomic entries, instant re-runs."""

import os

import pytest

from research.errors import ConfigError
from research.experiments import ResultStore, load_config, result_key, run_experiment
from research.experiments.runner import config_key

GCODE_CFG = 'name = "g"\nreproduces = "-"\n[path]\ngcode = "part.nc"\n[output]\nfigure = false\n'


def test_key_depends_on_config_code_and_input_bytes(tmp_path):
    f = tmp_path / "in.txt"
    f.write_text("a")
    k = result_key({"x": 1}, {"data": f})
    assert k == result_key({"x": 1}, {"data": f}) and len(k) == 64
    assert k != result_key({"x": 2}, {"data": f})
    assert k != result_key({"x": 1}, {"data": f}, kind="chunk")
    f.write_text("b")
    assert k != result_key({"x": 1}, {"data": f})


def test_put_is_atomic_and_first_entry_wins(tmp_path):
    store = ResultStore(tmp_path)
    k = result_key({"y": 1})
    assert store.get(k) is None
    e = store.put(k, {"v": 1.0}, {"a": [1.0, 2.0]}, {"figure.png": b"png"})
    assert e.arrays()["a"].tolist() == [1.0, 2.0] and e.file("figure.png").read_bytes() == b"png"
    store.put(k, {"v": 2.0})
    assert store.get(k).record == {"v": 1.0}
    assert not [p for p in store.folder(k).parent.iterdir() if p.name.endswith(".tmp")]


def test_runner_caches_and_input_file_changes_the_key(tmp_path):
    (tmp_path / "part.nc").write_text("G21 G90\nG1 X10 F1200\nG1 Y10\n")
    cfg_file = tmp_path / "g.toml"
    cfg_file.write_text(GCODE_CFG)
    run = lambda: run_experiment(cfg_file, cache_dir=tmp_path / "c", log=lambda s: None)  # noqa: E731
    first, second = run(), run()
    assert not first.cached and second.cached and first.record["scalars"] == second.record["scalars"]
    assert second.trajectory().n_samples > 10
    (tmp_path / "part.nc").write_text("G21 G90\nG1 X10 F1200\nG1 Y12\n")
    third = run()
    assert not third.cached and third.key != first.key
    cfg, base = load_config(cfg_file)
    assert config_key(cfg, base) == third.key


@pytest.mark.parametrize("text, match", [
    (GCODE_CFG.replace("part.nc", "missing.nc"), r"key 'path.gcode': file not found: .*missing.nc"),
    ('name = "x"\nreproduces = "-"\n[path]\nname = "diamond"\n[interpolator]\nfeed_mm_per_min = 3.0\n',
     r"key 'interpolator.feed_mm_per_min': unknown key \(typo\? did you mean 'feed_mm_per_s'\?\)"),
    ('name = "x"\nreproduces = "-"\n[path]\nname = "diamond"\n[interpolator]\nfeed_mm_per_s = "250 mm/s"\n',
     r"key 'interpolator.feed_mm_per_s': .*plain number, the unit is in the key name"),
    ('name = "x"\nreproduces = "-"\n[path]\nname = "diamond"\n[drive]\nmodes = [{axis = "x", frequency_hz = 11.4, dampng = 0.1}]\n',
     r"key 'drive.modes\[0\].dampng': unknown key \(typo\? did you mean 'damping'\?\)"),
    ('name = "x"\nreproduces = "-"\n[path]\nname = "diamond"\n[drive]\nmodes = [{axis = "z", frequency_hz = 11.4}]\n',
     r"axis 'z' is not an axis of the path"),
    ('name = "x"\nreproduces = "-"\n[identification]\nlog_file = "nope.csv"\n', r"key 'identification.log_file': file not found"),
    ('name = "x"\nreproduces = "-"\n', r"give a \[path\]"),
])
def test_more_config_errors(tmp_path, text, match):
    f = tmp_path / "e.toml"
    f.write_text(text)
    with pytest.raises(ConfigError, match=match) as e:
        load_config(f)
    assert str(f) in str(e.value)


def test_no_stray_permissions(tmp_path):
    e = ResultStore(tmp_path).put(result_key({"z": 1}), {"v": 0})
    assert os.access(e.folder / "record.json", os.R_OK)
