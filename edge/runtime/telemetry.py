"""The runtime's telemetry: its status snapshot (schema cavatar.status/1), the status file and the sinks' info.

    snap = rt.snapshot()       # every counter, stage times, sinks, calibration age, model (see edge.runtime.status)
    rt.write_status()          # the snapshot, with the fps since the last write, to [runtime] status_file
    payload = rt.info()        # the sinks' info (MQTT: retained <prefix>/<device>/info): telemetry only

Read-only on the pipeline's state: any thread may call these (the monitor thread does, every
``runtime.status_s`` and ``runtime.info_s``).
"""

from __future__ import annotations

import os
import time
from typing import TYPE_CHECKING, Any, Callable

from edge import __version__
from edge.runtime.board_health import BoardHealth
from edge.runtime.carpet_calibration import ChosenCalibration
from edge.runtime.config import RuntimeConfig
from edge.runtime.counters import FRAME_COUNTERS, PUBLISH_COUNTERS, WORK_COUNTERS, Counters, StageTimes
from edge.runtime.publisher import Publisher
from edge.runtime.stages import FrameStages
from edge.runtime.status import SCHEMA, write_status
from edge.sources.base import FrameSource

if TYPE_CHECKING:
    from edge.infer.bundle import ModelBundle


def board_identity(info: Any) -> dict[str, Any]:
    """The board's INFO (as the source reports it) as the status file's ``source.board``."""
    return {"device_id": info.device_id, "rows": int(info.rows), "cols": int(info.cols),
            "adc_bits": int(info.adc_bits), "rate_hz": round(info.rate_mhz / 1000.0, 3),
            "firmware": f"{info.fw_major}.{info.fw_minor}.{info.fw_patch}",
            "protocol_version": int(info.protocol_version)}


def info_payload(s: dict[str, Any], activities: list[str] | None, state: str | None = None) -> dict[str, Any]:
    """The sinks' info payload from a status snapshot ``s``: versions, board, calibration age, health.

    Telemetry only: no key that looks like sensor data and no arrays (edge.record.check_telemetry).
    ``activities``: the bundle's activity labels (None: no bundle); ``state`` replaces the snapshot's.
    """
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
        "activities": activities,
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


class RuntimeTelemetry:
    """The telemetry half of :class:`edge.runtime.loop.Runtime` (a mixin): what it reads to report."""

    config: RuntimeConfig
    clock: Callable[[], float]
    times: StageTimes
    counters: Counters
    invalid: Counters
    state: str
    error: str | None
    end_reason: str | None
    source: FrameSource | None
    sinks: list | None
    bundle: ModelBundle | None
    chosen: ChosenCalibration | None
    stages: FrameStages | None
    publisher: Publisher | None
    board: BoardHealth | None
    _started_wall: float | None
    _started_mono: float | None
    _fps: float
    _fps_mark: tuple[float, int] | None

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
        board = board_identity(info) if info is not None else {}
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
        """The snapshot to the status file, its fps measured since the last write."""
        snap = self.snapshot()
        mark = (time.monotonic(), snap["frames"]["frames_in"])
        if self._fps_mark is not None and mark[0] > self._fps_mark[0]:
            self._fps = (mark[1] - self._fps_mark[1]) / (mark[0] - self._fps_mark[0])
            snap["fps"] = round(self._fps, 2)
        self._fps_mark = mark
        write_status(self.config.status_path(), snap)

    def info(self, state: str | None = None) -> dict[str, Any]:
        """The sinks' info payload (MQTT: retained on <prefix>/<device>/info): versions, calibration age, health."""
        s = self.snapshot()
        return info_payload(s, list(self.bundle.activities) if self.bundle is not None else None, state)


__all__ = ["RuntimeTelemetry", "board_identity", "info_payload"]
