"""jsonl:// — body records as JSON lines in a file, rotated; ``jsonl:-`` writes them to stdout.

    jsonl:///var/lib/cavatar/bodies.jsonl?rotate_mb=100&keep=10
    jsonl://runs/bodies.jsonl          (relative path; parent folders are created)
    jsonl:-                            (standard output, e.g. piped into jq)

One ``cavatar.bodies/1`` record per line (nothing else: every line validates against the
one schema). ``publish_info`` writes ``<stem>.info.json`` beside the file (atomically);
status and presence are not written.

Flush policy
- ``flush_ms=0`` (default): each record is written with one ``write()`` as it is published,
  so a reader (``tail -f``) sees it at once and a crash of the process loses nothing.
- ``flush_ms=N``: records gather in memory and are written together once the oldest has
  waited N ms. The check runs at each publish (the runtime publishes at least a
  heartbeat per frame), and at ``flush()``/``close()``; a crash loses at most N ms.
- fsync: on rotation and on close, not per record (SD cards wear out); a power cut can
  lose what the kernel had not yet written, never produce a half line (below).

Never a half-written line: records are written only as whole lines; a write that fails
part-way is cut back to the last whole line; and a file opened for appending that ends
in a torn line (the machine died mid-write) has that torn tail cut off first, logged and
counted in ``stats()['repaired']``.

Only its own files: an existing file is appended to only if it is a regular file (not
followed through a symbolic link) whose lines are this device's ``cavatar.bodies/1``
records (its first whole line is checked, and a torn tail must be the start of one);
anything else is refused (SinkError), never truncated or changed.

Rotation: when the next write would pass ``rotate_mb`` or the file is older than
``rotate_s`` (since this process opened it), the file is fsynced, renamed to
``<stem>-<UTC time to the µs>-<nn>.jsonl`` and a new one started; ``keep`` rotated files are
kept. Pruning deletes only regular files named exactly so, never another ``<stem>-*`` file.
"""

from __future__ import annotations

import json
import logging
import os
import re
import stat
import sys
import threading
import time
from datetime import datetime, timezone
from glob import escape as glob_escape
from pathlib import Path
from typing import Any, Mapping
from urllib.parse import unquote

from cavatar_common.atomic import write_atomic
from edge.health import OK, CheckContext, Finding, writable_file
from edge.record import RecordError, check_record, dumps
from edge.sinks.base import Option, Sink, SinkError, parse_sink_url
from edge.urls import redact

log = logging.getLogger(__name__)

SCHEME = "jsonl"
FORM = "jsonl:///path/bodies.jsonl?rotate_mb=100&rotate_s=0&keep=10&flush_ms=0 or jsonl:- (stdout)"


def _at_least_zero(kind):
    def parse(text: str):
        value = kind(text)
        if value < 0:
            raise ValueError("must be >= 0")
        return value
    return parse


OPTIONS = {
    "rotate_mb": Option(_at_least_zero(float), 100.0, "start a new file before this size in MB; 0: never"),
    "rotate_s": Option(_at_least_zero(float), 0.0, "start a new file when this one is older than this, seconds; 0: never"),
    "keep": Option(_at_least_zero(int), 10, "rotated files kept, oldest deleted first; 0: keep all"),
    "flush_ms": Option(_at_least_zero(float), 0.0, "0: write every record at once; N: write gathered records once the oldest waited N ms"),
}
STDOUT_OPTIONS = {"flush_ms": OPTIONS["flush_ms"]}
HEAD = b'{"schema":"cavatar.bodies/1"'  # how every line this sink writes begins (edge.record.dumps)
SCAN_BYTES = 1 << 20  # at most this much is read to check a file's first line or its torn tail


def parse(url: str) -> tuple[Path | None, dict[str, Any]]:
    """(the file, None for standard output; the typed options). ValueError quoting the form on any mistake."""
    if url.startswith("jsonl:-") or url.startswith("jsonl://-"):
        return None, parse_sink_url(url, SCHEME, FORM, STDOUT_OPTIONS)[1]
    location, opts = parse_sink_url(url, SCHEME, FORM, OPTIONS)
    location = unquote(location)
    if not location or location.endswith("/"):
        raise ValueError(f"jsonl:// needs a file path. Form: {FORM}")
    return Path(location), opts


def open_sink(url: str, device: str, **kwargs: Any) -> "JsonlSink":
    path, opts = parse(url)
    return JsonlSink(path, device, **opts, **kwargs)


def check(url: str, ctx: CheckContext) -> list[Finding]:
    """`cavatar doctor`: the file's folder is writable by this user, with free space (stdout: nothing to check)."""
    name = f"sink {redact(url)}"
    path, _ = parse(url)
    if path is None:
        return [Finding(name, OK, "standard output (under systemd: the journal)")]
    return [writable_file(name, path, free_space=True)]


class JsonlSink(Sink):
    scheme = SCHEME

    def __init__(self, path: Path | None, device: str, rotate_mb: float = 100.0, rotate_s: float = 0.0,
                 keep: int = 10, flush_ms: float = 0.0) -> None:
        super().__init__(device)
        self.path = path
        self.rotate_bytes = int(rotate_mb * 1e6)
        self.rotate_s = rotate_s
        self.keep = keep
        self.flush_ms = flush_ms
        self._lock = threading.Lock()     # the gathered lines; held only briefly
        self._io_lock = threading.Lock()  # the file; held across writes
        self._writing = 0
        self._buf: list[bytes] = []
        self._t_calls: list[float] = []
        self._fd: int | None = None
        self._size = 0
        self._opened = 0.0
        self.rotations = 0
        self.counters.add("repaired", 0)
        if path is not None:
            try:
                path.parent.mkdir(parents=True, exist_ok=True)
                self._open()
            except OSError as exc:
                raise SinkError(f"jsonl:// cannot write {str(path)!r}: {exc}") from None

    def describe(self) -> str:
        return f"jsonl:{'-' if self.path is None else '//' + str(self.path)}"

    # -- files ----------------------------------------------------------------------------

    def _open(self) -> None:
        assert self.path is not None
        try:
            fd = os.open(self.path, os.O_RDWR | os.O_CREAT | os.O_APPEND | os.O_NOFOLLOW | os.O_NONBLOCK, 0o644)
        except OSError:
            if self.path.is_symlink():
                raise SinkError(f"jsonl:// {str(self.path)!r} is a symbolic link: refused (a link could point at "
                                "anyone's file); give the real path") from None
            raise
        try:
            size = os.fstat(fd).st_size
            why = self._not_ours(fd, size)
            if why:
                raise SinkError(f"jsonl:// {str(self.path)!r} {why}: this sink did not write it, so it neither appends "
                                "to it nor changes it. Give another path, or move that file away.")
            if size:
                size = self._repair(fd, size)
        except BaseException:
            os.close(fd)
            raise
        os.set_blocking(fd, True)
        self._fd, self._size, self._opened = fd, size, time.monotonic()

    def _not_ours(self, fd: int, size: int) -> str:
        """Why the open file is not one this sink wrote for this device ("" when it is, or is empty)."""
        if not stat.S_ISREG(os.fstat(fd).st_mode):
            return "is not a regular file (for standard output use jsonl:-)"
        if size == 0:
            return ""
        head = os.pread(fd, min(size, SCAN_BYTES), 0)
        first, nl, _ = head.partition(b"\n")
        if not nl:  # one torn line and nothing else: it must be the start of a record
            return "" if first[:len(HEAD)] == HEAD[:len(first)] and size <= SCAN_BYTES else \
                "does not hold cavatar.bodies/1 records"
        try:
            record = json.loads(first)
            check_record(record)
        except (ValueError, RecordError):
            return "does not hold cavatar.bodies/1 records"
        if record.get("device") != self.device:
            return f"holds the records of device {record.get('device')!r}, not {self.device!r}"
        return ""

    def _repair(self, fd: int, size: int) -> int:
        """Cut a torn last line (no newline at the end; the start of a record); return the new size."""
        if os.pread(fd, 1, size - 1) == b"\n":
            return size
        start = max(0, size - SCAN_BYTES)
        chunk = os.pread(fd, size - start, start)
        nl = chunk.rfind(b"\n")
        end = start + nl + 1 if nl >= 0 else (0 if start == 0 else -1)
        tail = chunk[nl + 1:]
        if end < 0 or tail[:len(HEAD)] != HEAD[:len(tail)]:
            raise SinkError(f"jsonl:// {str(self.path)!r} ends in {size - max(end, 0)} bytes that are not the start "
                            "of a record: not a torn line of this sink's, so the file is left as it is. Give another "
                            "path, or move that file away.")
        os.ftruncate(fd, end)
        log.warning("jsonl:// %s ended in a torn line (%d bytes): cut off", self.path, size - end)
        self.counters.add("repaired")
        return end

    def _rotate(self) -> None:
        assert self.path is not None and self._fd is not None
        os.fsync(self._fd)
        os.close(self._fd)
        self._fd = None
        # One clock reading to the microsecond, and a counter that is always there, so names sort
        # oldest first (a separate millisecond reading could fall in the next second, and an
        # optional "-1" sorted before the name without it).
        stamp = datetime.now(timezone.utc).strftime("%Y%m%dT%H%M%S.%fZ")
        n = 0
        while (target := self.path.with_name(f"{self.path.stem}-{stamp}-{n:02d}{self.path.suffix}")).exists():
            n += 1
        os.replace(self.path, target)
        self.rotations += 1
        self._open()
        if self.keep:
            for old in self.rotated_files()[: -self.keep]:
                old.unlink(missing_ok=True)

    def rotated_files(self) -> list[Path]:
        """Rotated files, oldest first: regular files named exactly as :meth:`_rotate` names them."""
        if self.path is None:
            return []
        name = re.compile(re.escape(self.path.stem) + r"-\d{8}T\d{6}\.\d{6}Z-\d{2,}" + re.escape(self.path.suffix) + "$")
        return sorted(p for p in self.path.parent.glob(f"{glob_escape(self.path.stem)}-*")
                      if name.match(p.name) and not p.is_symlink() and p.is_file())

    # -- writing --------------------------------------------------------------------------

    def _write_bodies(self, record: Mapping, line: str, t_call: float) -> None:
        with self._lock:
            self._buf.append(line.encode() + b"\n")
            self._t_calls.append(t_call)
            due = self.flush_ms <= 0 or (time.monotonic() - self._t_calls[0]) * 1000.0 >= self.flush_ms
        if due:
            self._flush()

    def flush(self, timeout_s: float = 5.0) -> bool:
        """Write whatever is gathered now."""
        self._flush()
        return True

    def _flush(self) -> None:
        """Take the gathered lines (``_lock``, never held across I/O, so ``stats()`` never waits on a
        blocked write) and write them (``_io_lock``)."""
        with self._io_lock:
            with self._lock:
                if not self._buf:
                    return
                data = b"".join(self._buf)
                n, t_calls = len(self._buf), self._t_calls
                self._buf, self._t_calls = [], []
                self._writing = n
            try:
                if self.path is None:
                    self._write_stdout(data)
                else:
                    self._maybe_rotate(len(data))
                    self._write_whole(data)
            except (OSError, ValueError) as exc:  # disk full, stdout closed: count, log, keep going
                self.counters.add("errors")
                self.counters.add("dropped", n)
                log.error("jsonl:// %s: %d records not written: %s", self.describe(), n, exc)
                return
            finally:
                with self._lock:
                    self._writing = 0
        now = time.monotonic()
        for t in t_calls:
            self._count_delivered(now - t)

    @staticmethod
    def _write_stdout(data: bytes) -> None:
        """Straight to file descriptor 1 where there is one: a write blocked on a full pipe then holds no
        Python lock (``sys.stdout``'s would stop the interpreter from exiting)."""
        try:
            fd = sys.stdout.fileno()
        except (AttributeError, OSError, ValueError):
            fd = None
        if fd is None:
            sys.stdout.write(data.decode())
            sys.stdout.flush()
            return
        sys.stdout.flush()
        view = memoryview(data)
        while view:
            view = view[os.write(fd, view):]

    def _maybe_rotate(self, incoming: int) -> None:
        too_big = self.rotate_bytes and self._size and self._size + incoming > self.rotate_bytes
        too_old = self.rotate_s and time.monotonic() - self._opened >= self.rotate_s and self._size
        if too_big or too_old:
            self._rotate()

    def _write_whole(self, data: bytes) -> None:
        """Write whole lines or nothing: a failure part-way truncates back."""
        assert self._fd is not None
        before = self._size
        view = memoryview(data)
        try:
            while view:
                k = os.write(self._fd, view)
                view = view[k:]
        except OSError:
            try:
                os.ftruncate(self._fd, before)
            except OSError:
                pass
            raise
        self._size = before + len(data)

    @property
    def events_path(self) -> Path | None:
        """Fall / person-down events go here, one JSON line each (stdout with the bodies for jsonl:-)."""
        return None if self.path is None else self.path.with_name(f"{self.path.stem}.events.jsonl")

    def _write_event(self, payload: dict, line: str) -> None:
        data = line.encode() + b"\n"
        try:
            if self.path is None:
                with self._lock:
                    sys.stdout.write(data.decode())
                    sys.stdout.flush()
                return
            events_path = self.events_path
            assert events_path is not None  # self.path is set
            fd = os.open(events_path, os.O_WRONLY | os.O_CREAT | os.O_APPEND, 0o644)
            try:
                os.write(fd, data)  # one short line: a single append
                os.fsync(fd)
            finally:
                os.close(fd)
        except (OSError, ValueError) as exc:
            self.counters.add("errors")
            log.error("jsonl:// %s: event not written: %s", self.describe(), exc)

    def _write_info(self, info: dict) -> None:
        if self.path is None:
            return
        from edge.topics import info_payload

        target = self.path.with_name(f"{self.path.stem}.info.json")
        try:
            write_atomic(target, dumps(info_payload(self.device, info, time.time())) + "\n")
        except OSError as exc:
            self.counters.add("errors")
            log.error("jsonl:// cannot write %s: %s", target, exc)

    def _gauges(self) -> dict[str, Any]:
        with self._lock:
            return {"queued": len(self._buf) + self._writing, "rotations": self.rotations}

    def close(self) -> None:
        if self.closed:
            return
        self._flush()
        with self._io_lock:
            self.closed = True
            if self._fd is not None:
                try:
                    os.fsync(self._fd)
                finally:
                    os.close(self._fd)
                    self._fd = None
