"""Durable writes of the results store (:mod:`research.experiments.store`): a file written through a
temporary file, fsynced and renamed (:func:`atomic_write`), a folder fsynced so a rename in it lasts, and
the :class:`~research.errors.StoreError` naming the folder an ``OSError`` becomes (full disk, permissions).
"""

from __future__ import annotations

import errno
import os
import tempfile
from pathlib import Path

from research.errors import StoreError

#: suffix of the temporary folders / files of writes in progress (removed by ``gc_store``)
TMP_SUFFIX = ".tmp"


def atomic_write(target: str | Path, data) -> Path:
    """Write ``data`` (bytes, or an iterable of bytes written in turn) through a temporary file in the
    same folder, fsync, then rename: never a half-written file (an iterable that raises leaves the
    target as it was).

    Raises:
        StoreError: the folder cannot be written (full disk, permissions); the temporary file is removed.
    """
    target = Path(target)
    tmp = None
    try:
        target.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(dir=target.parent, prefix=f".{target.name}.", suffix=TMP_SUFFIX)
        with os.fdopen(fd, "wb") as f:
            for piece in (data,) if isinstance(data, (bytes, bytearray, memoryview)) else data:
                f.write(piece)
            f.flush()
            os.fsync(f.fileno())
        os.chmod(tmp, 0o644)
        os.replace(tmp, target)
        tmp = None
        fsync_dir(target.parent)
    except OSError as e:
        raise store_error(target.parent, e) from None
    finally:
        if tmp is not None:
            Path(tmp).unlink(missing_ok=True)
    return target


def write_synced(path: Path, data: bytes) -> None:
    """Write ``data`` to ``path`` and fsync it (the files of an entry, before its folder is renamed into place)."""
    with open(path, "wb") as f:
        f.write(data)
        f.flush()
        os.fsync(f.fileno())


def fsync_dir(folder: Path) -> None:
    """fsync a folder so a rename in it is durable (a no-op where folders cannot be opened)."""
    try:
        fd = os.open(folder, os.O_RDONLY)
    except OSError:
        return
    try:
        os.fsync(fd)
    except OSError as e:
        if e.errno not in (errno.EINVAL, errno.EBADF, errno.ENOTSUP):
            raise
    finally:
        os.close(fd)


def store_error(folder: Path, e: OSError, action: str = "write") -> StoreError:
    """A :class:`StoreError` naming ``folder`` and the cause (full disk, permissions, ...)."""
    if isinstance(e, StoreError):
        return e
    hints = {errno.ENOSPC: "the disk is full", errno.EDQUOT: "the disk quota is exceeded",
             errno.EACCES: "permission denied", errno.EPERM: "operation not permitted",
             errno.EROFS: "read-only file system"}
    what = hints.get(e.errno, e.strerror or str(e))
    where = f" ({e.filename})" if e.filename and str(e.filename) != str(folder) else ""
    if action == "read":
        return StoreError(f"{folder}: cannot read the results store: {what}{where} (fix permissions, or pass --cache DIR)")
    return StoreError(f"{folder}: cannot write: {what}{where}; nothing partial was left "
                      "(free space or fix permissions, or pass --cache DIR)")
