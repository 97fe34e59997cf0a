"""Where a session's captures come from: recordings, a live board (with prompts), or
the virtual carpet acting the session out (:class:`calibration.actor.Actor`).

Every provider has ``capture(step, attempt, last_result) -> Capture | None`` (None:
skip the step) and ``say(text)``.
"""

from __future__ import annotations

import sys
import time
from typing import Callable

import numpy as np

from calibration.capture import Capture, OpenFrames, from_source
from calibration.terminal import render_map

PROMPTS = {
    "self_test": ("Self-test", "Keep everyone off the carpet; checking the stream for 3 s.", 3.0),
    "empty": ("Empty capture", "Everyone off the carpet and its rug, please. Recording 10 s.", 10.0),
    "walk": ("Coverage walk", "Walk slowly over the whole carpet, edges included, for 60–90 s, until the map "
             "is filled. Press Ctrl-C when done.", 90.0),
    "board": ("Board equilibration", "Lay the 60×60 cm board flat; stand in its middle and lean slowly in a "
              "circle for 3 s; step off, move the board so it overlaps the last spot by ~10 cm; repeat until the "
              "board has visited the whole carpet (≈ 9 spots on 1.8 m). Ctrl-C when done.", 60.0),
    "stance": ("Known-weight poses", "Sit on the floor, legs stretched out, still, for 4 s; then stand still on "
               "both feet for 3 s at 3–5 spots, stepping off in between.", 30.0),
    "holdout": ("Held-out stance", "Stand still on both feet at one more spot for 3 s.", 4.0),
}


class RecordingProvider:
    """Captures from files (``.npz`` from a session, or ``cavatar record`` byte streams)."""

    def __init__(self, files: dict[str, str], out: Callable[[str], None] = print,
                 open_frames: OpenFrames | None = None) -> None:
        """``open_frames`` replays ``cavatar record`` files (edge.sources.open_source); ``.npz`` files need none."""
        self.files, self.out, self.open_frames = files, out, open_frames

    def capture(self, step: str, attempt: int, last) -> Capture | None:
        if attempt > 0:
            return None  # a recording cannot be retried: the finding says what to record again
        path = self.files.get(step) or (self.files.get("empty") if step == "self_test" else None)
        if path is None:
            return None
        self.out(f"{step}: reading {path}")
        return Capture.load(path, open_frames=self.open_frames)

    def say(self, text: str) -> None:
        self.out(text)


class SimProvider:
    """The virtual carpet: a scripted installer acts out every step.

    ``intruder`` ("standing", "walking", "present80") disturbs the first empty capture;
    on a retry the person has stepped off.
    """

    def __init__(self, actor, intruder: str | None = None, out: Callable[[str], None] = print,
                 live_map: bool = False) -> None:
        self.actor, self.intruder, self.out, self.live_map = actor, intruder, out, live_map
        w, h = actor.size_m
        self._spots = actor.stance_spots(5)
        self._sit = (0.25 * w, 0.5 * h)

    def capture(self, step: str, attempt: int, last) -> Capture | None:
        a = self.actor
        self.out(f"== {PROMPTS[step][0]} (virtual carpet{', retry ' + str(attempt) if attempt else ''})")
        if step == "self_test":
            return a.empty(3.0)
        if step == "empty":
            if attempt and last is not None and not last.ok:
                self.out("   the person steps off the carpet")
            return a.empty(10.0, intruder=self.intruder if attempt == 0 else None)
        if step == "walk":
            cap = a.walk()
            if self.live_map:
                self._replay_map(cap)
            return cap
        if step == "board":
            return a.board()
        if step == "stance":
            return a.stance(self._spots[:4], sit_spot=self._sit)
        if step == "holdout":
            return a.stance(self._spots[4:], name="holdout")
        return None

    def _replay_map(self, cap: Capture) -> None:
        """Show the coverage map filling up (what the installer sees during the walk)."""
        from calibration.empty import robust_noise

        base = np.percentile(cap.sign * cap.frames[:20], 50, axis=0)
        noise = robust_noise(cap.sign * cap.frames[:20])
        count = np.zeros(cap.shape)
        n = cap.frames.shape[0]
        for i, fr in enumerate(cap.frames):
            count += (cap.sign * fr - base) > np.maximum(6 * noise, 30)
            if i in (n // 3, 2 * n // 3, n - 1):
                self.out(render_map(count > 0, title=f"coverage after {i / cap.rate_hz:.0f} s"))

    def say(self, text: str) -> None:
        self.out(text)


class LiveProvider:
    """A live board: prompts the installer, records each step, shows the coverage map."""

    def __init__(self, url: str, open_frames: OpenFrames, ask: Callable[[str], str] = input,
                 out: Callable[[str], None] = print, rate_hz: float = 14.0) -> None:
        """``open_frames(url)``: the board's frame source, passed in by the runtime (edge.sources.open_source)."""
        self.url, self.open_frames, self.ask, self.out, self.rate_hz = url, open_frames, ask, out, rate_hz

    def capture(self, step: str, attempt: int, last) -> Capture | None:
        title, text, seconds = PROMPTS[step]
        if attempt and last is not None:
            self.out("Retrying: " + last.findings[-1])
        self.out(f"\n== {title}\n{text}")
        self.ask("Press Enter to start (Ctrl-C stops a long capture early) ")
        frames_max = int(seconds * self.rate_hz)
        count = None
        t0 = time.monotonic()

        def on_frame(i: int, counts: np.ndarray) -> bool:
            nonlocal count
            if step == "walk":
                if count is None:
                    count = [np.zeros(counts.shape), counts.astype(float)]
                count[0] += np.abs(counts.astype(float) - count[1]) > 40
                if i % 14 == 0:
                    sys.stdout.write("\x1b[H\x1b[2J" + render_map(count[0] > 0, title=f"coverage, {i / self.rate_hz:.0f} s") + "\n")
                    sys.stdout.flush()
            elif i % 14 == 0:
                self.out(f"   {i / self.rate_hz:4.0f} s of {seconds:.0f} s")
            return True

        cap = from_source(self.url, self.open_frames, max_frames=frames_max, on_frame=on_frame)
        self.out(f"   {cap.frames.shape[0]} frames in {time.monotonic() - t0:.0f} s")
        return cap

    def say(self, text: str) -> None:
        self.out(text)
