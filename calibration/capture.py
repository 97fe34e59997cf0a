"""A capture: the frames of one calibration step, with who recorded them.

``Capture.frames`` is (N, H, W) float32 raw counts (float so that damaged frames with
NaN can be represented), ``t_s`` (N,) device time, ``device`` the INFO fields
(device_id, rows, cols, adc_bits, sign, firmware, protocol_version), ``pitch_m``,
``rate_hz`` and ``stats`` (source counters, e.g. missed frames).

Captures load from ``.npz`` files this module writes (``counts`` (N, H, W), ``t_s``, ``meta``
JSON), or are read from a carpet source: a live board, or a ``cavatar record`` file replayed
through the real decoder. calibration does not open sources itself (it sits below the runtime
in design.md's layering): whoever runs it passes in ``open_frames(url) -> FrameSource``
(``edge.sources.open_source`` is one).
:func:`frame_validity` is the garbage filter every step applies first.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Iterable, Protocol

import numpy as np

DEFAULT_PITCH_M = 0.01905
DEFAULT_RATE_HZ = 14.0


class FrameSource(Protocol):
    """What calibration reads frames from (an ``edge.sources.CarpetSource`` is one): ``start()`` opens it and
    handshakes (``info`` then holds the board's INFO fields), ``frames(timeout_s)`` yields frames with ``counts``
    (H, W) and ``t_s`` until the source ends, ``stats()`` its counters, ``stop()`` closes it."""

    info: Any

    def start(self) -> Any: ...

    def stop(self) -> Any: ...

    def frames(self, timeout_s: float) -> Iterable[Any]: ...

    def stats(self) -> dict[str, Any]: ...


OpenFrames = Callable[[str], FrameSource]  # a source URL → a FrameSource, not started


@dataclass
class Capture:
    frames: np.ndarray  # (N, H, W) float32 counts
    t_s: np.ndarray  # (N,) float64
    device: dict[str, Any]
    pitch_m: float = DEFAULT_PITCH_M
    rate_hz: float = DEFAULT_RATE_HZ
    stats: dict[str, Any] = field(default_factory=dict)

    @property
    def shape(self) -> tuple[int, int]:
        return tuple(self.frames.shape[1:])  # type: ignore[return-value]

    @property
    def full_scale(self) -> int:
        return (1 << int(self.device["adc_bits"])) - 1

    @property
    def sign(self) -> int:
        return int(self.device["sign"])

    @property
    def duration_s(self) -> float:
        return float(len(self.t_s) / self.rate_hz) if len(self.t_s) else 0.0

    def save(self, path: str | Path) -> None:
        meta = {"device": self.device, "pitch_m": self.pitch_m, "rate_hz": self.rate_hz, "stats": self.stats}
        f = self.frames
        whole = bool(np.isfinite(f).all() and f.min(initial=0) >= 0 and f.max(initial=0) <= 65535
                     and np.array_equal(f, np.round(f)))
        from cavatar_common.atomic import atomic_path  # whole or not at all: a resumed session reads it back

        with atomic_path(path) as tmp:
            np.savez(tmp, counts=f.astype(np.uint16 if whole else np.float32), t_s=self.t_s, meta=np.array(json.dumps(meta)))

    @classmethod
    def load(cls, path: str | Path, pitch_m: float | None = None, open_frames: OpenFrames | None = None) -> "Capture":
        """A ``.npz`` capture, or a ``cavatar record`` byte stream (replayed as fast as possible through
        ``open_frames``, which the caller passes in)."""
        path = Path(path)
        if not path.exists():
            raise FileNotFoundError(f"no capture {path}")
        if path.suffix == ".npz":
            with np.load(path, allow_pickle=False) as z:
                meta = json.loads(str(z["meta"]))
                cap = cls(z["counts"].astype(np.float32), z["t_s"].astype(np.float64), meta["device"],
                          meta.get("pitch_m", DEFAULT_PITCH_M), meta.get("rate_hz", DEFAULT_RATE_HZ), meta.get("stats", {}))
        elif open_frames is None:
            raise ValueError(f"{path} is a `cavatar record` stream: reading it needs the runtime's decoder; pass "
                             "open_frames (edge.sources.open_source), as `cavatar calibrate` does")
        else:
            cap = from_source(f"replay://{path.resolve()}?speed=0", open_frames)
        if pitch_m:
            cap.pitch_m = pitch_m
        return cap


def device_of(info: Any) -> dict[str, Any]:
    """The calibration file's device record from an INFO packet."""
    return {"device_id": info.device_id, "rows": int(info.rows), "cols": int(info.cols), "adc_bits": int(info.adc_bits),
            "sign": int(info.sign), "firmware": [int(info.fw_major), int(info.fw_minor), int(info.fw_patch)],
            "protocol_version": int(getattr(info, "protocol_version", 0))}


def from_source(url: str, open_frames: OpenFrames, max_frames: int | None = None, on_frame=None) -> Capture:
    """Read frames from the source ``open_frames(url)`` until it ends, ``max_frames`` arrived or Ctrl-C.
    ``on_frame(i, counts)`` is called per frame (live progress); False stops.
    """
    source = open_frames(url)
    source.start()
    frames, times = [], []
    try:
        try:
            for i, fr in enumerate(source.frames(timeout_s=5.0)):
                frames.append(fr.counts.astype(np.float32))
                times.append(fr.t_s)
                if on_frame is not None and on_frame(i, fr.counts) is False:
                    break
                if max_frames is not None and len(frames) >= max_frames:
                    break
        except KeyboardInterrupt:  # Ctrl-C ends a live capture early; what arrived is kept
            pass
        stats = source.stats()
        info = source.info
    finally:
        source.stop()
    rate = float(getattr(info, "rate_mhz", 0) or 0) / 1000.0 or DEFAULT_RATE_HZ
    shape = (int(info.rows), int(info.cols))
    arr = np.stack(frames) if frames else np.zeros((0, *shape), np.float32)
    return Capture(arr, np.asarray(times, float), device_of(info), DEFAULT_PITCH_M, rate,
                   {"frames": stats.get("frames", {}), "decoder": stats.get("decoder", {})})


def frame_validity(frames: np.ndarray, full_scale: int) -> tuple[np.ndarray, dict[str, int]]:
    """(N,) bool of usable frames and the count of each reason for refusing one.

    Refused: non-finite values (NaN/∞), codes above full scale or below 0, a constant
    frame (every sensel the same code), an exact duplicate of the previous frame.
    """
    n = frames.shape[0]
    flat = frames.reshape(n, -1)
    finite = np.isfinite(flat).all(axis=1)
    hi = np.max(np.where(np.isfinite(flat), flat, -np.inf), axis=1)
    lo = np.min(np.where(np.isfinite(flat), flat, np.inf), axis=1)
    in_range = (hi <= full_scale) & (lo >= 0)
    constant = hi == lo
    dup = np.zeros(n, bool)
    if n > 1:
        dup[1:] = (flat[1:] == flat[:-1]).all(axis=1)
    ok = finite & in_range & ~constant & ~dup
    reasons = {"non_finite": int((~finite).sum()), "out_of_range": int((finite & ~in_range).sum()),
               "constant": int((finite & in_range & constant).sum()), "duplicate": int((dup & finite).sum())}
    return ok, {k: v for k, v in reasons.items() if v}


def sensel_xy_m(r: float, c: float, pitch_m: float) -> tuple[float, float]:
    """Carpet-frame position (x along columns, y along rows) of sensel (r, c)'s centre."""
    return ((c + 0.5) * pitch_m, (r + 0.5) * pitch_m)
