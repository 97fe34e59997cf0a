"""A bounded on-disk FIFO of publish payloads: keeps QoS ≥ 1 records while the broker is away.

Layout: one directory, segment files ``<n:016d>.spool`` of at most ``segment_records``
lines, one payload per line, oldest number first. The newest segment is *open* (being
appended to); the others are *sealed* (fsynced, read-only) and are what the drainer
sends. A segment is deleted only once every one of its records was acknowledged
(:meth:`remove`, called after PUBACK). On start, segments left by an earlier run are
sealed and sent first, so records survive a restart of the runtime too.

Bound: beyond ``max_bytes`` the oldest sealed segment not being sent is deleted, and its
records are counted as dropped (recent data is kept). If nothing can be deleted, the new
record is dropped.

Durability: each line is one ``os.write`` on an O_APPEND file (a process crash loses
nothing already appended); a segment is fsynced when sealed. A power cut can lose the
unsealed tail; a torn last line is skipped when read.
"""

from __future__ import annotations

import logging
import os
import threading
from dataclasses import dataclass, field
from pathlib import Path

log = logging.getLogger(__name__)

SUFFIX = ".spool"
FIRST_NUMBER = 10**12  # room to number rescued segments below the first one


@dataclass
class Segment:
    number: int
    path: Path
    records: int
    size: int
    claimed: bool = False
    acked: set[int] = field(default_factory=set)


class Spool:
    """Thread-safe bounded FIFO of payload lines in ``directory``."""

    def __init__(self, directory: str | os.PathLike, max_bytes: int, segment_records: int = 256) -> None:
        self.dir = Path(directory)
        self.max_bytes = int(max_bytes)
        self.segment_records = int(segment_records)
        self.dropped = 0  # records deleted or refused to respect max_bytes
        self.torn = 0  # torn/unreadable lines skipped when reading
        self._lock = threading.Lock()
        try:
            self.dir.mkdir(parents=True, exist_ok=True)
            probe = self.dir / ".write-test"
            probe.write_bytes(b"")
            probe.unlink()
        except OSError as exc:
            raise OSError(f"spool directory {str(self.dir)!r} is not writable: {exc}") from None
        self._sealed: list[Segment] = []
        for path in sorted(self.dir.glob(f"*{SUFFIX}")):
            try:
                number = int(path.stem)
            except ValueError:
                continue
            data = path.read_bytes()
            self._sealed.append(Segment(number, path, data.count(b"\n"), len(data)))
        self._open: Segment | None = None
        self._fd: int | None = None
        last = self._sealed[-1].number if self._sealed else FIRST_NUMBER - 1
        self._next = last + 1

    # -- sizes ----------------------------------------------------------------------------

    def __len__(self) -> int:
        with self._lock:
            return self._count()

    def _count(self) -> int:
        n = sum(s.records - len(s.acked) for s in self._sealed)
        return n + (self._open.records if self._open else 0)

    def size_bytes(self) -> int:
        with self._lock:
            return sum(s.size for s in self._sealed) + (self._open.size if self._open else 0)

    def open_records(self) -> int:
        with self._lock:
            return self._open.records if self._open else 0

    # -- writing --------------------------------------------------------------------------

    def append(self, line: str | bytes) -> bool:
        """Append one payload (no newline inside). False if it had to be dropped (spool full)."""
        data = (line.encode() if isinstance(line, str) else line) + b"\n"
        with self._lock:
            while self._total_size() + len(data) > self.max_bytes:
                victim = next((s for s in self._sealed if not s.claimed), None)
                if victim is None:
                    self.dropped += 1
                    return False
                self._sealed.remove(victim)
                self.dropped += victim.records - len(victim.acked)
                victim.path.unlink(missing_ok=True)
                log.warning("spool full (%d bytes): dropped %d oldest records", self.max_bytes, victim.records)
            if self._open is None:
                self._open = Segment(self._next, self.dir / f"{self._next:016d}{SUFFIX}", 0, 0)
                self._next += 1
                self._fd = os.open(self._open.path, os.O_WRONLY | os.O_CREAT | os.O_APPEND, 0o600)
            _write_all(self._fd, data)
            self._open.records += 1
            self._open.size += len(data)
            if self._open.records >= self.segment_records:
                self._seal()
            return True

    def prepend(self, lines: list[str | bytes]) -> None:
        """Store ``lines`` as a segment that is sent before everything already here (close-time rescue)."""
        if not lines:
            return
        data = b"".join((x.encode() if isinstance(x, str) else x) + b"\n" for x in lines)
        with self._lock:
            numbers = [s.number for s in self._sealed] + ([self._open.number] if self._open else [])
            number = min(numbers, default=self._next) - 1
            path = self.dir / f"{number:016d}{SUFFIX}"
            _write_file(path, data)
            self._sealed.insert(0, Segment(number, path, len(lines), len(data)))

    def seal(self) -> bool:
        """Close the open segment so the drainer can send it. False if there was nothing to seal."""
        with self._lock:
            return self._seal()

    def _seal(self) -> bool:
        if self._open is None:
            return False
        os.fsync(self._fd)
        os.close(self._fd)
        self._sealed.append(self._open)
        self._open, self._fd = None, None
        return True

    def _total_size(self) -> int:
        return sum(s.size for s in self._sealed) + (self._open.size if self._open else 0)

    # -- draining -------------------------------------------------------------------------

    def claim(self) -> tuple[Segment, list[bytes]] | None:
        """The oldest sealed segment and its lines (claimed: the bound will not delete it)."""
        with self._lock:
            seg = next((s for s in self._sealed if not s.claimed), None)
            if seg is None:
                return None
            seg.claimed = True
        try:
            data = seg.path.read_bytes()
        except FileNotFoundError:
            data = b""
        parts = data.split(b"\n")
        if parts[-1]:
            self.torn += 1  # a torn last line (power cut while appending): skipped
        lines = [p for p in parts[:-1] if p.strip()]
        return seg, lines

    def release(self, seg: Segment) -> None:
        """Give a claimed segment back (sending failed); acknowledged lines are remembered."""
        with self._lock:
            seg.claimed = False

    def remove(self, seg: Segment) -> None:
        """Delete a fully acknowledged segment."""
        with self._lock:
            if seg in self._sealed:
                self._sealed.remove(seg)
            seg.path.unlink(missing_ok=True)

    def close(self) -> None:
        with self._lock:
            self._seal()


def _write_all(fd: int, data: bytes) -> None:
    view = memoryview(data)
    while view:
        n = os.write(fd, view)
        view = view[n:]


def _write_file(path: Path, data: bytes) -> None:
    tmp = path.with_suffix(".tmp")
    fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o600)
    try:
        _write_all(fd, data)
        os.fsync(fd)
    finally:
        os.close(fd)
    os.replace(tmp, path)
