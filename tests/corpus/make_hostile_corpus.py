"""Writes the hostile corpus: byte streams an attacker or bad luck would send (wire/*.bin, each with valid
COBS framing and packet CRCs) and damaged calibration files (calibration/*.npz). The expected outcome of
each is in tests/corpus/hostile/expected.json; test_hostile_corpus.py replays the committed files.

    .venv/bin/python tests/corpus/make_hostile_corpus.py     # rewrite the files (deterministic)

Board A is ``carpet-A`` (8×6, 12-bit, sign -1); its frames read 1000..1099. Every other board's frames
read 3000, so a test can tell whose frames came through.
"""

from __future__ import annotations

import json
import zlib
from pathlib import Path

import numpy as np

from firmware_protocol import codec

ROOT = Path(__file__).parent / "hostile"
HERE = ROOT / "wire"
ROWS, COLS = 8, 6
PACKED12 = codec.PACKING["packed12"]


def info(device_id: str = "carpet-A", rows: int = ROWS, cols: int = COLS, bits: int = 12, sign: int = -1,
         packing: int = PACKED12) -> object:
    return codec.Info(0, codec.PROTOCOL_VERSION, codec.DEFINITION_HASH, 1, 2, 3, device_id, rows, cols, 1, 1, bits,
                      packing, sign, 14000, 0)


class Stream:
    """Packets with a running packet seq, frame seq and device time."""

    def __init__(self) -> None:
        self.packets: list = []
        self.seq = 0
        self.frame_seq = 0
        self.t_us = 0

    def add(self, pkt) -> None:
        fields = {f: getattr(pkt, f) for f in pkt.__dataclass_fields__}
        fields["seq"] = self.seq & 0xFFFF
        self.packets.append(type(pkt)(**fields))
        self.seq += 1

    def frame(self, value: int, rows: int = ROWS, cols: int = COLS, end: bool = True, crc_delta: int = 0,
              only_rows=None, frame_seq: int | None = None) -> None:
        counts = np.full((rows, cols), value, np.uint16)
        fs = self.frame_seq if frame_seq is None else frame_seq
        for r in range(rows) if only_rows is None else only_rows:
            self.add(codec.make_row(0, fs, self.t_us + 500 * r, r, counts[r].tolist(), PACKED12))
        if end:
            crc = (zlib.crc32(counts.astype("<u2").tobytes()) + crc_delta) & 0xFFFFFFFF
            self.add(codec.FrameEnd(0, fs, self.t_us + 500 * (rows - 1), rows, 500 * (rows - 1), crc))
        if frame_seq is None:
            self.frame_seq += 1
        self.t_us += 71_428

    def frames(self, n: int, base: int = 1000, **kw) -> None:
        for k in range(n):
            self.frame(base + k if base == 1000 else base, **kw)

    def bytes(self) -> bytes:
        return b"".join(codec.encode(p) for p in self.packets)


def swap(other) -> Stream:
    s = Stream()
    s.add(info())
    s.frames(3)
    s.add(other)
    s.frames(3, base=3000, rows=other.rows, cols=other.cols)
    return s


def build() -> dict[str, bytes]:
    out: dict[str, Stream] = {}
    # finding 1: another board answers mid-stream (or after a replug): its frames never come through
    out["board_swap_device_id"] = swap(info(device_id="carpet-B"))
    out["board_swap_adc_bits"] = swap(info(bits=10))
    out["board_swap_sign"] = swap(info(sign=1))
    out["board_swap_grid"] = swap(info(rows=6, cols=6))
    back = swap(info(device_id="carpet-B"))
    back.add(info())
    back.frames(2)
    out["board_swap_and_back"] = back
    # INFO out of range: refused at the handshake, never sizes a buffer
    for name, bad in (("info_huge_grid", info(rows=65535, cols=65535)), ("info_3_bits", info(bits=3)),
                      ("info_bits_beyond_packing", info(bits=16)), ("info_sign_zero", info(sign=0))):
        s = Stream()
        s.add(bad)
        s.frames(2)
        out[name] = s
    # a mid-stream INFO out of range: ignored (counted), board A's frames go on
    s = Stream()
    s.add(info())
    s.frames(2)
    s.add(info(rows=4000, cols=4000))
    s.frames(2)
    out["info_out_of_range_mid_stream"] = s
    # finding 9: frames without FRAME_END, or with a wrong CRC-32, are never emitted
    s = Stream()
    s.add(info())
    s.frames(3, end=False)
    out["frames_without_frame_end"] = s
    s = Stream()
    s.add(info())
    s.frame(1000, crc_delta=1)
    s.frame(1001)
    out["frame_crc_wrong"] = s
    # rows of two frames mixed under one frame number, no FRAME_END, then a whole frame 1
    s = Stream()
    s.add(info())
    s.frame(1000, end=False, only_rows=range(4), frame_seq=0)
    s.frame(3000, end=False, only_rows=range(4, ROWS), frame_seq=0)
    s.frame_seq = 1
    s.frame(1001)
    out["rows_of_two_frames_mixed"] = s
    return {name: stream.bytes() for name, stream in out.items()}


def valid_calibration() -> bytes:
    """A valid calibration of board A (8×6), byte for byte the same every time."""
    import tempfile

    from calibration.file import Calibration

    cal = Calibration(np.full((ROWS, COLS), 2000.0, np.float32), np.full((ROWS, COLS), 3.0, np.float32),
                      np.ones((ROWS, COLS), np.float32), np.zeros((ROWS, COLS), np.uint8),
                      device={"device_id": "carpet-A", "rows": ROWS, "cols": COLS, "adc_bits": 12, "sign": -1},
                      pitch_m=0.01905, created="2026-01-01T00:00:00+00:00")
    with tempfile.TemporaryDirectory() as tmp:
        cal.save(Path(tmp) / "c.npz")
        return (Path(tmp) / "c.npz").read_bytes()


def _npz(members: dict[str, bytes]) -> bytes:
    import io
    import zipfile

    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w", zipfile.ZIP_DEFLATED) as zf:
        for name, data in members.items():
            zf.writestr(zipfile.ZipInfo(name, date_time=(1980, 1, 1, 0, 0, 0)), data, zipfile.ZIP_DEFLATED)
    return buf.getvalue()


def _members(npz: bytes) -> dict[str, bytes]:
    import io
    import zipfile

    with zipfile.ZipFile(io.BytesIO(npz)) as zf:
        return {i.filename: zf.read(i) for i in zf.infolist()}


def _npy(array: np.ndarray) -> bytes:
    import io

    buf = io.BytesIO()
    np.lib.format.write_array(buf, array, allow_pickle=True)
    return buf.getvalue()


def build_calibrations() -> dict[str, bytes]:
    """Finding 8: every damage is one clear line, nothing inflated before it is checked."""
    good = valid_calibration()
    out = {"empty": b"", "truncated": good[: len(good) // 2]}
    flipped = bytearray(good)
    flipped[len(good) // 3] ^= 0x10
    out["bit_flipped"] = bytes(flipped)
    members = _members(good)
    bomb = dict(members)
    bomb["gain.npy"] = _npy(np.zeros(8 << 20))  # 64 MB of zeros in ~64 KB
    out["bomb"] = _npz(bomb)
    pickled = dict(members)
    pickled["meta.npy"] = _npy(np.array([{"schema": "x"}], dtype=object))
    out["pickled_meta"] = _npz(pickled)
    huge = dict(members)
    huge["meta.npy"] = _npy(np.array(json.dumps({"schema": "cavatar.calibration/1",
                                                  "device": {"rows": 100000, "cols": 100000}})))
    out["huge_grid"] = _npz(huge)
    extra = dict(members)
    extra["payload.npy"] = _npy(np.zeros(4))
    out["extra_member"] = _npz(extra)
    out["not_a_zip"] = b"PK\x03\x04" + bytes(200)
    return out


def main() -> None:
    HERE.mkdir(parents=True, exist_ok=True)
    for name, data in build().items():
        (HERE / f"{name}.bin").write_bytes(data)
        print(f"wire/{name}.bin: {len(data)} bytes")
    (ROOT / "calibration").mkdir(parents=True, exist_ok=True)
    for name, data in build_calibrations().items():
        (ROOT / "calibration" / f"{name}.npz").write_bytes(data)
        print(f"calibration/{name}.npz: {len(data)} bytes")


if __name__ == "__main__":
    main()
