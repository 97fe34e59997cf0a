"""Shared helpers of the virtual board tests: small boards, commands, frames read back from packets."""

from __future__ import annotations

import numpy as np

from firmware_protocol import codec
from firmware_protocol.virtual_board import VirtualBoard

ROWS, COLS = 8, 6


def ramp_frames(rows=ROWS, cols=COLS, bits=12):
    """A frame source whose every sample says where it came from."""
    full = (1 << bits) - 1

    def frames(k):
        return [[(k * 131 + r * 17 + c * 5) % (full + 1) for c in range(cols)] for r in range(rows)]

    return frames


def small_board(**kw):
    kw.setdefault("frames", ramp_frames(kw.get("rows", ROWS), kw.get("cols", COLS), kw.get("adc_bits", 12)))
    kw.setdefault("rows", ROWS)
    kw.setdefault("cols", COLS)
    return VirtualBoard(**kw)


def cmd(name, seq=1, **fields):
    return codec.encode_command(name, seq, **fields)


def started(board, t=0.0):
    """Board streaming from ``t``, with a host decoder that has seen INFO and the ACK."""
    dec = codec.StreamDecoder()
    dec.feed(board.read(t))
    board.receive(cmd("START", 1), now_s=t)
    return dec


def frames_of(packets):
    """frame_seq → (rows dict, FrameEnd or None), in order of arrival."""
    out = {}
    for p in packets:
        if isinstance(p, codec.Row):
            rows, _ = out.setdefault(p.frame_seq, ({}, None))
            rows[p.row] = codec.unpack_samples(p.samples, p.packing, p.count)
        elif isinstance(p, codec.FrameEnd):
            rows, _ = out.setdefault(p.frame_seq, ({}, None))
            out[p.frame_seq] = (rows, p)
    return out


def crc_of(rows_dict):
    return codec.frame_crc32(np.asarray(rows_dict[r], dtype="<u2").tobytes() for r in sorted(rows_dict))


def check_frames_true(frames, source, frame_seq_start=0, complete=True):
    """Every received sample equals what the source made (no false accepts)."""
    for fseq, (rows, end) in frames.items():
        want = source((fseq - frame_seq_start) & 0xFFFFFFFF)
        for r, vals in rows.items():
            assert vals == want[r], f"frame {fseq} row {r} differs"
        if complete and end is not None and len(rows) == end.rows:
            assert crc_of(rows) == end.frame_crc32


# ---------------------------------------------------------------- INFO and commands
