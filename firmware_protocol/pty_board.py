"""A :class:`VirtualBoard` behind a pseudo-terminal, so the host talks to it through real pyserial.

A thread owns the pty: it hands what the host writes to ``board.receive`` and writes
``board.read(now)`` to the host in real time (rows when they are scanned, at the
board's rate). ``port`` is a stable symlink in a temporary folder, like a udev
symlink, pointing at the current ``/dev/pts/N``.

Usage::

    import serial
    from firmware_protocol import codec
    from firmware_protocol.pty_board import PtyBoard
    from firmware_protocol.virtual_board import VirtualBoard

    with PtyBoard(VirtualBoard(rows=32, cols=32)) as pty:
        port = serial.Serial(pty.port, timeout=0.5)
        port.write(codec.encode_command("GET_INFO", 0) + codec.encode_command("START", 1))
        dec = codec.StreamDecoder()
        packets = dec.feed(port.read(4096))       # Info, Ack, Row, ...
        pty.unplug()    # pty closed, symlink gone: port.read raises SerialException
        pty.replug()    # a new pty behind the same symlink; the board boots again
        port.close()

Unplug closes both ends of the pty, so the host's reads fail exactly as they do when a
USB-serial adapter is pulled (pyserial raises ``SerialException``), and removes the
symlink (udev does). The board's own ``unplug()``/``replug()`` flags are obeyed too.
Faults are injected on the board itself (``pty.board.drop_bytes(10)``; it is thread-safe).
"""

from __future__ import annotations

import errno
import logging
import os
import select
import shutil
import tempfile
import threading
import time
import tty

from firmware_protocol.virtual_board import VirtualBoard

log = logging.getLogger(__name__)

_POLL_S = 0.01  # longest the thread sleeps before looking at its flags again
_WAIT_S = 2.0  # longest start/unplug/replug/stop wait for the thread


class PtyBoard:
    """Serve ``board`` on a pseudo-terminal from a thread (see the module docstring).

    ``link_path``: where the symlink goes (default ``<tempdir>/ttyCAVATAR0``).
    ``max_backlog_bytes``: bytes held while the host does not read, beyond the pty's own
    buffer; more are dropped and counted in ``overflow_bytes`` (a CDC device does the same).
    """

    def __init__(self, board: VirtualBoard, link_path: str | None = None, max_backlog_bytes: int = 1 << 20) -> None:
        self.board = board
        self._tmpdir = None if link_path else tempfile.mkdtemp(prefix="cavatar-pty-")
        self.port = link_path or os.path.join(self._tmpdir, "ttyCAVATAR0")
        self.max_backlog_bytes = max_backlog_bytes
        self.overflow_bytes = 0
        self.bytes_written = 0
        self.bytes_received = 0
        self.error: BaseException | None = None  # what stopped the thread, if anything did
        self._master: int | None = None
        self._slave: int | None = None
        self.pts_path: str | None = None
        self._out = bytearray()
        self._stop = threading.Event()
        self._state_changed = threading.Event()
        self._thread: threading.Thread | None = None
        self._generation = -1

    # ------------------------------------------------------------------ public

    def start(self) -> "PtyBoard":
        """Open the pty, make the symlink, start the thread (the board powers up now)."""
        if self._thread is not None:
            return self
        self._stop.clear()
        if self.board.plugged:
            self._open()
        self._thread = threading.Thread(target=self._run, name=f"PtyBoard {self.port}", daemon=True)
        self._thread.start()
        return self

    def stop(self) -> None:
        """Stop the thread, close the pty, remove the symlink (and the temporary folder)."""
        self._stop.set()
        if self._thread is not None:
            self._thread.join(_WAIT_S)
            if self._thread.is_alive():  # pragma: no cover - the loop is bounded by _POLL_S
                log.error("PtyBoard thread did not stop within %.1f s", _WAIT_S)
            self._thread = None
        self._close()
        if self._tmpdir is not None:
            shutil.rmtree(self._tmpdir, ignore_errors=True)
            self._tmpdir = None

    def unplug(self) -> None:
        """Pull the cable: the board unplugs, the pty closes and the symlink goes (returns when done)."""
        self.board.unplug(now_s=time.monotonic())
        self._wait_for(lambda: self._master is None)

    def replug(self) -> None:
        """Plug back in: a new pty behind the same symlink (returns when the symlink points at it)."""
        self.board.replug(now_s=time.monotonic())
        self._wait_for(lambda: self._master is not None)

    @property
    def connected(self) -> bool:
        return self._master is not None

    def __enter__(self) -> "PtyBoard":
        return self.start()

    def __exit__(self, *exc) -> None:
        self.stop()

    # ------------------------------------------------------------------ the pty

    def _open(self) -> None:
        master, slave = os.openpty()
        try:
            tty.setraw(slave)  # no echo, no line editing: bytes pass untouched
            tty.setraw(master)
            os.set_blocking(master, False)
            pts_path = os.ttyname(slave)
            tmp = self.port + ".new"
            if os.path.lexists(tmp):
                os.unlink(tmp)
            os.symlink(pts_path, tmp)
            os.replace(tmp, self.port)  # atomic re-point, as udev does
        except BaseException:
            os.close(master)
            os.close(slave)
            raise
        self._out.clear()
        self._generation = self.board.plug_generation
        self.pts_path = pts_path
        self._slave = slave
        self._master = master  # last: `connected` means the link is in place

    def _close(self) -> None:
        try:
            os.unlink(self.port)  # first: once `connected` is False the link is gone
        except FileNotFoundError:
            pass
        for fd in (self._slave, self._master):
            if fd is not None:
                try:
                    os.close(fd)
                except OSError:
                    pass
        self._out.clear()
        self.pts_path = None
        self._slave = None
        self._master = None

    def _wait_for(self, cond) -> None:
        deadline = time.monotonic() + _WAIT_S
        while not cond() and time.monotonic() < deadline:
            if self._thread is None:  # not started: do it here
                self._sync_plug_state()
                continue
            self._state_changed.wait(_POLL_S)
            self._state_changed.clear()

    def _sync_plug_state(self) -> None:
        """Follow the board's plug flags: close on unplug, reopen on replug."""
        board = self.board
        if self._master is not None and (not board.plugged or board.plug_generation != self._generation):
            self._close()
            self._state_changed.set()
        if self._master is None and board.plugged:
            self._open()
            self._state_changed.set()

    # ------------------------------------------------------------------ the thread

    def _run(self) -> None:
        try:
            while not self._stop.is_set():
                self._sync_plug_state()
                if self._master is None:
                    self.board.read(time.monotonic())  # keeps a self-powered board's clock moving
                    self._stop.wait(_POLL_S)
                    continue
                self._step()
        except BaseException as exc:  # a frame generator that raised, an fd error: keep it for the test
            self.error = exc
            log.exception("PtyBoard thread stopped")

    def _step(self) -> None:
        now = time.monotonic()
        data = self.board.read(now)
        if data:
            room = self.max_backlog_bytes - len(self._out)
            if len(data) > room:
                self.overflow_bytes += len(data) - max(room, 0)
                data = data[: max(room, 0)]
            self._out += data
        if self._out:
            self._write()
        due = self.board.next_due_s()
        timeout = _POLL_S if due is None else min(_POLL_S, max(0.0, due - time.monotonic()))
        master = self._master
        wlist = [master] if self._out else []
        try:
            readable, _, _ = select.select([master], wlist, [], timeout)
        except (OSError, ValueError):
            return
        if readable:
            try:
                cmd = os.read(master, 65536)
            except BlockingIOError:
                cmd = b""
            except OSError as exc:
                if exc.errno != errno.EIO:
                    raise
                cmd = b""
            if cmd:
                self.bytes_received += len(cmd)
                self.board.receive(cmd, now_s=time.monotonic())

    def _write(self) -> None:
        try:
            n = os.write(self._master, self._out)
        except BlockingIOError:
            return
        except OSError as exc:
            if exc.errno in (errno.EIO, errno.EAGAIN):
                return
            raise
        del self._out[:n]
        self.bytes_written += n
