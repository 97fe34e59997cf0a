"""The faults a virtual board has been asked to inject, waiting for the bytes or frames they hit.

Link faults (``drop``, ``flip``, ``garbage``) hit the next bytes out, in the order they
were asked for; frame faults (``tear``, ``skip``, ``duplicate``) hit the next frames
scanned. One seeded random generator shapes them all, so a run is repeatable given the
seed. ``injected`` counts what was actually applied (the board adds its own: stalls,
unplugs, torn rows, duplicated frames, bytes lost unplugged).
"""

from __future__ import annotations

import random
from collections import Counter, deque
from typing import Iterable

_RNG_SALT = 0x5EED_F417  # keeps the fault generator apart from the frame generator of the same seed


class PendingFaults:
    """Faults queued for the next bytes and frames out, and the count of those applied."""

    def __init__(self, seed: int) -> None:
        self._link_ops: deque = deque()  # ("garbage", bytes) | ("drop", n) | ("flip", n)
        self._rng = random.Random(seed ^ _RNG_SALT)
        self._tear_rows: list[list[int] | None] = []  # per frame to tear: its lost rows, None for a seeded choice
        self._duplicate_frames = 0
        self._skip_frames = 0
        self.injected: Counter = Counter()

    # ------------------------------------------------------------------ link: the next bytes out

    @property
    def link_ops_waiting(self) -> bool:
        """Whether a link fault waits for bytes (garbage comes out even with nothing else to send)."""
        return bool(self._link_ops)

    def drop_bytes(self, n: int) -> None:
        """Lose the next ``n`` bytes out."""
        if n > 0:
            self._link_ops.append(("drop", int(n)))

    def flip_bits(self, n: int) -> None:
        """Flip one (seeded random) bit in each of the next ``n`` bytes out."""
        if n > 0:
            self._link_ops.append(("flip", int(n)))

    def garbage(self, n: int, zeros: bool = True) -> bytes:
        """Insert ``n`` seeded random bytes before the next bytes out (``zeros=False``: no 0x00). Returns them."""
        junk = bytearray(self._rng.randbytes(n))
        if not zeros:
            junk = bytearray(b or 1 + self._rng.randrange(255) for b in junk)
        if n > 0:
            self._link_ops.append(("garbage", bytes(junk)))
        return bytes(junk)

    def apply_to_link(self, data: bytes) -> bytes:
        """``data`` as the host receives it: the waiting link faults applied, in order, as far as it reaches."""
        out = bytearray()
        pos = 0
        ops = self._link_ops
        while ops:
            kind, arg = ops[0]
            if kind == "garbage":
                out += arg
                self.injected["garbage_bytes"] += len(arg)
                ops.popleft()
                continue
            if pos >= len(data):
                break
            k = min(arg, len(data) - pos)
            if kind == "drop":
                self.injected["dropped_bytes"] += k
            else:
                for b in data[pos : pos + k]:
                    out.append(b ^ (1 << self._rng.randrange(8)))
                self.injected["flipped_bits"] += k
            pos += k
            if k < arg:
                ops[0] = (kind, arg - k)
                break
            ops.popleft()
        out += data[pos:]
        return bytes(out)

    # ------------------------------------------------------------------ frames: the next frames scanned

    def tear_next_frame(self, missing_rows: Iterable[int] | None = None) -> None:
        """Lose some rows of the next frame sent (default: a seeded choice of max(1, rows//8) rows)."""
        self._tear_rows.append(None if missing_rows is None else list(missing_rows))

    def skip_frames(self, k: int) -> None:
        """Scan the next ``k`` frames without sending them."""
        self._skip_frames += max(0, int(k))

    def duplicate_next_frame(self) -> None:
        """Send the next frame twice."""
        self._duplicate_frames += 1

    def take_skip(self) -> bool:
        """Whether the frame being scanned is to be skipped (counted as applied)."""
        if self._skip_frames <= 0:
            return False
        self._skip_frames -= 1
        self.injected["skipped_frames"] += 1
        return True

    def take_tear(self, rows: int) -> frozenset:
        """The rows (of ``rows``) to lose from the frame being sent; empty when it is not to be torn."""
        if not self._tear_rows:
            return frozenset()
        chosen = self._tear_rows.pop(0)
        if chosen is None:
            k = max(1, rows // 8)
            chosen = self._rng.sample(range(rows), min(k, rows))
        self.injected["torn_frames"] += 1
        return frozenset(r for r in chosen if 0 <= r < rows)

    def take_duplicate(self) -> bool:
        """Whether the frame being sent is to be sent twice."""
        if self._duplicate_frames <= 0:
            return False
        self._duplicate_frames -= 1
        return True
