"""The runtime's loop: reader thread → pipeline thread → publisher thread, one stop event; its status.

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
"""

from __future__ import annotations

import logging
import os
import sys
import threading
import time
from pathlib import Path
from typing import TYPE_CHECKING, Any, Callable

from edge import __version__
from edge.runtime.board_health import LOST, BoardHealth
from edge.runtime.carpet_calibration import ChosenCalibration, check_board, choose_calibration
from edge.runtime.config import RuntimeConfig
from edge.runtime.counters import FRAME_COUNTERS, PUBLISH_COUNTERS, WORK_COUNTERS, Counters, StageTimes
from edge.runtime.errors import SetupError
from edge.runtime.publisher import Publisher
from edge.runtime.sd_notify import Notifier
from edge.runtime.stages import FrameOutcome, FrameStages
from edge.runtime.status import SCHEMA, write_status
from edge.sources.base import FrameSource, require_frame_source

if TYPE_CHECKING:
    from calibration.file import Calibration
    from edge.infer.bundle import ModelBundle
    from edge.runtime.events import EventStage
    from edge.runtime.seq import SeqLedger

log = logging.getLogger(__name__)


def _stderr(text: str) -> None:
    print(text, file=sys.stderr, flush=True)


class Runtime:
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

    # ------------------------------------------------------------------ setup
    def setup(self) -> None:
        """Load and check everything; open the sinks last, so a refusal leaves no output behind. SetupError."""
        from edge.runtime.seq import SeqLedger, SeqLedgerBusy, SeqLedgerError

        status = self.config.status_path()
        ledger = SeqLedger(status, self.config.device.id)
        try:  # first: a second runtime on this status file is refused before it touches the board
            self._seq_start = ledger.open(at_least=self._previous_seq() + 1)
        except (SeqLedgerBusy, SeqLedgerError) as exc:
            raise SetupError(str(exc)) from None
        except OSError as exc:
            raise SetupError(f"status file {status}: cannot be written, nor its seq ledger beside it ({exc}); set [runtime] "
                             "status_file (--status-file) to a writable place") from None
        self.seqs = ledger
        try:
            self._setup()
        except BaseException:
            ledger.discard()
            self.seqs = None
            raise

    def _setup(self) -> None:
        from calibration.runtime import CalibratedFrames
        from edge.infer import BundleError, ModelBundle
        from edge.runtime.reader import open_timed_source
        from edge.scene import SceneTracker
        from edge.sources import SourceError

        cfg = self.config
        if self.source is not None:  # also one set after construction (tests): held to the same interface
            self.source = require_frame_source(self.source)
        if self.bundle is None:
            path = cfg.bundle_path()
            try:
                self.bundle = ModelBundle.load(path, threads=cfg.model.threads)
            except BundleError as exc:
                raise SetupError(f"model bundle refused: {exc}. The runtime never runs a bundle that does not match its "
                                 "manifest; reinstall the package for the shipped bundle, or point [model] bundle "
                                 "(--bundle DIR) at an intact bundle folder written by `cavatar bundle`.") from None
        if self.source is None:
            try:
                self.source = open_timed_source(cfg.source.url, self.times, queue_frames=cfg.source.queue_frames,
                                                missing_rows=cfg.source.missing_rows)
            except (ValueError, SourceError) as exc:
                raise SetupError(f"source {cfg.source.url}: {exc}") from None
        if self.chosen is None:  # before the source starts: the virtual carpet's session takes seconds
            self.chosen = choose_calibration(cfg.calibration.file, cfg.source.url, cfg.output_dir(), self.say)
        try:
            self.source.start()
        except (SourceError, OSError, ValueError) as exc:
            raise SetupError(f"source {cfg.source.url} did not start: {exc}") from None
        try:
            info = self.source.info
            grid = (int(info.rows), int(info.cols))
            if tuple(self.bundle.grid) != grid:
                raise SetupError(f"the model bundle {self.bundle.folder} is for a {self.bundle.grid[0]}×{self.bundle.grid[1]} "
                                 f"carpet; this board is {grid[0]}×{grid[1]}. Use a bundle exported for this grid "
                                 "([model] bundle, --bundle DIR).")
            check_board(self.chosen, info)
            cal = self.chosen.calibration
            if abs(cal.pitch_m - self.bundle.pitch_m) > 0.05 * self.bundle.pitch_m:
                raise SetupError(f"this carpet's pitch is {cal.pitch_m * 1e3:.2f} mm (calibration), the model bundle was "
                                 f"trained at {self.bundle.pitch_m * 1e3:.2f} mm; use a bundle trained for this pitch.")
            calibrated = CalibratedFrames(cal, info, baseline=cfg.calibration.baseline)
            scene = SceneTracker(grid[0], grid[1], cal.pitch_m, cfg.scene)
            self.stages = FrameStages(calibrated, scene, self.bundle, device=cfg.device.id, times=self.times,
                                      counters=self.counters, invalid=self.invalid,
                                      heartbeat_s=cfg.runtime.heartbeat_s, seq_start=self._seq_start,
                                      resolve_heading=cfg.model.resolve_heading,
                                      heading_params=cfg.model.heading_params or None)
            status = cfg.status_path()
            try:
                status.parent.mkdir(parents=True, exist_ok=True)
            except OSError as exc:
                raise SetupError(f"status file {status}: cannot create its folder ({exc}); set [runtime] status_file "
                                 "(--status-file) to a writable place") from None
            if not os.access(status.parent, os.W_OK) or (status.exists() and not os.access(status, os.W_OK)):
                raise SetupError(f"status file {status}: not writable by this user; set [runtime] status_file "
                                 "(--status-file) to a writable place")
            if self.sinks is None:
                self.sinks = self._open_sinks()
        except BaseException:
            self.source.stop()
            raise
        self.publisher = Publisher(self.sinks, counters=self.counters, times=self.times,
                                   queue_records=cfg.sinks.queue_records, clock=self.clock)
        if cfg.events.enabled:
            from edge.runtime.events import EventStage

            self.events = EventStage(cfg.events, cfg.device.id, self.chosen.calibration.pitch_m, self.times,
                                     clock=self.clock)
        self.state = "ready"

    def _open_sinks(self) -> list:
        from edge.sinks import SinkError, open_sink, redact

        sinks: list = []
        for url in self.config.sinks.urls:
            try:
                sinks.append(open_sink(url, device=self.config.device.id))
            except (SinkError, ValueError, OSError) as exc:
                for s in sinks:
                    s.close()
                raise SetupError(f"sink {redact(url)}: {exc}") from None
        return sinks

    def _previous_seq(self) -> int:
        """The last seq a previous run with this status file published (-1: none), so seq keeps increasing."""
        from edge.runtime.status import StatusFileError, read_status

        path = self.config.status_path()
        if not path.exists():
            return -1
        try:
            old = read_status(path)
        except StatusFileError:
            return -1
        last = (old.get("publish") or {}).get("last_seq")
        if old.get("device") == self.config.device.id and isinstance(last, int) and last >= 0:
            return last
        return -1

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

    # ------------------------------------------------------------------ health
    def _source_stats(self) -> dict[str, Any]:
        if self.source is None:
            return {}
        for _ in range(3):
            try:
                return self.source.stats()
            except RuntimeError:  # a counter dict changed size while copied by the reader thread: try again
                continue
        return {}

    def queue_depths(self) -> dict[str, tuple[int, int] | None]:
        """Read-only, any thread: (depth now, bound) of the reader → pipeline frame queue ("frames") and of the
        pipeline → publisher record queue ("records"); None where there is none (not set up)."""
        pub = self.publisher
        return {"frames": self.source.queue_depth() if self.source is not None else None,
                "records": (pub.queued(), pub.bound) if pub is not None else None}

    def snapshot(self) -> dict[str, Any]:
        """The status (schema cavatar.status/1): every counter, stage times, sinks (see edge.runtime.status)."""
        from edge.sinks import redact

        now = self.clock()
        c = self.counters.snapshot()
        st = self._source_stats()
        info = self.source.info if self.source is not None else None
        board = {}
        if info is not None:
            board = {"device_id": info.device_id, "rows": int(info.rows), "cols": int(info.cols),
                     "adc_bits": int(info.adc_bits), "rate_hz": round(info.rate_mhz / 1000.0, 3),
                     "firmware": f"{info.fw_major}.{info.fw_minor}.{info.fw_patch}",
                     "protocol_version": int(info.protocol_version)}
        state = self.state
        if state == "running" and st.get("board_mismatch"):
            state = "board_mismatch"  # another board answered: frames held back (edge.sources.carpet)
        src_queue = dict(st.get("source", {}))
        src_queue.setdefault("dropped_slow_consumer", 0)
        frames = {k: c.get(k, 0) for k in FRAME_COUNTERS}
        work: dict[str, Any] = {k: c.get(k, 0) for k in WORK_COUNTERS}
        work["tracks_open"] = self.stages.tracks_open if self.stages else 0
        work["saved"] = {"frames_without_inference": c.get("frames_empty", 0) + c.get("frames_unconfirmed", 0),
                         "encoder_runs": c.get("person_frames", 0) - c.get("encoder_runs", 0),
                         "head_runs": c.get("person_frames", 0) - c.get("head_runs", 0)}
        publish: dict[str, Any] = {k: c.get(k, 0) for k in PUBLISH_COUNTERS}
        publish["queued"] = self.publisher.queued() if self.publisher else 0
        publish["last_seq"] = self.publisher.last_seq if self.publisher else None
        uptime = time.monotonic() - self._started_mono if self._started_mono else 0.0
        board_health = self.board.as_dict(time.monotonic()) if self.board is not None else None
        board_lost = board_health is not None and not board_health["connected"]
        publish["sinks"] = {}
        for sink in self.sinks or []:
            try:
                publish["sinks"][redact(sink.describe())] = sink.stats()
            except Exception as exc:
                publish["sinks"][redact(sink.describe())] = {"error": str(exc)}
        return {
            "schema": SCHEMA, "device": self.config.device.id, "state": state, "error": self.error,
            "end_reason": self.end_reason, "pid": os.getpid(), "version": __version__,
            "started": self._started_wall, "updated": now,
            "uptime_s": round(uptime, 3), "fps": round(self._fps, 2),
            "fps_mean": round(c.get("frames_in", 0) / uptime, 2) if uptime > 0 else 0.0,
            "people": self.stages.people_now if self.stages and not board_lost else 0,
            "board_health": board_health,
            "source": {"url": redact(self.config.source.url), "board": board, "queue": src_queue,
                       "decoder": st.get("decoder", {}), "assembly": st.get("frames", {}),
                       "board_status": st.get("board_status", {}), "board_mismatch": st.get("board_mismatch")},
            "frames": frames, "invalid_reasons": self.invalid.snapshot(), "work": work,
            "stages_ms": self.times.summary(), "publish": publish,
            "calibration": self._calibration_status(now), "model": self._model_status(),
        }

    def _calibration_status(self, now: float) -> dict[str, Any]:
        if self.chosen is None:
            return {}
        from datetime import datetime, timezone

        cal = self.chosen.calibration
        age_days = cal.age_s(datetime.fromtimestamp(now, timezone.utc)) / 86400.0
        out = {"file": str(self.chosen.path), "automatic": self.chosen.automatic, "sha256": cal.sha256[:12],
               "created": cal.created, "age_days": round(age_days, 3),
               "max_age_days": self.config.calibration.max_age_days,
               "due": age_days > self.config.calibration.max_age_days}
        if self.stages is not None:
            out["runtime"] = dict(self.stages.calibrated.counters)
        return out

    def _model_status(self) -> dict[str, Any]:
        if self.bundle is None:
            return {}
        body = self.bundle.manifest.get("body_model", {})
        return {"bundle": str(self.bundle.folder), "version": self.bundle.version,
                "body_model": f"{body.get('name')}@{str(body.get('sha256', ''))[:12]}"}

    def write_status(self) -> None:
        snap = self.snapshot()
        mark = (time.monotonic(), snap["frames"]["frames_in"])
        if self._fps_mark is not None and mark[0] > self._fps_mark[0]:
            self._fps = (mark[1] - self._fps_mark[1]) / (mark[0] - self._fps_mark[0])
            snap["fps"] = round(self._fps, 2)
        self._fps_mark = mark
        write_status(self.config.status_path(), snap)

    def info(self, state: str | None = None) -> dict[str, Any]:
        """The sinks' info payload (MQTT: retained on <prefix>/<device>/info): versions, calibration age, health.

        Telemetry only: no key that looks like sensor data and no arrays (edge.record.check_telemetry).
        """
        s = self.snapshot()
        fr, work, pub, stages = s["frames"], s["work"], s["publish"], s["stages_ms"]
        board = s["source"]["board"]
        cal = s["calibration"]
        decoder_dropped = s["source"]["decoder"].get("dropped_total", 0)
        asm = s["source"]["assembly"]
        return {
            "state": state or s["state"], "runtime_version": __version__, "model": s["model"].get("version"),
            "body_model": s["model"].get("body_model"), "board_device_id": board.get("device_id"),
            "firmware": board.get("firmware"), "protocol_version": board.get("protocol_version"),
            "grid": [board.get("rows"), board.get("cols")] if board else None, "rate_hz": board.get("rate_hz"),
            "board_connected": None if s["board_health"] is None else s["board_health"]["connected"],
            "activities": list(self.bundle.activities) if self.bundle is not None else None,
            "calibration": {"sha256": cal.get("sha256"), "created": cal.get("created"), "age_days": cal.get("age_days"),
                            "max_age_days": cal.get("max_age_days"), "due": cal.get("due"), "automatic": cal.get("automatic")},
            "started": s["started"], "uptime_s": s["uptime_s"],
            "health": {
                "fps": s["fps"], "people": s["people"], "frames_in": fr["frames_in"],
                "last_frame_age_s": None if s["board_health"] is None else s["board_health"]["last_frame_age_s"],
                "frames_dropped": s["source"]["queue"].get("dropped_slow_consumer", 0),
                "frames_lost_on_link": asm.get("crc_mismatch", 0) + asm.get("torn_dropped", 0) + asm.get("missed_frames", 0),
                "decoder_dropped": decoder_dropped, "frames_invalid": fr["frames_invalid"],
                "frames_empty": fr["frames_empty"], "encoder_runs": work["encoder_runs"], "head_runs": work["head_runs"],
                "still_reuses": work["still_reuses"], "records": pub["records"], "heartbeats": pub["heartbeats"],
                "queue_dropped": pub["queue_dropped"], "ms_per_frame": stages["frame"]["median_ms"],
                "ms_per_frame_p99": stages["frame"]["p99_ms"], "publish_lag_ms": stages["lag"]["median_ms"],
            },
        }


__all__ = ["Runtime"]
