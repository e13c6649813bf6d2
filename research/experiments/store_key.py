"""Keys of the results store (:mod:`research.experiments.store`): the SHA-256 of the result-relevant part
of a config, the code version (a hash of the package's source) and the bytes of every input file.
"""

from __future__ import annotations

import hashlib
import json
from functools import lru_cache
from pathlib import Path

import numpy as np

import research

#: fields of a config that do not change its results (not hashed)
COSMETIC = ("name", "reproduces", "description", "output", "sweep", "paper")


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
    return hashlib.sha256(json.dumps(payload, sort_keys=True, default=json_default).encode()).hexdigest()


def json_default(x):
    if isinstance(x, np.ndarray) or hasattr(x, "__array__"):
        return np.asarray(x).tolist()
    if isinstance(x, (np.floating, np.integer, np.bool_)):
        return x.item()
    if isinstance(x, Path):
        return str(x)
    raise TypeError(f"not JSON serializable: {type(x).__name__}")
