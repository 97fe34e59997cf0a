"""What every sink is: a small base class, its counters, and URL option parsing.

A sink publishes body records (never pressure). Every ``publish_bodies`` goes through
:func:`edge.record.check_record` first, so a sink accepts only records shaped like the
ones :mod:`edge.record` builds; anything else (an extra ``pressure_kpa`` key, a NaN) is a
:class:`edge.record.RecordError` and nothing is written.

Counters (``stats()``, :class:`edge.counters.Counters` and a :class:`LagWindow`): ``sent`` records
delivered (QoS 0: written to the socket; QoS ≥ 1:
acknowledged; files: written), ``dropped`` records known lost (queue full, disconnected
QoS 0, spool overflow, write errors), ``queued`` records waiting in memory now,
``spooled`` records waiting on disk now, ``errors`` failures seen (connect, write),
``refused`` records refused by the privacy/structure check, ``lag_ms``/``lag_ms_max``
median/max over the last 256 records of publish call → delivered.
"""

from __future__ import annotations

import statistics
import threading
import time
from abc import ABC, abstractmethod
from collections import deque
from contextlib import contextmanager
from typing import Any, Iterator, Mapping, Sequence

from edge.counters import Counters
from edge.record import RecordError, check_record, check_telemetry, dumps
from edge.topics import EVENTS_SCHEMA
from edge.urls import Option, parse_bool, parse_url

__all__ = ["LagWindow", "SINK_COUNTERS", "Sink", "SinkError", "Option", "parse_bool", "parse_sink_url"]


class SinkError(Exception):
    """A sink cannot be opened or used; the message says what to do."""


def parse_sink_url(url: str, scheme: str, form: str, options: dict[str, Option]) -> tuple[str, dict[str, Any]]:
    """:func:`edge.urls.parse_url` for sinks (same typed options, same errors, says "sink")."""
    return parse_url(url, scheme, form, options, kind="sink")


SINK_COUNTERS = ("sent", "dropped", "errors", "refused")


class LagWindow:
    """Publish call → delivered, in milliseconds, over the last ``n`` records (thread-safe)."""

    def __init__(self, n: int = 256) -> None:
        self._lock = threading.Lock()
        self._lags_ms: deque[float] = deque(maxlen=n)

    def add(self, lag_s: float) -> None:
        with self._lock:
            self._lags_ms.append(lag_s * 1000.0)

    def summary(self) -> dict[str, float | None]:
        """{"lag_ms": median, "lag_ms_max": max}, both None before the first delivery."""
        with self._lock:
            lags = list(self._lags_ms)
        return {"lag_ms": round(statistics.median(lags), 3) if lags else None,
                "lag_ms_max": round(max(lags), 3) if lags else None}


class Sink(ABC):
    """Base of every sink. Subclasses implement ``_write_bodies`` and ``close``; the rest is optional."""

    scheme: str = ""

    def __init__(self, device: str) -> None:
        self.device = device
        self.counters = Counters(SINK_COUNTERS)
        self.lags = LagWindow()
        self.closed = False

    # -- the API the runtime uses ---------------------------------------------------------

    def publish_bodies(self, record: Mapping) -> None:
        """Publish one ``cavatar.bodies/1`` record. RecordError (nothing published) if it is not one."""
        with self._counting_refusals():
            check_record(record)
            if record["device"] != self.device:
                raise RecordError(f"record device {record['device']!r} is not this sink's device {self.device!r}")
            line = dumps(record)
        self._check_open()
        self._write_bodies(record, line, time.monotonic())

    def publish_info(self, info: Mapping) -> None:
        """Retained device information (model, versions, calibration age, counters). No arrays, no pressure."""
        with self._counting_refusals():
            check_telemetry(dict(info), "info")
        self._write_info(dict(info))

    def publish_event(self, payload: Mapping) -> None:
        """One ``cavatar.events/1`` payload (a fall or person-down event raised or cleared); checked like info."""
        with self._counting_refusals():
            check_telemetry(dict(payload), "event")
            if payload.get("schema") != EVENTS_SCHEMA or payload.get("device") != self.device:
                raise RecordError(f"not a cavatar.events/1 payload of device {self.device!r}")
            line = dumps(dict(payload))
        self._check_open()
        self._write_event(dict(payload), line)

    def publish_status(self, online: bool) -> None:
        """Availability: True → "online", False → "offline" (close() publishes "offline" itself)."""

    def publish_presence(self, count: int, activities: Sequence[str]) -> None:
        """Low-rate derived state: how many people and what they do (one activity per person)."""

    @abstractmethod
    def close(self) -> None:
        """Deliver what can be delivered within a bounded time, release everything. Idempotent."""

    def stats(self) -> dict[str, Any]:
        out: dict[str, Any] = dict(self.counters.snapshot())
        out.update(self.lags.summary())
        out.update(queued=0, spooled=0)
        out.update(self._gauges())
        return out

    # -- for subclasses -------------------------------------------------------------------

    @contextmanager
    def _counting_refusals(self) -> Iterator[None]:
        """A RecordError raised inside (what a check refused) is counted as ``refused``, then raised on."""
        try:
            yield
        except RecordError:
            self.counters.add("refused")
            raise

    def _check_open(self) -> None:
        if self.closed:
            raise SinkError(f"{self.scheme}:// sink is closed")

    def _count_delivered(self, lag_s: float | None = None, n: int = 1) -> None:
        """``n`` records delivered; ``lag_s`` (publish call → delivered) joins the lag window when known."""
        self.counters.add("sent", n)
        if lag_s is not None:
            self.lags.add(lag_s)

    @abstractmethod
    def _write_bodies(self, record: Mapping, line: str, t_call: float) -> None: ...

    def _write_info(self, info: dict) -> None:
        pass

    def _write_event(self, payload: dict, line: str) -> None:
        pass

    def _gauges(self) -> dict[str, Any]:
        return {}

    def describe(self) -> str:
        return f"{self.scheme}://"

    def __enter__(self) -> "Sink":
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
