"""Record seq numbers that never repeat for a device: reserved in blocks, persisted before use.

    ledger = SeqLedger(Path("/var/lib/cavatar/status.json"), "carpet-01")
    first = ledger.open()        # SeqLedgerBusy if another runtime holds this status file
    ledger.reserve(seq)          # before publishing ``seq``: persists a new block when needed
    ledger.close()

Consumers deduplicate by ``(device, seq)`` (docs/mqtt.md), so a seq published twice is a
record lost. The ledger ``<status file>.seq`` (JSON: device → first seq not yet handed out)
is rewritten atomically (temporary file, fsync, rename, fsync of the folder) each time the
runtime passes the end of its block, BEFORE a seq of the new block is published. After a
crash or SIGKILL the next run starts at the end of the last reserved block: numbers are
skipped (at most one block), never reused; a clean stop gives the unused rest back, so
the next run continues without a gap.

One runtime per status file: ``<status file>.lock`` is held with ``flock`` while the
ledger is open (the kernel releases it when the process dies, so a crash leaves no stale
lock); a second runtime on the same file is refused, naming the holder's pid.
"""

from __future__ import annotations

import fcntl
import json
import os
from pathlib import Path

from cavatar_common.atomic import write_atomic

BLOCK = 1024  # seqs reserved per write: at 14 Hz one write every ~73 s


class SeqLedgerBusy(Exception):
    """Another runtime holds this status file's lock."""


class SeqLedgerError(Exception):
    """The ledger cannot be read or written; the message says which file and why."""


class SeqLedger:
    def __init__(self, status_path: Path, device: str, block: int = BLOCK) -> None:
        status_path = Path(status_path)
        self.path = status_path.with_name(status_path.name + ".seq")
        self.lock_path = status_path.with_name(status_path.name + ".lock")
        self.device = device
        self.block = max(1, int(block))
        self.reserved_end = 0  # seqs below this are reserved on disk
        self._lock_fd: int | None = None
        self._all: dict[str, int] = {}
        self._created: list[Path] = []

    def open(self, at_least: int = 0) -> int:
        """Lock, read, reserve the first block; the first seq to use (>= ``at_least``)."""
        self._created = [q for q in (self.lock_path, self.path) if not q.exists()]
        self._lock()
        try:
            self._all = self._read()
            first = max(int(at_least), self._all.get(self.device, 0))
            self.reserved_end = first
            self.reserve(first)
        except BaseException:
            self.discard()
            raise
        return first

    def reserve(self, seq: int) -> None:
        """Make sure ``seq`` is reserved on disk before it is used (OSError: nothing reserved, do not use it)."""
        if seq < self.reserved_end:
            return
        end = seq + self.block
        self._all[self.device] = end
        self._write(self._all)
        self.reserved_end = end

    def close(self, next_seq: int | None = None) -> None:
        """Unlock. ``next_seq`` (a clean stop: the first seq not handed out) gives the rest of the block back,
        so the next run continues without a gap; a crash skips to the end of the block instead."""
        if next_seq is not None and self._lock_fd is not None and next_seq <= self.reserved_end:
            try:
                self._all[self.device] = int(next_seq)
                self._write(self._all)
                self.reserved_end = int(next_seq)
            except OSError:  # the reservation on disk stands: numbers skipped, never reused
                pass
        if self._lock_fd is not None:
            try:
                fcntl.flock(self._lock_fd, fcntl.LOCK_UN)
            finally:
                os.close(self._lock_fd)
                self._lock_fd = None

    def discard(self) -> None:
        """Unlock and remove the files :meth:`open` created (a runtime that refused to start leaves nothing)."""
        self.close()
        for q in self._created:
            q.unlink(missing_ok=True)
        self._created = []

    # ------------------------------------------------------------------ files
    def _lock(self) -> None:
        self.lock_path.parent.mkdir(parents=True, exist_ok=True)
        fd = os.open(self.lock_path, os.O_RDWR | os.O_CREAT, 0o644)
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            holder = os.pread(fd, 32, 0).decode(errors="replace").strip() or "unknown"
            os.close(fd)
            raise SeqLedgerBusy(f"another runtime (pid {holder}) is running with {self.lock_path.with_suffix('')}: "
                                "two runtimes on one status file would publish the same seq numbers. Stop it, or "
                                "give this one its own [runtime] status_file (--status-file).") from None
        os.ftruncate(fd, 0)
        os.pwrite(fd, f"{os.getpid()}\n".encode(), 0)
        self._lock_fd = fd

    def _read(self) -> dict[str, int]:
        try:
            text = self.path.read_text(encoding="utf-8")
        except FileNotFoundError:
            return {}
        except OSError as exc:
            raise SeqLedgerError(f"seq ledger {self.path}: {exc}") from None
        try:
            data = json.loads(text)
            if not isinstance(data, dict) or not all(isinstance(k, str) and isinstance(v, int) and v >= 0
                                                     for k, v in data.items()):
                raise ValueError("not an object of device → non-negative integer")
        except ValueError as exc:
            raise SeqLedgerError(f"seq ledger {self.path} is damaged ({exc}); records would reuse seq numbers. "
                                 "Move it away only if consumers may see seq start again from the status file's "
                                 "last_seq.") from None
        return data

    def _write(self, data: dict[str, int]) -> None:
        write_atomic(self.path, json.dumps(data, sort_keys=True) + "\n")  # fsynced, renamed, folder fsynced


__all__ = ["BLOCK", "SeqLedger", "SeqLedgerBusy", "SeqLedgerError"]
