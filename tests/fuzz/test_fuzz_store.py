"""Fuzz tests of the results store: random records and arrays round-trip through ``put`` / ``get``;
random damage to any file of an entry (truncation, byte edits, deletion, a stray manifest) is never
served: ``get`` returns ``None`` unless the bytes are unchanged, and ``put`` then restores the entry.

Only :class:`StoreError` may escape (none is expected here: the folder is writable).

Examples per test: ``RESEARCH_FUZZ_EXAMPLES`` (default 60: every put fsyncs, so the file takes about ten
seconds); set it to 10000 for a long run.
"""

from __future__ import annotations

import json
import os
import shutil
import tempfile
from pathlib import Path

import numpy as np
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from research.experiments.store import ResultStore, result_key, verify_store

EXAMPLES = int(os.environ.get("RESEARCH_FUZZ_EXAMPLES", "60"))
FUZZ = settings(max_examples=EXAMPLES, deadline=None, derandomize=EXAMPLES <= 200,
                suppress_health_check=[HealthCheck.too_slow])

JSON = st.recursive(
    st.one_of(st.none(), st.booleans(), st.integers(-2**53, 2**53), st.floats(allow_nan=False, allow_infinity=False),
              st.text(max_size=10)),
    lambda inner: st.one_of(st.lists(inner, max_size=4), st.dictionaries(st.text(max_size=6), inner, max_size=4)),
    max_leaves=12,
)
ARRAYS = st.dictionaries(st.from_regex(r"[a-z][a-z0-9_]{0,7}", fullmatch=True),
                         arrays(st.sampled_from([np.float64, np.int64, np.bool_]), st.integers(0, 20)), max_size=3)
FILES = st.dictionaries(st.sampled_from(["figure.png", "trajectory.npz", "notes.txt"]), st.binary(max_size=200), max_size=2)


def _same(entry, record, arrs, files) -> None:
    assert entry.record == json.loads(json.dumps(record))
    got = entry.arrays()
    assert set(got) == set(arrs)
    for k, v in arrs.items():
        np.testing.assert_array_equal(got[k], v)
        assert got[k].dtype == v.dtype
    for name, data in files.items():
        assert entry.read_bytes(name) == data


@FUZZ
@given(st.dictionaries(st.text(max_size=8), JSON, max_size=5), ARRAYS, FILES)
def test_put_get_round_trip(record, arrs, files):
    root = Path(tempfile.mkdtemp(prefix="fuzz_store_"))
    try:
        store = ResultStore(root)
        key = result_key({"r": json.loads(json.dumps(record))})
        _same(store.put(key, record, arrs, files), record, arrs, files)
        _same(store.get(key), record, arrs, files)
        assert verify_store(root) == (1, [])
    finally:
        shutil.rmtree(root)


DAMAGE = st.sampled_from(["truncate", "edit", "delete", "append", "empty"])


@FUZZ
@given(st.sampled_from(["record.json", "arrays.npz", "figure.png", "manifest.json"]), DAMAGE,
       st.floats(0, 1), st.binary(min_size=1, max_size=3))
def test_damaged_entries_are_never_served_and_put_restores_them(name, damage, where, new):
    root = Path(tempfile.mkdtemp(prefix="fuzz_store_"))
    try:
        store = ResultStore(root)
        key = result_key({"damage": 1})
        record, arrs, files = {"v": [1.5, 2.5], "s": "ok"}, {"a": np.linspace(0, 1, 7)}, {"figure.png": b"\x89PNG" * 5}
        store.put(key, record, arrs, files)
        f = store.folder(key) / name
        data = bytearray(f.read_bytes())
        pos = int(where * (len(data) - 1))
        if damage == "truncate":
            data = data[:pos]
        elif damage == "edit":
            data[pos:pos + 1] = new
        elif damage == "append":
            data += new
        elif damage == "empty":
            data = bytearray()
        if damage == "delete":
            f.unlink()
            changed = True
        else:
            old = f.read_bytes()
            changed = bytes(data) != old
            if name == "manifest.json" and changed:  # layout-only edits (whitespace) leave the same manifest
                try:
                    changed = json.loads(bytes(data)) != json.loads(old)
                except ValueError:
                    pass
            f.write_bytes(bytes(data))
        entry = store.get(key)
        if changed:
            assert entry is None
            assert len(verify_store(root)[1]) == 1
            entry = store.put(key, record, arrs, files)
        _same(entry, record, arrs, files)
        _same(store.get(key), record, arrs, files)
        assert verify_store(root) == (1, [])
    finally:
        shutil.rmtree(root)
