"""Named event counts, thread-safe: the one counter class of the runtime, its sinks and its status.

    c = Counters(("sent", "dropped"))   # names listed up front always show, at 0
    c.add("sent"); c.add("dropped", 3)
    c.snapshot()                       # {"sent": 1, "dropped": 3}

Written by several threads (reader, pipeline, publisher, a sink's network thread), read by
the status writer; every method takes the one lock.
"""

from __future__ import annotations

import threading


class Counters:
    """Named event counts (thread-safe); a name not listed at construction starts at 0 when first added."""

    def __init__(self, names: tuple[str, ...] = ()) -> None:
        self._lock = threading.Lock()
        self._values: dict[str, int] = dict.fromkeys(names, 0)

    def add(self, name: str, n: int = 1) -> None:
        with self._lock:
            self._values[name] = self._values.get(name, 0) + n

    def set(self, name: str, value: int) -> None:
        with self._lock:
            self._values[name] = value

    def get(self, name: str) -> int:
        with self._lock:
            return self._values.get(name, 0)

    def snapshot(self) -> dict[str, int]:
        with self._lock:
            return dict(self._values)


__all__ = ["Counters"]
