"""The status file: the runtime's health, rewritten atomically every second; and how to print it.

Schema ``cavatar.status/1`` (JSON). Top level: schema, device, state (running, stopping,
stopped, failed; board_mismatch while another board answers and its frames are held back), error,
end_reason, pid, version, started, updated (Unix seconds),
uptime_s, fps (over the last status period), fps_mean (over the run), people (confirmed
people in the last frame), and the groups:

- ``source``: url (password redacted), board (device id, grid, ADC bits, rate, firmware),
  ``queue`` (frames dropped for a slow pipeline, reconnects, stalls), ``decoder`` (packets,
  bytes, dropped by reason, e.g. bad_crc, missed), ``assembly`` (crc_mismatch, torn_dropped,
  missed_frames, duplicate_frames, …), ``board_status`` (the board's last STATUS packet),
  ``board_mismatch`` (why frames are held back: another board's identity; null otherwise);
- ``frames``: frames_in, frames_invalid, frames_empty, frames_unconfirmed, frames_people,
  frames_failed; ``invalid_reasons``: reason → count;
- ``work``: person_frames, encoder_runs, head_runs, still_reuses, tracks_started,
  tracks_freed, tracks_open, and ``saved`` (encoder and head runs avoided, frames without inference);
- ``stages_ms``: stage → {median_ms, p99_ms, n} over the last ``timing_window`` frames
  (decode, calibrate, scene, encoder, head, body, frame, publish, lag);
- ``publish``: records, heartbeats, queue_dropped, published, sink_errors, queued,
  last_seq, info_published, and ``sinks``: URL → that sink's own counters;
- ``calibration``: file, sha256, created, age_days, max_age_days, due, automatic, and the
  runtime calibration's counters; ``model``: bundle, version, body model.
"""

from __future__ import annotations

import json
from datetime import datetime, timezone
from pathlib import Path
from typing import Any

SCHEMA = "cavatar.status/1"


def write_status(path: str | Path, status: dict[str, Any]) -> None:
    """Write ``status`` to ``path`` atomically (cavatar_common.atomic: a temporary file beside it, then a rename). Not fsynced:
    it is rewritten every second, on a tmpfs (/run/cavatar) in the service, and a reader never sees half of it."""
    from cavatar_common.atomic import write_atomic

    p = Path(path)
    p.parent.mkdir(parents=True, exist_ok=True)
    text = json.dumps(status, indent=1, sort_keys=False, allow_nan=False, default=_jsonable) + "\n"
    write_atomic(p, text, durable=False)


def _jsonable(obj: Any) -> Any:
    if hasattr(obj, "item"):  # numpy scalars
        return obj.item()
    if isinstance(obj, (set, tuple)):
        return list(obj)
    return str(obj)


class StatusFileError(Exception):
    pass


def read_status(path: str | Path) -> dict[str, Any]:
    p = Path(path)
    try:
        data = json.loads(p.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise StatusFileError(f"no status file {p}: is `cavatar run` running with this status file "
                              "(runtime.status_file in its config, or --status-file)?") from None
    except (OSError, ValueError) as exc:
        raise StatusFileError(f"{p} is not a readable status file ({exc})") from None
    if not isinstance(data, dict) or data.get("schema") != SCHEMA:
        raise StatusFileError(f"{p} is not a cavatar status file (schema {data.get('schema') if isinstance(data, dict) else None!r})")
    return data


def _ms(stage: dict[str, Any] | None) -> str:
    if not stage or stage.get("median_ms") is None:
        return "-"
    return f"{stage['median_ms']:.2f}/{stage['p99_ms']:.2f}"


def _reasons(counts: dict[str, int] | None) -> str:
    counts = {k: v for k, v in (counts or {}).items() if v}
    return " (" + ", ".join(f"{k} {v}" for k, v in sorted(counts.items())) + ")" if counts else ""


def _when(t: float | None) -> str:
    if not t:
        return "-"
    return datetime.fromtimestamp(t, timezone.utc).astimezone().strftime("%Y-%m-%d %H:%M:%S")


def _board_line(health: dict[str, Any] | None) -> str:
    if not health:
        return "  board health: -"
    if health.get("connected"):
        return f"  board health: connected (last frame {health.get('last_frame_age_s', 0):.1f} s ago)"
    return (f"  board health: LOST, reported unavailable — {health.get('reason') or 'no frames'} "
            f"(last frame {health.get('last_frame_age_s', 0):.0f} s ago; limit {health.get('timeout_s')} s)")


def format_status(s: dict[str, Any], now_s: float | None = None) -> str:
    """A readable multi-line report of a status dict (what `cavatar status` prints)."""
    import time

    now_s = time.time() if now_s is None else now_s
    fr, work, pub = s.get("frames", {}), s.get("work", {}), s.get("publish", {})
    src, cal, model = s.get("source", {}), s.get("calibration", {}), s.get("model", {})
    age = now_s - s.get("updated", now_s)
    stale = "  (STALE: not updated for %.0f s; is the runtime still alive?)" % age if s.get("state") == "running" and age > 5 else ""
    lines = [
        f"device {s.get('device')}: {s.get('state')}{stale}" + (f" — error: {s['error']}" if s.get("error") else ""),
        f"  started {_when(s.get('started'))}, updated {_when(s.get('updated'))}, uptime {s.get('uptime_s', 0):.0f} s, "
        f"pid {s.get('pid')}",
    ]
    board = src.get("board") or {}
    q, dec, asm = src.get("queue", {}), src.get("decoder", {}), src.get("assembly", {})
    if src.get("board_mismatch"):
        lines.append(f"  BOARD MISMATCH, nothing published: {src['board_mismatch']}")
    lines += [
        f"source {src.get('url')}: board {board.get('device_id', '-')} {board.get('rows', '?')}x{board.get('cols', '?')}, "
        f"{board.get('adc_bits', '?')}-bit, {board.get('rate_hz', '?')} Hz, firmware {board.get('firmware', '-')}",
        f"  {s.get('fps', 0):.1f} fps now, {s.get('fps_mean', 0):.1f} on average; dropped for a slow pipeline "
        f"{q.get('dropped_slow_consumer', 0)}, "
        f"reconnects {q.get('reconnects', 0)}, stalls {q.get('stalls', 0)}",
        _board_line(s.get("board_health")),
        f"  decoder: {dec.get('packets', 0)} packets, dropped {dec.get('dropped_total', 0)}{_reasons(dec.get('dropped'))}, "
        f"missed {dec.get('missed', 0)}; frames: crc mismatch {asm.get('crc_mismatch', 0)}, "
        f"torn {asm.get('torn_dropped', 0)}, missed {asm.get('missed_frames', 0)}, duplicate {asm.get('duplicate_frames', 0)}",
        f"frames: in {fr.get('frames_in', 0)}, with people {fr.get('frames_people', 0)}, empty {fr.get('frames_empty', 0)}, "
        f"unconfirmed {fr.get('frames_unconfirmed', 0)}, invalid {fr.get('frames_invalid', 0)}{_reasons(s.get('invalid_reasons'))}, "
        f"failed {fr.get('frames_failed', 0)}; people now {s.get('people', 0)}",
        f"work: person-frames {work.get('person_frames', 0)}, encoder runs {work.get('encoder_runs', 0)}, head runs "
        f"{work.get('head_runs', 0)}, still reuses {work.get('still_reuses', 0)}, tracks open {work.get('tracks_open', 0)} "
        f"(started {work.get('tracks_started', 0)}, freed {work.get('tracks_freed', 0)})",
        f"  saved: {work.get('saved', {}).get('frames_without_inference', 0)} frames without inference, "
        f"{work.get('saved', {}).get('encoder_runs', 0)} encoder and {work.get('saved', {}).get('head_runs', 0)} head runs",
        "stages, ms median/p99: " + ", ".join(f"{k} {_ms(v)}" for k, v in (s.get("stages_ms") or {}).items()),
        f"publish: records {pub.get('records', 0)}, heartbeats {pub.get('heartbeats', 0)}, published "
        f"{pub.get('published', 0)}, queued {pub.get('queued', 0)}, queue dropped {pub.get('queue_dropped', 0)}, "
        f"sink errors {pub.get('sink_errors', 0)}, last seq {pub.get('last_seq')}",
    ]
    for url, st in (pub.get("sinks") or {}).items():
        extra = ", ".join(f"{k} {v}" for k, v in st.items() if k not in ("sent", "dropped", "errors", "refused"))
        lines.append(f"  {url}: sent {st.get('sent', 0)}, dropped {st.get('dropped', 0)}, errors {st.get('errors', 0)}, "
                     f"refused {st.get('refused', 0)}" + (f"; {extra}" if extra else ""))
    due = " — DUE for recalibration" if cal.get("due") else ""
    lines += [
        f"calibration {cal.get('file')}{' (automatic, virtual carpet)' if cal.get('automatic') else ''}: sha256 "
        f"{cal.get('sha256')}, created {cal.get('created')}, {cal.get('age_days', 0):.1f} of {cal.get('max_age_days')} days{due}",
        f"model {model.get('version')} ({model.get('bundle')}), body model {model.get('body_model')}",
    ]
    return "\n".join(lines)


__all__ = ["SCHEMA", "StatusFileError", "format_status", "read_status", "write_status"]
