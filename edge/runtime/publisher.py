"""The publisher: records from the pipeline → every sink, each sink on its own thread.

Every sink has its own worker thread and its own bounded queue, so a sink that blocks (a
``jsonl:-`` piped into a reader that stopped reading, a broker that hangs) holds back only
itself: the pipeline, the other sinks, the status file and shutdown go on.

The pipeline hands records over with :meth:`Publisher.put_record`, which never blocks: each
sink's queue holds ``queue_records``; when one is full that sink's OLDEST record is dropped
and counted (``queue_dropped``, and per sink in :meth:`dropped_by_sink`; its seq is then
missing downstream of that sink, as a loss should be). ``published`` counts records every
sink has handled. Info and presence are latest-value slots per sink (a newer one replaces
one not yet sent). Only the workers touch the sinks, so sinks need no locking against the
runtime.

:meth:`close` drains: every record queued before it is published, then each sink is
closed (an MQTT sink publishes "offline" before it disconnects; a JSON-lines file is
flushed and fsynced), all within one ``timeout_s``. A sink still busy then, or stuck in one
publish call for ``stall_s``, is abandoned (its worker is a daemon thread), logged with the
records it did not publish.

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


class _Entry:
    """One record on its way to every sink; ``pending`` sinks still to handle it."""

    __slots__ = ("record", "frame_time_s", "pending", "lost")

    def __init__(self, record: dict, frame_time_s: float, sinks: int) -> None:
        self.record, self.frame_time_s = record, frame_time_s
        self.pending, self.lost = sinks, False


class _SinkWorker:
    """One sink's thread and bounded queue."""

    def __init__(self, publisher: "Publisher", sink: Any, index: int) -> None:
        self.pub, self.sink = publisher, sink
        self.cond = threading.Condition()
        self.records: deque[_Entry] = deque()
        self.events: deque[dict] = deque()  # fall / person-down events: rare, never dropped
        self.info: dict | None = None
        self.presence: tuple[int, tuple[str, ...]] | None = None
        self.closing = False
        self.dropped = 0
        self.busy_since: float | None = None  # monotonic time the current publish call began; None between calls
        self.thread = threading.Thread(target=self.run, name=f"publisher-{index}", daemon=True)

    def put(self, entry: _Entry) -> _Entry | None:
        """Queue ``entry``; return the entry dropped to make room (oldest), if any."""
        with self.cond:
            old = None
            if len(self.records) >= self.pub.bound:
                old = self.records.popleft()
                self.dropped += 1
            self.records.append(entry)
            self.cond.notify()
        return old

    def put_event(self, payload: dict) -> None:
        with self.cond:
            self.events.append(payload)
            self.cond.notify()

    def set_slot(self, name: str, value: Any) -> None:
        with self.cond:
            setattr(self, name, value)
            self.cond.notify()

    def queued(self) -> int:
        with self.cond:
            return len(self.records)

    def call(self, method: str, *args: Any) -> None:
        self.busy_since = time.monotonic()
        try:
            self.pub._call(self.sink, method, *args)
        finally:
            self.busy_since = None

    def stuck(self, now: float, stall_s: float) -> bool:
        """In one publish call for more than ``stall_s`` (a sink's own close() is bounded by the sink)."""
        since = self.busy_since
        return since is not None and now - since > stall_s

    def run(self) -> None:
        pub = self.pub
        try:
            while True:
                with self.cond:
                    while not (self.records or self.events or self.info is not None or self.presence is not None
                               or self.closing):
                        self.cond.wait(0.25)
                    entry = self.records.popleft() if self.records else None
                    event = self.events.popleft() if self.events else None
                    info, self.info = self.info, None
                    presence, self.presence = self.presence, None
                    if entry is None and event is None and info is None and presence is None:
                        break  # closing and drained
                if entry is not None:
                    t0 = time.perf_counter()
                    self.call("publish_bodies", entry.record)
                    pub.times.add("publish", (time.perf_counter() - t0) * 1e3)
                    pub._handled(entry)
                if event is not None:
                    self.call("publish_event", event)
                if info is not None:
                    self.call("publish_info", info)
                if presence is not None:
                    self.call("publish_presence", presence[0], list(presence[1]))
        finally:
            try:
                self.sink.close()
            except Exception as exc:
                log.error("closing %s failed: %s", self.sink.describe(), exc)


class Publisher:
    def __init__(self, sinks: Sequence[Any], *, counters: Counters, times: StageTimes, queue_records: int = 256,
                 presence_s: float = 1.0, clock=time.time) -> None:
        self.sinks = list(sinks)
        self.counters, self.times = counters, times
        self.presence_s = presence_s
        self.clock = clock
        self._max = max(1, int(queue_records))
        self._lock = threading.Lock()
        self._workers = [_SinkWorker(self, sink, i) for i, sink in enumerate(self.sinks)]
        self._presence_sent: tuple[int, tuple[str, ...]] | None = None
        self._presence_wait: tuple[int, tuple[str, ...]] | None = None
        self._presence_t = -1e18
        self._started = False
        self._closed = False
        self.last_seq: int | None = None
        self._errors_said: set[str] = set()

    # ------------------------------------------------------------------ producer side
    def start(self) -> None:
        for sink in self.sinks:
            self._call(sink, "publish_status", True)
        for worker in self._workers:
            worker.thread.start()
        self._started = True

    def put_record(self, record: dict, frame_time_s: float) -> None:
        """Queue one record for every sink (``frame_time_s``: wall time the frame completed, for the lag).

        Never blocks: a sink whose queue is full loses its oldest record (counted)."""
        if not self._workers:
            self._finish(_Entry(record, frame_time_s, 0))
            return
        entry = _Entry(record, frame_time_s, len(self._workers))
        for worker in self._workers:
            old = worker.put(entry)
            if old is not None:
                self.counters.add("queue_dropped")
                with self._lock:
                    old.lost = True
                self._handled(old, publish=False)

    def put_event(self, payload: dict) -> None:
        """Queue one ``cavatar.events/1`` payload for every sink (publish_event); never dropped."""
        self.counters.add("events_published")
        for worker in self._workers:
            worker.put_event(payload)

    def put_info(self, info: dict) -> None:
        self.counters.add("info_published")
        for worker in self._workers:
            worker.set_slot("info", info)

    def put_presence(self, count: int, activities: Sequence[str]) -> None:
        """Presence for the sinks: sent now if the count changed, else at most every ``presence_s``."""
        key = (int(count), tuple(activities))
        now = time.monotonic()
        with self._lock:
            if key == self._presence_sent:
                self._presence_wait = None
                return
            count_changed = self._presence_sent is None or key[0] != self._presence_sent[0]
            if not count_changed and now - self._presence_t < self.presence_s:
                self._presence_wait = key  # sent by a later call (or at close) once presence_s has passed
                return
            self._presence_sent, self._presence_t, self._presence_wait = key, now, None
        for worker in self._workers:
            worker.set_slot("presence", key)

    def queued(self) -> int:
        """Records waiting for the slowest sink."""
        return max((w.queued() for w in self._workers), default=0)

    def dropped_by_sink(self) -> dict[str, int]:
        """Records each sink lost because its queue was full (by ``sink.describe()``)."""
        return {w.sink.describe(): w.dropped for w in self._workers}

    @property
    def bound(self) -> int:
        """Most records one sink's queue holds (``queue_records``); beyond it its oldest is dropped."""
        return self._max

    def close(self, timeout_s: float = 10.0, stall_s: float = 2.0) -> None:
        """Publish everything queued, close every sink; all within ``timeout_s``. A sink stuck in one publish call
        for more than ``stall_s`` is abandoned at once (a pipe nobody reads never drains)."""
        if self._closed:
            return
        self._closed = True
        with self._lock:
            presence, self._presence_wait = self._presence_wait, None
        if presence is not None:
            for worker in self._workers:
                worker.set_slot("presence", presence)
        for worker in self._workers:
            worker.set_slot("closing", True)
        if not self._started:
            for worker in self._workers:
                worker.run()
            return
        t0 = time.monotonic()
        deadline = t0 + timeout_s
        waiting = list(self._workers)
        while waiting and time.monotonic() < deadline:
            waiting[0].thread.join(timeout=min(0.05, max(0.0, deadline - time.monotonic())))
            now = time.monotonic()
            waiting = [w for w in waiting if w.thread.is_alive() and not w.stuck(now, stall_s)]
        for worker in self._workers:
            if worker.thread.is_alive():
                log.error("publisher: %s still busy after %.1f s; abandoned with %d records not published",
                          worker.sink.describe(), time.monotonic() - t0, worker.queued())

    # ------------------------------------------------------------------ the workers
    def _handled(self, entry: _Entry, publish: bool = True) -> None:
        with self._lock:
            entry.pending -= 1
            done = entry.pending == 0
        if done:
            self._finish(entry)

    def _finish(self, entry: _Entry) -> None:
        if entry.lost:
            return
        self.times.add("lag", max(0.0, self.clock() - entry.frame_time_s) * 1e3)
        self.counters.add("published")
        with self._lock:
            seq = entry.record["seq"]
            if self.last_seq is None or seq > self.last_seq:
                self.last_seq = seq

    def _call(self, sink: Any, method: str, *args: Any) -> None:
        try:
            getattr(sink, method)(*args)
        except Exception as exc:  # a sink failure never stops the runtime: logged once per kind, counted
            self.counters.add("sink_errors")
            key = f"{sink.describe()} {method} {type(exc).__name__}"
            with self._lock:
                new = key not in self._errors_said
                self._errors_said.add(key)
            if new:
                log.error("%s.%s failed: %s", sink.describe(), method, exc)


__all__ = ["Publisher"]
