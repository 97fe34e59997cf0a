"""The reader thread of the runtime: a :class:`~edge.sources.CarpetSource` that records its decoding time.

The source's own reader thread reads the link, decodes packets, assembles frames and puts
them in its bounded queue; on a live link a slow pipeline makes it drop the oldest frame
(``dropped_slow_consumer``), so the pipeline always gets the newest. The source reports the
time spent decoding and assembling each frame (``on_decoded``); here it becomes that frame's
``decode`` stage time.
"""

from __future__ import annotations

from typing import Any, cast

from edge.runtime.counters import StageTimes
from edge.sources import CarpetSource, open_source


class TimedCarpetSource(CarpetSource):
    """CarpetSource + ``decode`` stage times (protocol decoding and frame assembly per frame) in ``times``."""

    def __init__(self, link: Any, *, times: StageTimes, **kwargs: Any) -> None:
        super().__init__(link, on_decoded=lambda ms: times.add("decode", ms), **kwargs)
        self.times = times


def open_timed_source(url: str, times: StageTimes, **kwargs: Any) -> TimedCarpetSource:
    """Like :func:`edge.sources.open_source`, with decode timing (not started)."""
    return cast(TimedCarpetSource, open_source(url, source_class=TimedCarpetSource, times=times, **kwargs))


__all__ = ["TimedCarpetSource", "open_timed_source"]
