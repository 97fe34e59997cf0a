"""The reader thread: a :class:`~edge.sources.CarpetSource` that also times its decoding.

The source's own reader thread reads the link, decodes packets, assembles frames and puts
them in its bounded queue; on a live link a slow pipeline makes it drop the oldest frame
(``dropped_slow_consumer``), so the pipeline always gets the newest. Here the decoder's
``feed`` and the assembler's ``push`` are wrapped to measure their time; the time spent
since the last frame is recorded as that frame's ``decode`` milliseconds.
"""

from __future__ import annotations

import time
from typing import Any, cast

from edge.runtime.counters import StageTimes
from edge.sources import CarpetSource, open_source


class _Timed:
    """Wraps ``inner`` so that calls to ``method`` add their duration to ``owner``'s pending decode time."""

    def __init__(self, inner: Any, method: str, owner: "TimedCarpetSource", emits_frames: bool) -> None:
        self._inner, self._method, self._owner, self._emits = inner, method, owner, emits_frames

    def __getattr__(self, name: str) -> Any:
        attr = getattr(self._inner, name)
        if name != self._method:
            return attr

        def timed(*args: Any, **kwargs: Any) -> Any:
            t0 = time.perf_counter()
            out = attr(*args, **kwargs)
            self._owner._decode_s += time.perf_counter() - t0
            if self._emits and out:
                self._owner._frames_done(len(out))
            return out

        return timed


class TimedCarpetSource(CarpetSource):
    """CarpetSource + ``decode`` stage times (protocol decoding and frame assembly per frame)."""

    def __init__(self, link: Any, *, times: StageTimes, **kwargs: Any) -> None:
        super().__init__(link, **kwargs)
        self.times = times
        self._decode_s = 0.0
        self.decoder = _Timed(self.decoder, "feed", self, emits_frames=False)  # type: ignore[assignment]  # a timing proxy

    def _adopt_info(self, info: Any) -> None:
        super()._adopt_info(info)
        if self.assembler is not None and not isinstance(self.assembler, _Timed):
            self.assembler = _Timed(self.assembler, "push", self, emits_frames=True)  # type: ignore[assignment]

    def _handshake(self) -> None:
        super()._handshake()
        self._decode_s = 0.0  # the handshake's decoding belongs to no frame

    @property
    def ended(self) -> bool:
        """True once the reader thread has finished (end of a recording, or a fatal error) and every frame was taken."""
        return self._thread is not None and not self._thread.is_alive() and self._queue.empty()

    def queue_depth(self) -> tuple[int, int]:
        """(frames waiting for the pipeline now, the queue's bound ``queue_frames``); read-only."""
        return self._queue.qsize(), self._queue.maxsize

    def _frames_done(self, n: int) -> None:
        ms = self._decode_s * 1e3 / n
        for _ in range(n):
            self.times.add("decode", ms)
        self._decode_s = 0.0


def open_timed_source(url: str, times: StageTimes, **kwargs: Any) -> TimedCarpetSource:
    """Like :func:`edge.sources.open_source`, with decode timing (not started)."""
    return cast(TimedCarpetSource, open_source(url, source_class=TimedCarpetSource, times=times, **kwargs))


__all__ = ["TimedCarpetSource", "open_timed_source"]
