"""Content-addressed store and the runner on top of it: keys, atomic checksummed entries, instant re-runs,
damaged entries recomputed, disk and permission failures as StoreError."""

import errno
import hashlib
import json
import logging
import os
import tempfile

import numpy as np
import pytest

from research.errors import ConfigError, StoreError
from research.experiments import ResultStore, load_config, result_key, run_experiment
from research.experiments.runner import config_key
from research.experiments.store import gc_store, verify_store

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
    assert config_key(cfg, base, kind="run") == third.key
    assert config_key(cfg, base) != third.key  # a sweep point's key: never the same entry as a run


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


# -- integrity (issue: results store integrity) ---------------------------------------------------------
CORNER_CFG = 'name = "c"\nreproduces = "-"\n[path]\nname = "corner90"\n[output]\nfigure = false\n'


def _run_corner(tmp_path):
    cfg = tmp_path / "c.toml"
    cfg.write_text(CORNER_CFG)
    return run_experiment(cfg, cache_dir=tmp_path / "c", log=lambda s: None)


def _truncate(f, keep=0.5):
    data = f.read_bytes()
    f.write_bytes(data[: int(len(data) * keep)])


@pytest.mark.parametrize("keep", [0.0, 0.5])
def test_truncated_record_json_is_recomputed_and_replaced(tmp_path, keep, caplog):
    """Item 1: an empty or truncated record.json (power loss) is a logged miss; the point is recomputed
    and the entry replaced, so later runs are served from the store again."""
    first = _run_corner(tmp_path)
    store = ResultStore(tmp_path / "c" / "store")
    _truncate(store.folder(first.key) / "record.json", keep)
    with caplog.at_level(logging.WARNING, logger="research.experiments.store"):
        second = _run_corner(tmp_path)
    assert not second.cached and second.record["scalars"] == first.record["scalars"]
    assert str(store.folder(first.key)) in caplog.text
    assert _run_corner(tmp_path).cached
    assert json.loads((store.folder(first.key) / "record.json").read_text())["scalars"] == first.record["scalars"]


def test_truncated_arrays_npz_is_a_miss_and_put_replaces_it(tmp_path):
    """Item 2: a truncated arrays.npz (a vmap chunk) is detected by the checksum, not served."""
    store = ResultStore(tmp_path)
    k = result_key({"chunk": 1}, kind="vmap-chunk")
    cols = {"cycle_time": np.linspace(1.0, 2.0, 50)}
    store.put(k, {"kind": "vmap-chunk"}, cols)
    _truncate(store.folder(k) / "arrays.npz")
    assert store.get(k) is None
    store.put(k, {"kind": "vmap-chunk"}, cols)
    np.testing.assert_array_equal(store.get(k).arrays()["cycle_time"], cols["cycle_time"])


def test_vmap_sweep_recomputes_a_damaged_chunk(tmp_path):
    """Item 2 end to end: the resumed sweep recomputes the chunk instead of raising BadZipFile."""
    from research.experiments.sweep import run_sweep

    cfg = tmp_path / "s.toml"
    cfg.write_text('name = "s"\nreproduces = "-"\n[path]\nname = "diamond"\n[output]\nfigure = false\n'
                   '[sweep]\nengine = "vmap"\nsensitivities = false\nchunk = 4\n[sweep.parameters]\n'
                   '"interpolator.tolerance_um" = [100.0, 200.0]\n')
    kw = dict(cache_dir=tmp_path / "c", figures_dir=tmp_path / "f", log=lambda s: None, show_progress=False)
    first = run_sweep(cfg, **kw)
    assert first.stats["fast"] == 2
    root = tmp_path / "c" / "store"
    npz = [p for p in root.rglob("arrays.npz")]
    assert len(npz) == 1
    _truncate(npz[0])
    again = run_sweep(cfg, **kw)
    assert again.stats["computed"] == 2 and again.stats["cached"] == 0 and again.stats["fast"] == 2
    assert [r["max_corner_error"] for r in again.rows] == pytest.approx([0.1, 0.2], rel=1e-9)  # eq 14: = eps
    assert verify_store(root) == (1, [])


def test_damaged_trajectory_is_not_served_as_cached(tmp_path):
    """Item 3: a truncated trajectory.npz, or one with a flipped byte (same size), fails the manifest."""
    first = _run_corner(tmp_path)
    f = ResultStore(tmp_path / "c" / "store").folder(first.key) / "trajectory.npz"
    good = f.read_bytes()
    for bad in (good[: len(good) // 2], good[:100] + bytes([good[100] ^ 1]) + good[101:]):
        f.write_bytes(bad)
        again = _run_corner(tmp_path)
        assert not again.cached
        assert again.trajectory().n_samples == first.trajectory().n_samples
        assert f.read_bytes() == good  # the replaced entry holds the same (deterministic) bytes


def test_manifest_lists_sha256_of_every_file(tmp_path):
    store = ResultStore(tmp_path)
    k = result_key({"m": 1})
    e = store.put(k, {"v": 1}, {"a": [1.0]}, {"figure.png": b"\x89PNG"})
    manifest = json.loads((e.folder / "manifest.json").read_text())
    assert set(manifest["files"]) == {"record.json", "arrays.npz", "figure.png"}
    body = {k: v for k, v in manifest.items() if k != "self_sha256"}
    assert manifest["self_sha256"] == hashlib.sha256(json.dumps(body, sort_keys=True).encode()).hexdigest()
    for name, meta in manifest["files"].items():
        data = (e.folder / name).read_bytes()
        assert meta == {"sha256": hashlib.sha256(data).hexdigest(), "bytes": len(data)}


def test_disk_full_is_a_store_error_and_leaves_no_partial_entry(tmp_path, monkeypatch):
    import research.experiments.store as store_module

    def full(fd):
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(store_module.os, "fsync", full)
    store = ResultStore(tmp_path / "s")
    k = result_key({"full": 1})
    with pytest.raises(StoreError, match=r"disk is full") as e:
        store.put(k, {"v": 1}, {"a": [1.0, 2.0]})
    assert str(store.folder(k).parent) in str(e.value)
    assert not store.folder(k).exists() and not list(store.folder(k).parent.iterdir())


def test_permission_denied_is_a_store_error_naming_the_folder(tmp_path, monkeypatch):
    def denied(*a, dir=None, **kw):
        raise PermissionError(errno.EACCES, "Permission denied", str(dir))

    monkeypatch.setattr(tempfile, "mkdtemp", denied)
    store = ResultStore(tmp_path / "s")
    k = result_key({"perm": 1})
    with pytest.raises(StoreError, match=r"permission denied") as e:
        store.put(k, {"v": 1})
    assert str(store.folder(k).parent) in str(e.value) and not store.folder(k).exists()


def test_verify_and_gc_find_and_remove_damage(tmp_path):
    store = ResultStore(tmp_path)
    keys = [result_key({"i": i}) for i in range(3)]
    for i, k in enumerate(keys):
        store.put(k, {"i": i}, {"a": np.arange(10.0) + i})
    (store.folder(keys[1]) / "record.json").write_text('{"i": 9}')  # same size, other bytes
    leftover = store.folder(keys[2]).parent / f".{keys[2][:12]}.x.tmp"
    leftover.mkdir()
    good, problems = verify_store(tmp_path)
    assert good == 2 and {p.folder for p in problems} == {store.folder(keys[1]), leftover}
    removed, stale = gc_store(tmp_path)
    assert len(removed) == 2 and stale == []
    assert verify_store(tmp_path) == (2, []) and store.get(keys[1]) is None and store.get(keys[0]).record == {"i": 0}


def test_stored_file_copied_in_pieces_is_checked_and_never_half_written(tmp_path):
    """``Entry.chunks`` through ``atomic_write``: the copy of a stored file equals it; a stored file
    changed after the entry was read (same size, one byte flipped) raises StoreError once it has
    been read through, and the target keeps its old contents with no temporary file left."""
    from research.experiments.store_io import atomic_write

    store = ResultStore(tmp_path / "s")
    data = bytes(range(256)) * 9000  # 2.3 MB: three pieces of 1 MiB
    e = store.put(result_key({"m": 2}), {"v": 1}, None, {"trajectory.npz": data})
    target = tmp_path / "out" / "trajectory.npz"
    atomic_write(target, e.chunks("trajectory.npz"))
    assert target.read_bytes() == data
    f = e.folder / "trajectory.npz"
    f.chmod(0o644)
    f.write_bytes(data[:5] + bytes([data[5] ^ 1]) + data[6:])
    with pytest.raises(StoreError, match="checksum mismatch"):
        atomic_write(target, e.chunks("trajectory.npz"))
    assert target.read_bytes() == data
    assert sorted(p.name for p in target.parent.iterdir()) == ["trajectory.npz"]


def test_readable_json_is_json_dumps_with_number_lists_inline():
    """``json_text.dumps`` parses back to what ``json.dumps`` writes (numbers in the same ``repr``
    digits, NaN and inf as ``json`` writes them, bools and strings in lists left as they are, NumPy
    scalars through ``default``), and a list of numbers takes one line where ``json.dumps(indent=2)``
    takes one per item."""
    import json

    from research.experiments import json_text
    from research.experiments.store_key import json_default

    rng = np.random.default_rng(3)
    doc = {"scalars": {"t": 1.25, "n": 3}, "corners": rng.normal(size=500).tolist(), "flags": [True, False],
           "mixed": [1, "a", [2.0, 3.0]], "rows": [{"x": [0.1, 1e-300, float("nan"), float("inf")]}],
           "np": [np.float64(0.5), np.int64(7)], "empty": [], "text": "a \"quoted\" [1, 2]"}
    text = json_text.dumps(doc, indent=2, default=json_default)
    want = json.dumps(doc, indent=2, default=json_default)
    assert json.dumps(json.loads(text)) == json.dumps(json.loads(want))
    assert len(text.splitlines()) < 40 < len(want.splitlines())
