"""A carpet source: link → handshake → decoder → frame assembly, on its own reader thread.

The reader thread reads the link continuously (so no OS buffer grows and latency stays
at one frame) and puts whole frames in a bounded queue. When the consumer falls behind
on a live link, the oldest frame is dropped (``dropped_slow_consumer``): we always hand
out the newest data. A recording is never dropped from; the reader waits instead, and
paces frames by their device timestamps when ``speed`` > 0.

On a live link that is lost (unplug, reset), the reader closes it and reopens it with
back-off (0.1 s doubling to 0.5 s), repeats the handshake and resumes — no restart.

The first INFO pins the board's identity (device id, grid, ADC bits, sign: what a
calibration is bound to). An INFO with another identity, mid-stream or after a replug,
holds every frame back (``board_mismatch`` in :meth:`stats`, packets counted) until an INFO of
the pinned board comes again: bodies are never computed with another carpet's calibration.

``on_decoded(ms)``, when given, is called on the reader thread once per assembled frame with
the milliseconds spent decoding packets and assembling rows since the previous frame (the
runtime's ``decode`` stage time; the handshake's decoding belongs to no frame).
"""

from __future__ import annotations

import logging
import queue
import threading
import time
from collections import Counter
from typing import Any, BinaryIO, Callable, Iterator

from edge.frames import FrameAssembler, RawFrame
from edge.sources.base import Link, LinkEnded, LinkLost, SourceError
from edge.sources.board_info import (
    IDENTITY,
    INFO_TYPES,
    board_mismatch_message,
    identity_changes,
    info_problems,
    is_info,
    no_info_message,
)
from edge.wiring import WiringMap
from firmware_protocol import codec

log = logging.getLogger(__name__)

_END = object()  # queue sentinel: the source has ended

__all__ = ["IDENTITY", "CarpetSource", "CommandRefused"]  # IDENTITY: kept importable from here


class CommandRefused(SourceError):
    """The board answered a command with NAK."""


class CarpetSource:
    """Frames from a readout board. Use as a context manager, then iterate :meth:`frames`."""

    def __init__(
        self,
        link: Link,
        *,
        wiring: dict[str, Any] | None = None,
        missing_rows: str = "drop",
        queue_frames: int = 4,
        speed: float = 1.0,
        handshake_timeout_s: float = 3.0,
        stall_timeout_s: float = 2.0,
        record_to: BinaryIO | None = None,
        on_decoded: Callable[[float], None] | None = None,
    ) -> None:
        self.link = link
        self.wiring_config = wiring
        self.missing_rows = missing_rows
        self.speed = speed
        self.handshake_timeout_s = handshake_timeout_s
        self.stall_timeout_s = stall_timeout_s
        self.record_to = record_to
        self.on_decoded = on_decoded
        self._decode_s = 0.0  # decoding and assembly since the last frame (reader thread only)
        self.decoder = codec.StreamDecoder("device_to_host")
        self.counters: Counter = Counter()
        self.info: Any = None
        self.board_mismatch: str | None = None  # why frames are held back: another board answered
        self.last_status: Any = None
        self.assembler: FrameAssembler | None = None
        self._queue: queue.Queue = queue.Queue(maxsize=max(1, queue_frames))
        self._replies: queue.Queue = queue.Queue()
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self._cmd_seq = 0
        self._write_lock = threading.Lock()
        self._pending: list[Any] = []  # packets read during the handshake, after INFO
        self._t0_host: float | None = None
        self.error: BaseException | None = None

    # ------------------------------------------------------------------ lifecycle

    def __enter__(self) -> "CarpetSource":
        self.start()
        return self

    def __exit__(self, *exc: Any) -> None:
        self.stop()

    def start(self) -> None:
        """Open the link, learn who the board is, start streaming and the reader thread."""
        self.link.open()
        try:
            self._handshake()
        except BaseException:
            self.link.close()
            raise
        self._thread = threading.Thread(target=self._run, name=f"source-{self.link.describe()}", daemon=True)
        self._thread.start()

    def stop(self) -> None:
        self._stop.set()
        if self._thread is not None:
            self._thread.join(timeout=3.0)
        if self.link.writable:
            try:
                self._send("STOP")
            except (LinkLost, OSError):
                pass
        self.link.close()

    # ------------------------------------------------------------------ consuming

    def frames(self, timeout_s: float | None = None) -> Iterator[RawFrame]:
        """Yield frames until the source ends or stops; ``timeout_s`` bounds the wait for each."""
        while not self._stop.is_set() or not self._queue.empty():
            try:
                item = self._queue.get(timeout=0.1 if timeout_s is None else timeout_s)
            except queue.Empty:
                if timeout_s is not None:
                    return
                continue
            if item is _END:
                if self.error is not None:
                    raise self.error
                return
            yield item

    @property
    def ended(self) -> bool:
        """True once the reader thread has finished (end of a recording, or a fatal error) and every frame was taken."""
        return self._thread is not None and not self._thread.is_alive() and self._queue.empty()

    def queue_depth(self) -> tuple[int, int]:
        """(frames waiting for the consumer now, the queue's bound ``queue_frames``); read-only, any thread."""
        return self._queue.qsize(), self._queue.maxsize

    def read_frame(self, timeout_s: float = 1.0) -> RawFrame | None:
        """The next frame, or None when none came within ``timeout_s`` or the source ended."""
        for frame in self.frames(timeout_s=timeout_s):
            return frame
        return None

    def command(self, name: str, timeout_s: float = 1.0, **fields: Any) -> Any:
        """Send a command and wait for its ACK (returned) or NAK (CommandRefused)."""
        seq = self._send(name, **fields)
        deadline = time.monotonic() + timeout_s
        while time.monotonic() < deadline:
            try:
                reply = self._replies.get(timeout=max(0.0, deadline - time.monotonic()))
            except queue.Empty:
                break
            if reply.cmd_seq != seq:
                continue
            if isinstance(reply, codec.Nak):
                reason = codec.NAK_REASON_NAMES.get(reply.reason, reply.reason)
                raise CommandRefused(f"the board refused {name} {fields or ''}: {reason}")
            return reply
        raise SourceError(f"no answer to {name} within {timeout_s} s")

    def stats(self) -> dict[str, Any]:
        """Counters of every stage: decoder drops, assembly, link events, queue."""
        out: dict[str, Any] = {"decoder": self.decoder.stats.as_dict(), "source": dict(self.counters)}
        if self.assembler is not None:
            out["frames"] = dict(self.assembler.counters)
        out["board_mismatch"] = self.board_mismatch
        if self.last_status is not None:
            out["board_status"] = {f.name: getattr(self.last_status, f.name) for f in self.last_status.DEF.fields}
        return out

    # ------------------------------------------------------------------ internals

    def _send(self, name: str, **fields: Any) -> int:
        if not self.link.writable:
            raise SourceError(f"{self.link.describe()} cannot carry commands")
        with self._write_lock:
            self._cmd_seq = (self._cmd_seq + 1) & 0xFFFF
            self.link.write(codec.encode_command(name, self._cmd_seq, **fields))
            return self._cmd_seq

    def _read(self, timeout_s: float) -> bytes:
        data = self.link.read(timeout_s)
        if data and self.record_to is not None:
            self.record_to.write(data)
        return data

    def _handshake(self) -> None:
        """GET_INFO until INFO arrives (or find INFO in a recording); check it; START."""
        deadline = time.monotonic() + self.handshake_timeout_s
        next_ask = 0.0
        self._pending = []
        info = None
        while info is None:
            now = time.monotonic()
            if now > deadline:
                raise SourceError(no_info_message(self.link.describe(), self.decoder.stats, self.handshake_timeout_s))
            if self.link.writable and now >= next_ask:
                self._send("GET_INFO")
                next_ask = now + 0.5
            try:
                data = self._read(0.05)
            except LinkEnded:
                raise SourceError(f"{self.link.describe()}: no INFO packet in the data; "
                                  "is it a capture written by `cavatar record`?") from None
            for pkt in self.decoder.feed(data):
                if info is None and is_info(pkt):
                    problems = info_problems(pkt)
                    if problems:
                        self.counters["info_out_of_range"] += 1
                        raise SourceError(f"{self.link.describe()}: the board's INFO is out of range: "
                                          + ", ".join(problems) + "; check the firmware")
                    info = pkt
                elif info is not None:
                    self._pending.append(pkt)
        self._adopt_info(info)
        if self.link.writable:
            self._send("START")
        self.counters["handshakes"] += 1
        self._decode_s = 0.0  # what was decoded before (a lost link's last packets) belongs to no frame

    def _adopt_info(self, info: Any) -> None:
        """Adopt the first INFO; pin its board identity. A later INFO (mid-stream or after a replug) of
        another board stops the frames until the pinned board is back (``board_mismatch``)."""
        if self.info is None:
            self.info = info
            wiring = WiringMap.from_config(self.wiring_config, info.rows, info.cols)
            self.assembler = FrameAssembler(info, wiring, missing_rows=self.missing_rows)
            return
        diffs = identity_changes(self.info, info)
        assert self.assembler is not None  # made with the first INFO
        self.assembler.reset()
        if diffs:
            self.counters["board_mismatch"] += 1
            message = board_mismatch_message(diffs)
            if message != self.board_mismatch:
                log.error("%s: %s", self.link.describe(), message)
            self.board_mismatch = message
            return
        if self.board_mismatch is not None:
            log.warning("%s: the original board is back; frames resume", self.link.describe())
        self.board_mismatch = None
        self.info = info

    def _run(self) -> None:
        try:
            for pkt in self._pending:
                self._dispatch(pkt)
            self._pending = []
            last_frame = time.monotonic()
            while not self._stop.is_set():
                try:
                    data = self._read(0.05)
                except LinkLost as exc:
                    self._reconnect(exc)
                    last_frame = time.monotonic()
                    continue
                t0 = time.perf_counter()
                packets = self.decoder.feed(data)
                self._decode_s += time.perf_counter() - t0
                for pkt in packets:
                    if self._dispatch(pkt):
                        last_frame = time.monotonic()
                if self.link.paced and time.monotonic() - last_frame > self.stall_timeout_s:
                    self.counters["stalls"] += 1
                    log.warning("%s: no frame for %.1f s; asking the board to start again", self.link.describe(), self.stall_timeout_s)
                    try:
                        self._send("START")
                    except (LinkLost, OSError):
                        pass
                    last_frame = time.monotonic()
        except LinkEnded:
            pass
        except BaseException as exc:  # surfaced to the consumer by frames()
            log.error("%s: reader stopped: %s", self.link.describe(), exc)
            self.error = exc
        finally:
            self._put(_END, block=True)

    def _dispatch(self, pkt: Any) -> bool:
        """Handle one packet; True when it completed a frame."""
        if isinstance(pkt, INFO_TYPES):  # per packet: no call on the hot path
            problems = info_problems(pkt)
            if problems:  # counted and ignored; never sizes a buffer
                self.counters["info_out_of_range"] += 1
                log.warning("%s: an INFO out of range ignored: %s", self.link.describe(), ", ".join(problems))
                return False
            self._adopt_info(pkt)
            return False
        if isinstance(pkt, codec.Status):
            self.last_status = pkt
            return False
        if isinstance(pkt, (codec.Ack, codec.Nak)):
            self._replies.put(pkt)
            return False
        if self.board_mismatch is not None:  # another board's packets: never turned into frames
            self.counters["packets_board_mismatch"] += 1
            return False
        t0 = time.perf_counter()
        assert self.assembler is not None  # the handshake adopted an INFO before any frame packet
        frames = self.assembler.push(pkt)
        self._decode_s += time.perf_counter() - t0
        if frames:
            self._frames_decoded(len(frames))
        for frame in frames:
            self._pace(frame)
            self._put(frame, block=not self.link.paced)
        return bool(frames)

    def _frames_decoded(self, n: int) -> None:
        """Share the decoding time since the last frame among the ``n`` frames just assembled."""
        if self.on_decoded is not None:
            ms = self._decode_s * 1e3 / n
            for _ in range(n):
                self.on_decoded(ms)
        self._decode_s = 0.0

    def _pace(self, frame: RawFrame) -> None:
        if self.link.paced or self.speed <= 0:
            return
        now = time.monotonic()
        if self._t0_host is None:
            self._t0_host = now - frame.t_s / self.speed
        wait = self._t0_host + frame.t_s / self.speed - now
        if wait > 0:
            self._stop.wait(min(wait, 5.0))

    def _put(self, item: Any, block: bool) -> None:
        if block:
            while not self._stop.is_set() or item is _END:
                try:
                    self._queue.put(item, timeout=0.1)
                    return
                except queue.Full:
                    if item is _END:  # make room: the consumer may be gone
                        try:
                            self._queue.get_nowait()
                        except queue.Empty:
                            pass
            return
        while True:
            try:
                self._queue.put_nowait(item)
                return
            except queue.Full:
                try:
                    self._queue.get_nowait()
                    self.counters["dropped_slow_consumer"] += 1
                except queue.Empty:
                    pass

    def _reconnect(self, why: BaseException) -> None:
        self.counters["disconnects"] += 1
        log.warning("%s: link lost (%s); reconnecting", self.link.describe(), why)
        self.link.close()
        if not self.link.reconnectable:
            raise SourceError(f"{self.link.describe()}: link lost ({why})")
        self.decoder.reset()
        if self.assembler is not None:
            self.assembler.reset()
        delay = 0.1
        while not self._stop.is_set():
            try:
                self.link.open()
                self._handshake()
            except (LinkLost, SourceError, OSError) as exc:
                self.link.close()
                log.debug("reconnect failed: %s", exc)
                self._stop.wait(delay)
                delay = min(delay * 2, 0.5)
                continue
            for pkt in self._pending:
                self._dispatch(pkt)
            self._pending = []
            self.counters["reconnects"] += 1
            log.warning("%s: reconnected", self.link.describe())
            return
