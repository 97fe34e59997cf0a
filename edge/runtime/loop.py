"""The runtime's loop: reader thread → pipeline thread → publisher thread, one stop event.

    rt = Runtime(load_config("cavatar.toml"))
    rt.start()                  # SetupError (bad bundle, wrong calibration, …) before any output exists
    rt.wait(10.0)               # True once it ended by itself (seconds reached, source ended, failure)
    rt.stop()                   # reader stops, publisher drains, sinks say "offline" and close, status "stopped"

    snapshot = Runtime(cfg).run_for(frames=50)   # tests: start, process exactly 50 frames, stop

Threads (docs/runtime.md):
- reader (the source's own): link → decoder → frame assembly → bounded queue of
  ``source.queue_frames``; a live board's oldest frame is dropped when the pipeline falls
  behind (counted), so the pipeline always gets the newest;
- pipeline: :class:`~edge.runtime.stages.FrameStages` per frame, records to the publisher;
- publisher: :class:`~edge.runtime.publisher.Publisher`, the only thread touching sinks;
- monitor: the status file every ``runtime.status_s``, the sinks' info every ``runtime.info_s``.

Injectable for tests: ``source`` (an :class:`~edge.sources.base.FrameSource`, not started; an object lacking one
of its members is refused here with TypeError), ``sinks``,
``bundle``, ``calibration`` (a Calibration), ``clock`` (wall time for records' lag, status).

:class:`Runtime` takes ``setup()`` from :mod:`edge.runtime.setup` and ``snapshot()``, ``write_status()``,
``info()`` and ``queue_depths()`` from :mod:`edge.runtime.telemetry`; the threads and lifecycle are here.
"""

from __future__ import annotations

import logging
import sys
import threading
import time
from pathlib import Path
from typing import TYPE_CHECKING, Callable

from edge.runtime.board_health import LOST, BoardHealth
from edge.runtime.carpet_calibration import ChosenCalibration
from edge.runtime.config import RuntimeConfig
from edge.runtime.counters import FRAME_COUNTERS, PUBLISH_COUNTERS, WORK_COUNTERS, Counters, StageTimes
from edge.runtime.publisher import Publisher
from edge.runtime.sd_notify import Notifier
from edge.runtime.setup import RuntimeSetup
from edge.runtime.stages import FrameOutcome, FrameStages
from edge.runtime.telemetry import RuntimeTelemetry
from edge.sources.base import FrameSource, require_frame_source

if TYPE_CHECKING:
    from calibration.file import Calibration
    from edge.infer.bundle import ModelBundle
    from edge.runtime.events import EventStage
    from edge.runtime.seq import SeqLedger

log = logging.getLogger(__name__)


def _stderr(text: str) -> None:
    print(text, file=sys.stderr, flush=True)


class Runtime(RuntimeSetup, RuntimeTelemetry):
    """One carpet's runtime: setup, threads, lifecycle and status (see the module's docstring)."""

    def __init__(self, config: RuntimeConfig, *, source: FrameSource | None = None, sinks: list | None = None,
                 bundle: ModelBundle | None = None, calibration: Calibration | None = None,
                 clock: Callable[[], float] = time.time, say: Callable[[str], None] = _stderr) -> None:
        self.config = config
        self.clock = clock
        self.say = say
        self.times = StageTimes(config.runtime.timing_window)
        self.counters = Counters(FRAME_COUNTERS + WORK_COUNTERS + PUBLISH_COUNTERS + ("calibration_advice",))
        self.invalid = Counters()
        self.state = "new"
        self.error: str | None = None
        self.end_reason: str | None = None
        self.source: FrameSource | None = require_frame_source(source) if source is not None else None
        self.sinks: list | None = sinks
        self.bundle: ModelBundle | None = bundle
        self.chosen: ChosenCalibration | None = (
            ChosenCalibration(calibration, Path("(given)"), False) if calibration is not None else None)
        self.stages: FrameStages | None = None
        self.events: EventStage | None = None  # when [events] enabled
        self.publisher: Publisher | None = None
        self.seqs: SeqLedger | None = None  # while set up
        self._seq_start = 0
        self.on_outcome: list[Callable[[FrameOutcome], None]] = []  # called in the pipeline thread (tests, the demo)
        self._stop = threading.Event()
        self._ended = threading.Event()
        self._threads: list[threading.Thread] = []
        self._frame_limit: int | None = None
        self._started_wall: float | None = None
        self._started_mono: float | None = None
        self._fps = 0.0
        self._fps_mark: tuple[float, int] | None = None
        self._lock = threading.Lock()
        self._stopped = False
        self.board: BoardHealth | None = None  # made at start(): frames arriving or not ([source] board_timeout_s)
        self.notifier = Notifier.from_environment()  # systemd Type=notify: READY, STATUS, WATCHDOG (no-op elsewhere)

    # ------------------------------------------------------------------ lifecycle
    def start(self) -> None:
        if self.state == "new":
            self.setup()
        if self.state != "ready":
            raise RuntimeError(f"cannot start a runtime that is {self.state}")
        self._started_wall, self._started_mono = self.clock(), time.monotonic()
        self.board = BoardHealth(self.config.source.board_timeout_s, self._started_mono)
        self.state = "running"
        assert self.publisher is not None  # made by setup()
        self.publisher.start()
        self.write_status()
        self.publisher.put_info(self.info())
        for name, target in (("pipeline", self._pipeline_loop), ("monitor", self._monitor_loop)):
            t = threading.Thread(target=target, name=name, daemon=True)
            t.start()
            self._threads.append(t)
        self.notifier.ready(f"running: {self.config.source.url.split('?')[0]}")

    def request_stop(self) -> None:
        """Ask every thread to finish (safe from a signal handler); :meth:`stop` completes it."""
        self._stop.set()

    def wait(self, timeout_s: float | None = None) -> bool:
        """True once the pipeline has ended (stop requested, seconds reached, source ended, failure)."""
        return self._ended.wait(timeout_s)

    def stop(self, timeout_s: float = 10.0) -> dict:
        """Stop cleanly: reader, pipeline, publisher drained, sinks closed ("offline"), status 'stopped'.

        Bounded: everything within ``timeout_s`` (a sink that does not finish by then is abandoned)."""
        with self._lock:
            if self._stopped:
                return self.snapshot()
            self._stopped = True
        deadline = time.monotonic() + timeout_s
        self._stop.set()
        self.notifier.stopping("stopping: publishing what is queued, closing the sinks")
        if self.state == "running":
            self.state = "stopping"
            self.write_status()
        for t in self._threads:
            t.join(timeout=max(0.0, deadline - time.monotonic()))
        if self.source is not None:
            try:
                self.source.stop()
            except Exception as exc:  # a source that fails to stop must not keep the sinks open
                log.error("stopping the source: %s", exc)
        if self.publisher is not None:
            if self.state in ("stopping", "failed"):
                self.publisher.put_info(self.info(state="stopped" if self.error is None else "failed"))
            self.publisher.close(max(0.5, deadline - time.monotonic()))
        if self.state != "new":
            self.state = "failed" if self.error else "stopped"
            self.write_status()
        if self.seqs is not None:
            self.seqs.close(next_seq=self.stages.seq if self.stages is not None else None)
        return self.snapshot()

    def run_for(self, frames: int | None = None, seconds: float | None = None, timeout_s: float = 120.0) -> dict:
        """Start, process ``frames`` frames (or run ``seconds``), stop; returns the final status snapshot."""
        self._frame_limit = frames
        self.start()
        deadline = time.monotonic() + (seconds if seconds is not None else timeout_s)
        while not self.wait(0.05) and time.monotonic() < deadline:
            pass
        return self.stop()

    # ------------------------------------------------------------------ threads
    def _pipeline_loop(self) -> None:
        from calibration.runtime import status_temperature_c

        src, stages, pub, events = self.source, self.stages, self.publisher, self.events
        assert src is not None and stages is not None and pub is not None and self.board is not None  # setup(), start()
        assert self._started_mono is not None
        seconds = self.config.runtime.seconds
        deadline = self._started_mono + seconds if seconds > 0 else None
        last_status = None
        failures_said: set[str] = set()
        try:
            while not self._stop.is_set():
                got = False
                for frame in src.frames(timeout_s=0.2):
                    got = True
                    self.board.frame(time.monotonic(), self._source_stats())
                    self._watch_board()
                    temperature = None
                    if src.last_status is not last_status:
                        last_status = src.last_status
                        temperature = status_temperature_c(last_status)
                    try:
                        out = stages.process(frame, temperature)
                    except Exception as exc:  # a bug or a bad frame: logged once per kind, counted, next frame
                        self.counters.add("frames_failed")
                        kind = f"{type(exc).__name__}: {exc}"[:200]
                        if kind not in failures_said:
                            failures_said.add(kind)
                            log.exception("frame %d failed", frame.index)
                        out = None
                    if out is not None:
                        if out.record is not None and self._reserve_seq(out.record["seq"]):
                            pub.put_record(out.record, frame.host_time_s)
                        if out.kind in ("people", "empty", "unconfirmed"):
                            pub.put_presence(stages.people_now, out.activities)
                        for callback in self.on_outcome:
                            callback(out)
                    if events is not None:
                        for payload in events.frame(out, stages.scene_frame, frame.host_time_s):
                            pub.put_event(payload)
                    if self._limit_reached() or (deadline is not None and time.monotonic() >= deadline):
                        self._stop.set()
                    if self._stop.is_set():
                        break
                self._watch_board()
                if deadline is not None and time.monotonic() >= deadline:
                    self.end_reason = f"ran {seconds:g} s"
                    break
                if not got and events is not None:  # no frame: a lost board clears its events
                    for payload in events.idle():
                        pub.put_event(payload)
                if not got and src.ended:
                    self.end_reason = "the source ended"
                    break
        except Exception as exc:  # the source failed for good (e.g. a recording that cannot be read)
            self.error = f"{type(exc).__name__}: {exc}"
            log.error("source %s failed: %s", self.config.source.url, exc)
        finally:
            if events is not None:
                for payload in events.close():
                    pub.put_event(payload)
            if self.end_reason is None:
                self.end_reason = "failed" if self.error else ("frame limit" if self._limit_reached() else "stop requested")
            self._ended.set()
            self._stop.set()

    def _reserve_seq(self, seq: int) -> bool:
        """True once ``seq`` is reserved on disk (edge.runtime.seq); a record whose seq is not is never published."""
        assert self.seqs is not None  # set up before the pipeline thread starts
        try:
            self.seqs.reserve(seq)
            return True
        except OSError as exc:
            if not self.counters.get("seq_unreserved"):
                log.error("seq ledger %s: %s; records are not published until it can be written", self.seqs.path, exc)
            self.counters.add("seq_unreserved")
            return False

    def _limit_reached(self) -> bool:
        return self._frame_limit is not None and self.counters.get("frames_in") >= self._frame_limit

    def _watch_board(self) -> None:
        """Pipeline thread: a board transition is logged once (WARNING, the journal's level), presence is withdrawn
        when the board is lost (nobody is claimed on a carpet we cannot see), and the info (board_connected) goes to
        the sinks at once (MQTT: the retained board topic, Home Assistant's carpet entities' availability).
        Called at least every 0.2 s while the pipeline loop turns, so it also feeds systemd's watchdog."""
        self.notifier.watchdog()
        now = time.monotonic()
        assert self.board is not None and self.publisher is not None  # made by setup() and start()
        if not self.board.due(now):
            return
        change = self.board.check(now, self._source_stats())
        if change is None:
            return
        from edge.sinks import redact

        where = redact(self.config.source.url)
        if change.state == LOST:
            log.warning("board %s: %s; reported unavailable (presence withdrawn) until frames arrive again",
                        where, change.reason)
            self.publisher.put_presence(0, [])
        else:
            log.warning("board %s: frames again after %.1f s without; reported available", where, change.after_s)
        self.publisher.put_info(self.info())

    def _monitor_loop(self) -> None:
        rt = self.config.runtime
        next_info = time.monotonic() + rt.info_s
        while not self._stop.wait(rt.status_s):
            try:
                self.write_status()
                if self.notifier.active:  # one line for `systemctl status cavatar`
                    s = self.snapshot()
                    health = s["board_health"] or {}
                    self.notifier.status(f"board lost: {health.get('reason')}" if health.get("connected") is False else
                                         f"{self._fps:.1f} fps, {s['people']} people, {s['publish']['published']} published")
                if time.monotonic() >= next_info and self.publisher is not None:
                    next_info += rt.info_s
                    self.publisher.put_info(self.info())
            except Exception as exc:  # a full disk must not stop the pipeline
                log.error("status: %s", exc)


__all__ = ["Runtime"]
