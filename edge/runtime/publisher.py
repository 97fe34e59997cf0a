"""The publisher thread: records from the pipeline → every sink, off the pipeline's clock.

The pipeline hands records over with :meth:`Publisher.put_record`, which never blocks: the
queue holds ``queue_records``; when it is full the OLDEST record is dropped and counted
(``queue_dropped``; its seq is then missing downstream, as a loss should be). Info and
presence are latest-value slots (a newer one replaces one not yet sent). Only this thread
touches the sinks, so they need no locking against the runtime.

:meth:`close` drains: every record queued before it is published, then each sink is
closed (an MQTT sink publishes "offline" before it disconnects; a JSON-lines file is
flushed and fsynced), within ``timeout_s``.

Presence (people count and activities) goes to the sinks when the count changes, or when
the activities change and the last presence is at least ``presence_s`` old: a low-rate
state for Home Assistant, not a per-frame stream.
"""

from __future__ import annotations

import logging
import threading
import time
from collections import deque
from typing import Any, Sequence

from edge.runtime.counters import Counters, StageTimes

log = logging.getLogger(__name__)


class Publisher:
    def __init__(self, sinks: Sequence[Any], *, counters: Counters, times: StageTimes, queue_records: int = 256,
                 presence_s: float = 1.0, clock=time.time) -> None:
        self.sinks = list(sinks)
        self.counters, self.times = counters, times
        self.presence_s = presence_s
        self.clock = clock
        self._cond = threading.Condition()
        self._records: deque[tuple[dict, float]] = deque()
        self._events: deque[dict] = deque()  # fall / person-down events: rare, never dropped
        self._max = max(1, int(queue_records))
        self._info: dict | None = None
        self._presence: tuple[int, tuple[str, ...]] | None = None
        self._presence_sent: tuple[int, tuple[str, ...]] | None = None
        self._presence_t = -1e18
        self._closing = False
        self._thread: threading.Thread | None = None
        self.last_seq: int | None = None
        self._errors_said: set[str] = set()

    # ------------------------------------------------------------------ producer side
    def start(self) -> None:
        for sink in self.sinks:
            self._call(sink, "publish_status", True)
        self._thread = threading.Thread(target=self._run, name="publisher", daemon=True)
        self._thread.start()

    def put_record(self, record: dict, frame_time_s: float) -> None:
        """Queue one record (``frame_time_s``: wall time the frame completed, for the lag)."""
        with self._cond:
            if len(self._records) >= self._max:
                self._records.popleft()
                self.counters.add("queue_dropped")
            self._records.append((record, frame_time_s))
            self._cond.notify()

    def put_event(self, payload: dict) -> None:
        """Queue one ``cavatar.events/1`` payload (every sink's publish_event); never dropped."""
        with self._cond:
            self._events.append(payload)
            self._cond.notify()

    def put_info(self, info: dict) -> None:
        with self._cond:
            self._info = info
            self._cond.notify()

    def put_presence(self, count: int, activities: Sequence[str]) -> None:
        key = (int(count), tuple(activities))
        with self._cond:
            if key == self._presence_sent and self._presence is None:
                return
            self._presence = key
            self._cond.notify()

    def queued(self) -> int:
        with self._cond:
            return len(self._records)

    @property
    def bound(self) -> int:
        """Most records the queue holds (``queue_records``); beyond it the oldest is dropped."""
        return self._max

    def close(self, timeout_s: float = 10.0) -> None:
        """Publish everything queued, close every sink; bounded by ``timeout_s``."""
        with self._cond:
            self._closing = True
            self._cond.notify()
        if self._thread is not None:
            self._thread.join(timeout=timeout_s)
            if self._thread.is_alive():
                log.error("publisher: still busy after %.0f s; %d records not published", timeout_s, self.queued())
        else:
            self._close_sinks()

    # ------------------------------------------------------------------ the thread
    def _run(self) -> None:
        try:
            while True:
                with self._cond:
                    while not (self._records or self._events or self._info is not None or self._presence_due()
                               or self._closing):
                        self._cond.wait(0.25)
                    item = self._records.popleft() if self._records else None
                    event = self._events.popleft() if self._events else None
                    info, self._info = self._info, None
                    presence = None
                    if self._presence_due():
                        presence, self._presence = self._presence, None
                    done = self._closing and item is None and event is None and info is None and presence is None
                if done:
                    break
                if item is not None:
                    self._publish(*item)
                if event is not None:
                    for sink in self.sinks:
                        self._call(sink, "publish_event", event)
                    self.counters.add("events_published")
                if info is not None:
                    for sink in self.sinks:
                        self._call(sink, "publish_info", info)
                    self.counters.add("info_published")
                if presence is not None:
                    for sink in self.sinks:
                        self._call(sink, "publish_presence", presence[0], list(presence[1]))
                    self._presence_sent, self._presence_t = presence, time.monotonic()
        finally:
            self._close_sinks()

    def _presence_due(self) -> bool:
        if self._presence is None:
            return False
        if self._presence_sent is None or self._presence[0] != self._presence_sent[0]:
            return True
        return self._closing or time.monotonic() - self._presence_t >= self.presence_s

    def _publish(self, record: dict, frame_time_s: float) -> None:
        t0 = time.perf_counter()
        for sink in self.sinks:
            self._call(sink, "publish_bodies", record)
        self.times.add("publish", (time.perf_counter() - t0) * 1e3)
        self.times.add("lag", max(0.0, self.clock() - frame_time_s) * 1e3)
        self.counters.add("published")
        self.last_seq = record["seq"]

    def _call(self, sink: Any, method: str, *args: Any) -> None:
        try:
            getattr(sink, method)(*args)
        except Exception as exc:  # a sink failure never stops the runtime: logged once per kind, counted
            self.counters.add("sink_errors")
            key = f"{sink.describe()} {method} {type(exc).__name__}"
            if key not in self._errors_said:
                self._errors_said.add(key)
                log.error("%s.%s failed: %s", sink.describe(), method, exc)

    def _close_sinks(self) -> None:
        for sink in self.sinks:
            try:
                sink.close()
            except Exception as exc:
                log.error("closing %s failed: %s", sink.describe(), exc)


__all__ = ["Publisher"]
