"""Content-addressed results store: one folder per result, named by a hash of what produced it.

The key is the SHA-256 of (the result-relevant part of the config, the code version, the bytes of
every input file), so a re-run with the same inputs finds its result instead of recomputing it, and
a change of config, code or data gives a new entry. Entries are written in open formats
(``record.json``; ``arrays.npz`` for arrays; ``figure.png``, ``trajectory.npz``) plus a
``manifest.json`` holding the SHA-256 and size of every other file.

Guarantees:

- **atomic**: an entry is written into a temporary folder next to its final place, every file and the
  folder are fsynced, then the folder is renamed into place (and the parent fsynced): after a crash or
  power loss an entry is complete or absent, never half-written.
- **checksummed**: :meth:`ResultStore.get` verifies the manifest (its own checksum, then every file
  present, same size and SHA-256); an entry that fails is a miss (logged with its folder on the ``research.experiments.store``
  logger), the result is recomputed and :meth:`ResultStore.put` replaces the bad entry.
- **resumable**: a run or sweep stores every finished point or chunk as its own entry, so an
  interrupted one recomputes only what is missing.
- a full disk, a missing permission or a read-only file system raises
  :class:`~research.errors.StoreError` naming the folder, and leaves no partial entry.

:func:`verify_store` / :func:`gc_store` (``python -m research store verify|gc``) check every entry and
remove bad entries and the leftovers of interrupted writes.

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
import logging
import os
import shutil
import tempfile
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from research.errors import StoreError
from research.experiments import json_text
from research.experiments.store_io import TMP_SUFFIX, atomic_write, fsync_dir, store_error, write_synced
from research.experiments.store_key import COSMETIC, code_version, file_digest, json_default, result_key

#: the keys (:mod:`~research.experiments.store_key`) and durable writes (:mod:`~research.experiments.store_io`)
#: are importable from here as before
__all__ = ["COSMETIC", "MANIFEST", "MANIFEST_FORMAT", "Entry", "Problem", "ResultStore", "atomic_write", "code_version",
           "file_digest", "gc_store", "result_key", "verify_store"]

#: name of the checksum manifest inside every entry, and its format version
MANIFEST = "manifest.json"
MANIFEST_FORMAT = 1
#: suffix of the folders of replaced bad entries, like ``TMP_SUFFIX`` removed by :func:`gc_store`
_TRASH_SUFFIX = ".bad"

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class Entry:
    """A verified stored result: its key, folder, JSON record and manifest (arrays and files on demand).

    Files are read through :meth:`read_bytes`, which checks them against the manifest again, so a file
    damaged after :meth:`ResultStore.get` raises :class:`~research.errors.StoreError` instead of being
    served.
    """

    key: str
    folder: Path
    record: dict
    manifest: dict = field(default_factory=dict, repr=False)

    def read_bytes(self, name: str) -> bytes:
        """The bytes of file ``name`` of the entry, checked against its manifest checksum (:meth:`chunks`
        joined).

        Raises:
            StoreError: the file is not in the manifest, unreadable, or no longer matches it.
        """
        return b"".join(self.chunks(name))

    def chunks(self, name: str, size: int = 1 << 20):
        """The bytes of file ``name`` in pieces of ``size``, checked against its manifest checksum as
        they are read: a generator for :func:`~research.experiments.store_io.atomic_write`, which
        then never holds the whole file (a long program's ``trajectory.npz`` is hundreds of MB).

        Raises (once the whole file has been read, or at once if it cannot be opened):
            StoreError: the file is not in the manifest, unreadable, or no longer matches it; a
            target written from it is then left as it was.
        """
        meta = self.manifest.get("files", {}).get(name)
        if meta is None:
            raise StoreError(f"{self.folder}: the entry has no file {name!r} (files: {sorted(self.manifest.get('files', {}))})")
        digest, total = hashlib.sha256(), 0
        try:
            for piece in _pieces(self.folder / name, size):
                digest.update(piece)
                total += len(piece)
                yield piece
        except OSError as e:
            raise StoreError(f"{self.folder / name}: cannot read stored file ({e.strerror or e})") from None
        if total != meta["bytes"] or digest.hexdigest() != meta["sha256"]:
            raise StoreError(f"{self.folder / name}: stored file changed since it was written (checksum mismatch); "
                             "run `python -m research store gc` and re-run")

    def arrays(self) -> dict[str, np.ndarray]:
        """The ``arrays.npz`` of the entry (empty when it has none), checksum-verified."""
        if "arrays.npz" not in self.manifest.get("files", {}):
            return {}
        with np.load(io.BytesIO(self.read_bytes("arrays.npz")), allow_pickle=False) as data:
            return {k: data[k] for k in data.files}

    def file(self, name: str) -> Path | None:
        """An extra file of the entry (listed in its manifest), or ``None``."""
        return self.folder / name if name in self.manifest.get("files", {}) else None


@dataclass(frozen=True)
class Problem:
    """A bad entry or leftover found by :func:`verify_store`: its folder and what is wrong."""

    folder: Path
    reason: str


class ResultStore:
    """The store under ``root`` (created on first write)."""

    def __init__(self, root: str | Path):
        self.root = Path(root)

    def folder(self, key: str) -> Path:
        if not _is_key(key):
            raise StoreError(f"{self.root}: store keys are 64 lowercase hex digits, got {key!r}")
        return self.root / key[:2] / key

    def get(self, key: str) -> Entry | None:
        """The verified entry for ``key``, or ``None`` (absent, or damaged: logged as a warning).

        Raises:
            StoreError: the entry exists but cannot be read (permissions, I/O error).
        """
        folder = self.folder(key)
        if not folder.exists():
            return None
        entry, reason = _load(key, folder)
        if entry is None:
            log.warning("results store: damaged entry %s (%s); it is treated as missing, recomputed and replaced",
                        folder, reason)
        return entry

    def put(self, key: str, record: dict, arrays: dict[str, np.ndarray] | None = None,
            files: dict[str, bytes] | None = None) -> Entry:
        """Write an entry atomically (temporary folder, fsync, rename, manifest of checksums).

        A valid entry already there wins (it is returned, the new one dropped); a damaged one is replaced.

        Args:
            record: JSON-ready result (``record.json``).
            arrays: saved as ``arrays.npz``.
            files: extra files ``{name: bytes}`` (e.g. ``figure.png``); plain names only.

        Raises:
            StoreError: the store cannot be written (full disk, permissions); no partial entry is left.
        """
        final = self.folder(key)
        contents = {"record.json": json_text.dumps(record, indent=1, default=json_default).encode()}
        if arrays:
            buf = io.BytesIO()
            np.savez(buf, **{k: np.asarray(v) for k, v in arrays.items()})
            contents["arrays.npz"] = buf.getvalue()
            buf = None  # (its own copy)
        for name, data in (files or {}).items():
            _check_name(final, name)
            contents[name] = bytes(data)
        existing, _ = _load(key, final) if final.exists() else (None, "")
        if existing is not None:
            return existing
        tmp = None
        try:
            final.parent.mkdir(parents=True, exist_ok=True)
            tmp = Path(tempfile.mkdtemp(dir=final.parent, prefix=f".{key[:12]}.", suffix=TMP_SUFFIX))
            for name, data in contents.items():
                write_synced(tmp / name, data)
            write_synced(tmp / MANIFEST, _manifest(key, contents))
            os.chmod(tmp, 0o755)
            fsync_dir(tmp)
            self._install(key, tmp, final)
            tmp = None
            fsync_dir(final.parent)
        except OSError as e:
            raise store_error(final, e) from None
        finally:
            if tmp is not None:
                shutil.rmtree(tmp, ignore_errors=True)
        entry, reason = _load(key, final)
        if entry is None:
            raise StoreError(f"{final}: entry failed verification right after it was written ({reason})")
        return entry

    def _install(self, key: str, tmp: Path, final: Path) -> None:
        """Rename ``tmp`` to ``final``; a damaged entry in the way is moved aside and deleted first."""
        try:
            os.rename(tmp, final)
            return
        except OSError:
            if not final.exists():
                raise
        if _load(key, final)[0] is not None:  # a concurrent writer got there first with a good entry
            shutil.rmtree(tmp, ignore_errors=True)
            return
        trash = final.parent / f".{key[:12]}.{os.getpid()}{_TRASH_SUFFIX}"
        shutil.rmtree(trash, ignore_errors=True)
        os.rename(final, trash)
        os.rename(tmp, final)
        log.warning("results store: replaced damaged entry %s", final)
        shutil.rmtree(trash, ignore_errors=True)

    def add_file(self, key: str, name: str, data: bytes) -> Path:
        """Attach (or replace) a file of an existing, valid entry: atomic file write, then atomic manifest update.

        Raises:
            StoreError: no valid entry for ``key``, a bad name, or the store cannot be written.
        """
        folder = self.folder(key)
        _check_name(folder, name)
        entry, reason = _load(key, folder) if folder.exists() else (None, "no such entry")
        if entry is None:
            raise StoreError(f"{folder}: cannot attach {name!r}: {reason}")
        files = dict(entry.manifest["files"])
        files[name] = {"sha256": hashlib.sha256(data).hexdigest(), "bytes": len(data)}
        manifest = dict(entry.manifest) | {"files": files}
        manifest["self_sha256"] = _self_digest(manifest)
        target = atomic_write(folder / name, data)
        atomic_write(folder / MANIFEST, json.dumps(manifest, indent=1, sort_keys=True).encode())
        return target

    def keys(self) -> list[str]:
        """Keys of every entry folder under the store (valid or not)."""
        if not self.root.is_dir():
            return []
        return sorted(p.name for d in self.root.iterdir() if d.is_dir() and len(d.name) == 2
                      for p in d.iterdir() if p.is_dir() and _is_key(p.name) and p.name[:2] == d.name)


def verify_store(root: str | Path) -> tuple[int, list[Problem]]:
    """Check every entry of the store under ``root`` against its manifest.

    Returns:
        ``(valid entries, problems)``: damaged entries, and leftovers of interrupted writes
        (temporary or set-aside folders) and stray files, each with the reason.
    """
    root = Path(root)
    problems, good = [], 0
    if not root.exists():
        return 0, []
    if not root.is_dir():
        raise StoreError(f"{root}: not a folder")
    try:
        for d in sorted(root.iterdir()):
            if not (d.is_dir() and len(d.name) == 2):
                problems.append(Problem(d, "not a store shard folder (stray file or folder)"))
                continue
            for p in sorted(d.iterdir()):
                if p.name.endswith((TMP_SUFFIX, _TRASH_SUFFIX)):
                    problems.append(Problem(p, "leftover of an interrupted write"))
                elif not (p.is_dir() and _is_key(p.name) and p.name[:2] == d.name):
                    problems.append(Problem(p, "not a store entry (stray file or folder)"))
                else:
                    entry, reason = _load(p.name, p)
                    if entry is None:
                        problems.append(Problem(p, reason))
                    else:
                        good += 1
    except OSError as e:
        raise store_error(root, e, "read") from None
    return good, problems


def gc_store(root: str | Path, *, dry_run: bool = False, stale_code: bool = False) -> tuple[list[Problem], list[Path]]:
    """Remove what :func:`verify_store` finds (damaged entries, leftovers) and, with ``stale_code``, every
    entry written by another code version than :func:`code_version` (which no run can hit again).

    Returns:
        ``(problems removed, stale entries removed)``; nothing is removed with ``dry_run``.
    """
    _, problems = verify_store(root)
    stale = []
    if stale_code:
        store = ResultStore(root)
        for key in store.keys():
            entry, _ = _load(key, store.folder(key))
            if entry is not None and entry.manifest.get("code_version") != code_version():
                stale.append(entry.folder)
    if not dry_run:
        try:
            for p in [q.folder for q in problems] + stale:
                if p.is_dir() and not p.is_symlink():
                    shutil.rmtree(p)
                else:
                    p.unlink(missing_ok=True)
        except OSError as e:
            raise store_error(Path(root), e) from None
    return problems, stale


# -- helpers -----------------------------------------------------------------------------------------
def _is_key(name) -> bool:
    return isinstance(name, str) and len(name) == 64 and all(c in "0123456789abcdef" for c in name)


def _check_name(folder: Path, name) -> None:
    if (not isinstance(name, str) or name in ("", ".", "..", MANIFEST, "record.json") or "/" in name
            or "\\" in name or "\0" in name or name.endswith((TMP_SUFFIX, _TRASH_SUFFIX))):
        raise StoreError(f"{folder}: bad entry file name {name!r}; expected a plain file name "
                         f"other than {MANIFEST!r} and 'record.json'")


def _manifest(key: str, contents: dict[str, bytes]) -> bytes:
    files = {n: {"sha256": hashlib.sha256(d).hexdigest(), "bytes": len(d)} for n, d in contents.items()}
    doc = {"format": MANIFEST_FORMAT, "key": key, "code_version": code_version(), "files": files}
    return json.dumps(doc | {"self_sha256": _self_digest(doc)}, indent=1, sort_keys=True).encode()


def _self_digest(doc: dict) -> str:
    """SHA-256 of a manifest's canonical JSON without its own ``self_sha256`` (layout changes do not count)."""
    body = {k: v for k, v in doc.items() if k != "self_sha256"}
    return hashlib.sha256(json.dumps(body, sort_keys=True).encode()).hexdigest()


def _digest(path: Path, keep: bool = False, size: int = 1 << 20) -> tuple[int, str, bytes | None]:
    """``(bytes, SHA-256 hex digest, the bytes if keep else None)`` of a file read in pieces of
    ``size`` (a long program's ``trajectory.npz`` is hundreds of MB: not held to be checked)."""
    digest, total, kept = hashlib.sha256(), 0, []
    for piece in _pieces(path, size):
        digest.update(piece)
        total += len(piece)
        if keep:
            kept.append(piece)
    return total, digest.hexdigest(), b"".join(kept) if keep else None


def _pieces(path: Path, size: int):
    """The bytes of the file ``path`` in pieces of ``size``."""
    with open(path, "rb") as f:
        while piece := f.read(size):
            yield piece


def _load(key: str, folder: Path) -> tuple[Entry | None, str]:
    """``(entry, "")`` if ``folder`` holds a complete entry matching its manifest, else ``(None, reason)``.

    Raises:
        StoreError: the folder exists but cannot be read (permissions, I/O error).
    """
    try:
        try:
            manifest = json.loads((folder / MANIFEST).read_bytes())
        except FileNotFoundError:
            return None, f"no {MANIFEST} (incomplete or pre-manifest entry)"
        except (ValueError, UnicodeDecodeError) as e:
            return None, f"unreadable {MANIFEST} ({e})"
        files = manifest.get("files") if isinstance(manifest, dict) else None
        if (not isinstance(files, dict) or manifest.get("key") != key or manifest.get("format") != MANIFEST_FORMAT
                or "record.json" not in files):
            return None, f"{MANIFEST} is not a manifest of key {key[:12]}"
        if manifest.get("self_sha256") != _self_digest(manifest):
            return None, f"{MANIFEST} does not match its own checksum (edited or damaged)"
        record = None
        for name, meta in files.items():
            if not (isinstance(meta, dict) and isinstance(meta.get("sha256"), str) and isinstance(meta.get("bytes"), int)):
                return None, f"{MANIFEST}: bad record for {name!r}"
            try:
                _check_name(folder, name) if name != "record.json" else None
            except StoreError:
                return None, f"{MANIFEST}: bad file name {name!r}"
            try:
                size, digest, data = _digest(folder / name, keep=name == "record.json")
            except FileNotFoundError:
                return None, f"{name} is missing"
            if size != meta["bytes"]:
                return None, f"{name} has {size} bytes, the manifest says {meta['bytes']} (truncated?)"
            if digest != meta["sha256"]:
                return None, f"{name} does not match its SHA-256 checksum"
            if name == "record.json":
                try:
                    record = json.loads(data)
                except (ValueError, UnicodeDecodeError) as e:
                    return None, f"record.json is not JSON ({e})"
        return Entry(key, folder, record, manifest), ""
    except OSError as e:
        raise store_error(folder, e, "read") from None


