"""A bounded on-disk FIFO of publish payloads: keeps QoS ≥ 1 records while the broker is away.

Layout: one directory, segment files ``<n:016d>.spool`` of at most ``segment_records``
lines, one payload per line, oldest number first. The newest segment is *open* (being
appended to); the others are *sealed* (fsynced, read-only) and are what the drainer
sends. A segment is deleted only once every one of its records was acknowledged
(:meth:`remove`, called after PUBACK). On start, segments left by an earlier run are
sealed and sent first, so records survive a restart of the runtime too.

Bound: beyond ``max_bytes`` the oldest segment not being sent is deleted (the open one is
sealed first when it is the only one), its records counted as dropped and logged: the
oldest go first, recent data is kept. ``max_bytes`` must hold two segments of records of
about ``RECORD_BYTES`` (:func:`min_bytes`); less is a configuration error (ValueError).

The spool owns its files: the directory must be a real directory of this user, not
writable by others; only regular files of this user named ``<16 digits>.spool`` are read,
opened without following symbolic links; anything else there is ignored (counted in
``foreign``, logged). Every line read back is checked as a ``cavatar.bodies/1`` record
(of ``device``, when given) before :meth:`claim` hands it out; others are skipped
(``refused``, logged): a file dropped in the directory never leaves the device.

Durability: each line is one ``os.write`` on an O_APPEND file (a process crash loses
nothing already appended); a write that fails part-way (a full disk) is cut back to the
last whole line and the record counted as dropped; a segment is fsynced when sealed. A
power cut can lose the unsealed tail; a torn last line is skipped when read.
"""

from __future__ import annotations

import json
import logging
import os
import re
import stat
import threading
from dataclasses import dataclass, field
from pathlib import Path

from cavatar_common.atomic import atomic_path
from edge.record import RecordError, check_record, check_telemetry
from edge.topics import EVENTS_SCHEMA

log = logging.getLogger(__name__)

SUFFIX = ".spool"
NAME = re.compile(r"^\d{16}\.spool$")
FIRST_NUMBER = 10**12  # room to number rescued segments below the first one
RECORD_BYTES = 1536  # a typical record with one or two people (one person: ~1 KB of JSON)


def min_bytes(segment_records: int) -> int:
    """The smallest bound that holds two segments: one being filled, one being sent or dropped."""
    return 2 * int(segment_records) * RECORD_BYTES


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

    def __init__(self, directory: str | os.PathLike, max_bytes: int, segment_records: int = 256,
                 device: str | None = None) -> None:
        self.dir = Path(directory)
        self.max_bytes = int(max_bytes)
        self.segment_records = int(segment_records)
        self.device = device
        if self.max_bytes < min_bytes(self.segment_records):
            raise ValueError(f"spool bound {self.max_bytes / 1e6:g} MB holds less than two segments of "
                             f"{self.segment_records} records (~{RECORD_BYTES} bytes each): the newest records would be "
                             f"dropped. Use spool_mb >= {min_bytes(self.segment_records) / 1e6:g}.")
        self.dropped = 0  # records deleted or refused to respect max_bytes, or lost to a failed write
        self.torn = 0  # torn/unreadable lines skipped when reading
        self.refused = 0  # lines that are not a valid record (of this device): never handed out
        self.foreign = 0  # files in the directory that are not this spool's: ignored
        self._said: set[str] = set()
        self._lock = threading.Lock()
        self._check_dir()
        self._sealed: list[Segment] = []
        last = FIRST_NUMBER - 1
        for entry in sorted(os.scandir(self.dir), key=lambda e: e.name):
            if NAME.match(entry.name):  # new segments are numbered past every name here, ours or not
                last = max(last, int(entry.name[:16]))
            if entry.name.startswith(".") and entry.name.endswith(".tmp"):
                continue
            st = entry.stat(follow_symlinks=False)
            why = self._not_ours(entry.name, st)
            if why:
                self.foreign += 1
                log.warning("spool %s: %s is %s: ignored (never read or sent)", self.dir, entry.name, why)
                continue
            data = _read_own(Path(entry.path), self.max_bytes)
            if data is None:
                self.foreign += 1
                continue
            self._sealed.append(Segment(int(entry.name[:16]), Path(entry.path), data.count(b"\n"), len(data)))
        self._open: Segment | None = None
        self._fd: int | None = None
        self._next = last + 1

    def _check_dir(self) -> None:
        try:
            self.dir.mkdir(mode=0o700, parents=True, exist_ok=True)
            st = os.lstat(self.dir)
        except OSError as exc:
            raise OSError(f"spool directory {str(self.dir)!r} cannot be made: {exc}") from None
        if stat.S_ISLNK(st.st_mode) or not stat.S_ISDIR(st.st_mode):
            raise OSError(f"spool directory {str(self.dir)!r} is a symbolic link or not a directory; give a real "
                          "directory of this user")
        if st.st_uid != os.geteuid():
            raise OSError(f"spool directory {str(self.dir)!r} belongs to uid {st.st_uid}, not this user "
                          f"({os.geteuid()}); give one of this user's directories")
        if st.st_mode & 0o022:
            raise OSError(f"spool directory {str(self.dir)!r} is writable by others (mode {st.st_mode & 0o777:o}); "
                          f"`chmod 700 {self.dir}`")
        try:
            probe = self.dir / ".write-test"
            probe.write_bytes(b"")
            probe.unlink()
        except OSError as exc:
            raise OSError(f"spool directory {str(self.dir)!r} is not writable: {exc}") from None

    def _not_ours(self, name: str, st: os.stat_result) -> str:
        if not NAME.match(name):
            return "not a segment name"
        if stat.S_ISLNK(st.st_mode):
            return "a symbolic link"
        if not stat.S_ISREG(st.st_mode):
            return "not a regular file"
        if st.st_uid != os.geteuid():
            return f"owned by uid {st.st_uid}"
        if st.st_size > self.max_bytes:
            return f"larger ({st.st_size} bytes) than the spool's bound"
        return ""

    def _say(self, key: str, text: str, *args: object) -> None:
        """Log a kind of event at its first time (each is counted every time)."""
        if key not in self._said:
            self._said.add(key)
            log.warning(text, *args)

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
        """Append one payload (no newline inside). False if it was dropped (spool full, write failed)."""
        data = (line.encode() if isinstance(line, str) else line) + b"\n"
        with self._lock:
            if len(data) > self.max_bytes // 2:
                self.dropped += 1
                log.warning("spool: a record of %d bytes is larger than half the bound: dropped", len(data))
                return False
            while self._total_size() + len(data) > self.max_bytes:
                victim = next((s for s in self._sealed if not s.claimed), None)
                if victim is None and self._open is not None and self._open.records:
                    self._seal()  # the open segment holds the oldest records not being sent: it goes first
                    continue
                if victim is None:
                    self.dropped += 1
                    log.warning("spool full (%d bytes) and all of it being sent: the new record dropped", self.max_bytes)
                    return False
                self._sealed.remove(victim)
                lost = victim.records - len(victim.acked)
                self.dropped += lost
                victim.path.unlink(missing_ok=True)
                log.warning("spool full (%d bytes): dropped %d oldest records (%d dropped in all)", self.max_bytes,
                            lost, self.dropped)
            try:
                if self._open is None:
                    path = self.dir / f"{self._next:016d}{SUFFIX}"
                    fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL | os.O_APPEND | os.O_NOFOLLOW, 0o600)
                    self._open, self._fd = Segment(self._next, path, 0, 0), fd
                    self._next += 1
                assert self._fd is not None  # opened with self._open
                _write_all(self._fd, data)
            except OSError as exc:  # a full disk: no half line stays behind, the record is counted
                self._cut_back()
                self.dropped += 1
                self._say("write", "spool %s: a record could not be written (%s): dropped and counted", self.dir, exc)
                return False
            self._open.records += 1
            self._open.size += len(data)
            if self._open.records >= self.segment_records:
                try:
                    self._seal()
                except OSError as exc:
                    self._say("seal", "spool %s: sealing a segment failed (%s)", self.dir, exc)
            return True

    def _cut_back(self) -> None:
        """After a failed write: the open segment back to its last whole line."""
        if self._fd is None or self._open is None:
            return
        try:
            os.ftruncate(self._fd, self._open.size)
        except OSError:
            pass

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
        fd, seg = self._fd, self._open
        assert fd is not None  # opened with self._open
        self._sealed.append(seg)
        self._open, self._fd = None, None
        try:
            os.fsync(fd)
        finally:
            os.close(fd)
        return True

    def _total_size(self) -> int:
        return sum(s.size for s in self._sealed) + (self._open.size if self._open else 0)

    # -- draining -------------------------------------------------------------------------

    def claim(self) -> tuple[Segment, list[bytes]] | None:
        """The oldest sealed segment and its valid records (claimed: the bound will not delete it).

        Lines that are not a valid record (of ``device``) are skipped and counted in ``refused``."""
        with self._lock:
            seg = next((s for s in self._sealed if not s.claimed), None)
            if seg is None:
                return None
            seg.claimed = True
        data = _read_own(seg.path, self.max_bytes) or b""
        parts = data.split(b"\n")
        if parts[-1]:
            self.torn += 1  # a torn last line (power cut while appending): skipped
        lines = []
        for part in parts[:-1]:
            if not part.strip():
                continue
            why = self._invalid(part)
            if why:
                self.refused += 1
                self._say("refused", "spool %s: a line of %s is not a record of this device (%s): never sent",
                          self.dir, seg.path.name, why)
                continue
            lines.append(part)
        return seg, lines

    def _invalid(self, line: bytes) -> str:
        try:
            record = json.loads(line)
            if isinstance(record, dict) and record.get("schema") == EVENTS_SCHEMA:
                check_telemetry(record, "event")  # a fall / person-down event, spooled with the bodies
            else:
                check_record(record)
        except (ValueError, RecordError) as exc:
            return str(exc)[:120]
        if self.device is not None and record.get("device") != self.device:
            return f"device {record.get('device')!r}"
        return ""

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


def _read_own(path: Path, limit: int) -> bytes | None:
    """A segment's bytes, never through a symbolic link and only from this user's regular file of at most
    ``limit`` bytes; None otherwise (or when it is gone)."""
    try:
        fd = os.open(path, os.O_RDONLY | os.O_NOFOLLOW | os.O_NONBLOCK)
    except OSError:
        return None
    try:
        st = os.fstat(fd)
        if not stat.S_ISREG(st.st_mode) or st.st_uid != os.geteuid() or st.st_size > limit:
            return None
        chunks, left = [], st.st_size
        while left > 0:
            chunk = os.read(fd, min(left, 1 << 20))
            if not chunk:
                break
            chunks.append(chunk)
            left -= len(chunk)
        return b"".join(chunks)
    finally:
        os.close(fd)


def _write_file(path: Path, data: bytes) -> None:
    """``data`` as the whole of ``path``, owner-only (records stay private), via the atomic-write helper."""
    with atomic_path(path) as tmp:
        fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_TRUNC | os.O_NOFOLLOW, 0o600)
        try:
            _write_all(fd, data)
        finally:
            os.close(fd)
