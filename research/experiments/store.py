"""Content-addressed results store: one folder per result, named by a hash of what produced it.

The key is the SHA-256 of (the result-relevant part of the config, the code version, the bytes of
every input file), so a re-run with the same inputs finds its result instead of recomputing it, and
a change of config, code or data gives a new entry. Entries are written in open formats
(``record.json``; ``arrays.npz`` for arrays; ``figure.png``) into a temporary folder that is renamed
into place: an entry is either complete or absent, so an interrupted run or sweep never leaves a
half-written result.

Layout: ``<root>/<key[:2]>/<key>/``.

Example:
    >>> import tempfile
    >>> store = ResultStore(tempfile.mkdtemp())
    >>> k = result_key({"a": 1})
    >>> _ = store.put(k, {"cycle_time": 1.5})
    >>> store.get(k).record["cycle_time"]
    1.5
"""

from __future__ import annotations

import hashlib
import io
import json
import os
import shutil
import tempfile
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

import numpy as np

import research

#: fields of a config that do not change its results (not hashed)
COSMETIC = ("name", "reproduces", "description", "output", "sweep")


@lru_cache(maxsize=1)
def code_version() -> str:
    """``<package version>+<16 hex digits>``: a hash of every ``.py`` file of the ``research`` package
    (path and bytes), so any change of code invalidates stored results."""
    root = Path(research.__file__).resolve().parent
    h = hashlib.sha256()
    for f in sorted(root.rglob("*.py")):
        h.update(f.relative_to(root).as_posix().encode() + b"\0" + f.read_bytes() + b"\0")
    return f"{research.__version__}+{h.hexdigest()[:16]}"


def file_digest(path: str | Path) -> str:
    """SHA-256 of a file's bytes (hex)."""
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def result_key(config: dict, inputs: dict[str, str | Path] | None = None, *, kind: str = "point") -> str:
    """Hex SHA-256 of ``config`` (JSON, sorted keys), :func:`code_version` and the input files' bytes.

    Args:
        config: JSON-ready dictionary of everything that sets the result (no cosmetic fields).
        inputs: ``{name: file}`` read by the computation.
        kind: what the entry holds (``"point"``, ``"chunk"``, ...); part of the key.
    """
    payload = {
        "kind": kind,
        "config": config,
        "code": code_version(),
        "inputs": {k: file_digest(p) for k, p in sorted((inputs or {}).items())},
    }
    return hashlib.sha256(json.dumps(payload, sort_keys=True, default=_json_default).encode()).hexdigest()


@dataclass(frozen=True)
class Entry:
    """A stored result: its key, folder and JSON record (arrays and figure read on demand)."""

    key: str
    folder: Path
    record: dict

    def arrays(self) -> dict[str, np.ndarray]:
        """The ``arrays.npz`` of the entry (empty when it has none)."""
        f = self.folder / "arrays.npz"
        if not f.exists():
            return {}
        with np.load(f, allow_pickle=False) as data:
            return {k: data[k] for k in data.files}

    def file(self, name: str) -> Path | None:
        """An extra file of the entry, or ``None``."""
        f = self.folder / name
        return f if f.exists() else None


class ResultStore:
    """The store under ``root`` (created on first write)."""

    def __init__(self, root: str | Path):
        self.root = Path(root)

    def folder(self, key: str) -> Path:
        return self.root / key[:2] / key

    def get(self, key: str) -> Entry | None:
        """The entry for ``key``, or ``None``."""
        folder = self.folder(key)
        try:
            record = json.loads((folder / "record.json").read_text())
        except (OSError, ValueError):
            return None
        return Entry(key, folder, record)

    def put(self, key: str, record: dict, arrays: dict[str, np.ndarray] | None = None,
            files: dict[str, bytes] | None = None) -> Entry:
        """Write an entry atomically (temporary folder, then rename). An entry already there wins.

        Args:
            record: JSON-ready result (``record.json``).
            arrays: saved as ``arrays.npz``.
            files: extra files ``{name: bytes}`` (e.g. ``figure.png``).
        """
        final = self.folder(key)
        final.parent.mkdir(parents=True, exist_ok=True)
        tmp = Path(tempfile.mkdtemp(dir=final.parent, prefix=f".{key[:12]}.", suffix=".tmp"))
        try:
            if arrays:
                buf = io.BytesIO()
                np.savez(buf, **{k: np.asarray(v) for k, v in arrays.items()})
                (tmp / "arrays.npz").write_bytes(buf.getvalue())
            for name, data in (files or {}).items():
                (tmp / name).write_bytes(data)
            (tmp / "record.json").write_text(json.dumps(record, indent=1, default=_json_default))
            os.chmod(tmp, 0o755)
            os.rename(tmp, final)
        except OSError:
            if not final.exists():
                raise
        finally:
            shutil.rmtree(tmp, ignore_errors=True)
        return Entry(key, final, json.loads((final / "record.json").read_text()))

    def add_file(self, key: str, name: str, data: bytes) -> Path:
        """Attach a file to an existing entry (atomic file write)."""
        return atomic_write(self.folder(key) / name, data)


def atomic_write(target: str | Path, data: bytes) -> Path:
    """Write ``data`` through a temporary file in the same folder, then rename: never a half-written file."""
    target = Path(target)
    target.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=target.parent, prefix=f".{target.name}.", suffix=".tmp")
    try:
        with os.fdopen(fd, "wb") as f:
            f.write(data)
        os.chmod(tmp, 0o644)
        os.replace(tmp, target)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    return target


def _json_default(x):
    if isinstance(x, np.ndarray) or hasattr(x, "__array__"):
        return np.asarray(x).tolist()
    if isinstance(x, (np.floating, np.integer, np.bool_)):
        return x.item()
    if isinstance(x, Path):
        return str(x)
    raise TypeError(f"not JSON serializable: {type(x).__name__}")
