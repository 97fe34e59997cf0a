"""Write a file so that it is either the old one or the whole new one — never half of it.

A temporary file beside the target (same folder, so same file system), written, fsynced,
renamed over the target (``os.replace`` is atomic on POSIX), then the folder fsynced so the
rename itself survives a power cut. A failure removes the temporary file and leaves the
target as it was. Standard library only, so every package may use it.

    write_atomic("state.json", text)
    with atomic_path("capture.npz") as tmp:      # for writers that want a path (np.savez, …)
        np.savez(tmp, counts=counts)

``durable=False`` skips both fsyncs: still never half-written for readers, but a power cut
may keep the old file — for files rewritten every second on a tmpfs (the status file).
"""

from __future__ import annotations

import itertools
import os
from contextlib import contextmanager
from pathlib import Path
from typing import Iterator

_WRITES = itertools.count()  # one temporary name per write: two threads may write the same target at once


def _fsync_path(path: Path, directory: bool = False) -> None:
    fd = os.open(path, os.O_RDONLY | (os.O_DIRECTORY if directory else 0))
    try:
        os.fsync(fd)
    finally:
        os.close(fd)


@contextmanager
def atomic_path(path: str | Path, durable: bool = True) -> Iterator[Path]:
    """A temporary path beside ``path`` (same suffix, so writers that add one do not); becomes ``path`` on success."""
    target = Path(path)
    tmp = target.with_name(f".{target.stem}.{os.getpid()}.{next(_WRITES)}.part{target.suffix}")
    try:
        yield tmp
        if durable:
            _fsync_path(tmp)
        os.replace(tmp, target)
    except BaseException:
        try:
            tmp.unlink()
        except OSError:
            pass
        raise
    if durable:
        _fsync_path(target.parent if str(target.parent) else Path("."), directory=True)


def write_atomic(path: str | Path, data: bytes | str, durable: bool = True, encoding: str = "utf-8") -> None:
    """``data`` (bytes, or text in ``encoding``) as the whole new content of ``path``."""
    with atomic_path(path, durable) as tmp:
        tmp.write_bytes(data if isinstance(data, bytes) else data.encode(encoding))


__all__ = ["atomic_path", "write_atomic"]
