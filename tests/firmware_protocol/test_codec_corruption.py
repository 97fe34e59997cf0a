"""Seeded corruption of a long device stream: the decoder's promises, checked exactly.

About 100,000 packets (mostly 96-sample packed12 ROWs, with u8/u16/odd-count/long ROWs,
FRAME_END, STATUS, INFO, ACK and NAK mixed in) are encoded back to back; the byte stream
is then damaged with bit flips (some aimed at delimiters), garbage bursts (some rich in
0x00, a few longer than any legal packet) and dropped chunks, and fed to one
StreamDecoder in random read sizes. A packet counts as *undamaged* when none of its
bytes, its own delimiter or the delimiter before it was touched and nothing was inserted
between the two. Checked:

- no exception;
- every undamaged packet is decoded, equal to what was sent;
- zero false accepts: every decoded packet equals a sent one, in sending order;
- the counters add up exactly: accepted + dropped = non-empty chunks between delimiters,
  ``too_long`` = over-long chunks, ``missed`` = the seq gaps between accepted packets.
"""

from __future__ import annotations

import time
from collections import Counter

import numpy as np

from firmware_protocol import codec

SEED = 20240611
N_PACKETS = 100_000
P = codec.PACKING


def _sample_pool(rng: np.random.Generator, n: int, count: int, packing: int) -> list[bytes]:
    """``n`` distinct sample payloads near mid-scale with noise, packed by the codec."""
    full = {P["u8"]: 255, P["packed12"]: 4095, P["u16"]: 4095}[packing]  # u16 carries a 12-bit ADC
    vals = np.clip(rng.normal(full / 2, full / 50, size=(n, count)).round(), 0, full).astype(int)
    vals[:, :: max(1, count // 7)] = rng.integers(0, full + 1, size=vals[:, :: max(1, count // 7)].shape)
    return [codec.pack_samples(v.tolist(), packing) for v in vals]


def make_packets(rng: np.random.Generator, n: int) -> list:
    """A device stream of ``n`` packets: frames of ROWs + FRAME_END, with the other types mixed in."""
    pools = {
        ("packed12", 96): _sample_pool(rng, 600, 96, P["packed12"]),
        ("u8", 96): _sample_pool(rng, 200, 96, P["u8"]),
        ("u16", 96): _sample_pool(rng, 200, 96, P["u16"]),
        ("packed12", 33): _sample_pool(rng, 50, 33, P["packed12"]),  # odd count: padded nibble
        ("u16", 1000): _sample_pool(rng, 8, 1000, P["u16"]),  # > 254 bytes: several COBS blocks
        ("u16", 2039): _sample_pool(rng, 4, 2039, P["u16"]),  # exactly max_packet_bytes
    }
    kinds = [("packed12", 96)] * 14 + [("u8", 96)] * 3 + [("u16", 96)] * 2 + [("packed12", 33)]
    out: list = []
    seq = frame = 0
    t_us = 4_294_000_000  # wraps during the run
    while len(out) < n:
        kind = kinds[int(rng.integers(len(kinds)))]
        rows = 96 if kind[1] == 96 else 8
        if frame % 97 == 0:
            kind, rows = (("u16", 1000), 3) if frame % 2 else (("u16", 2039), 2)
        pool = pools[kind]
        t0 = t_us
        for r in range(rows):
            samples = pool[int(rng.integers(len(pool)))]
            out.append(codec.Row(seq & 0xFFFF, frame, t_us, r, kind[1], P[kind[0]], samples))
            seq += 1
            t_us = (t_us + 740) & 0xFFFFFFFF
        out.append(codec.FrameEnd(seq & 0xFFFF, frame, t_us, rows, (t_us - t0) & 0xFFFFFFFF, int(rng.integers(2**32))))
        seq += 1
        if frame % 14 == 0:
            out.append(codec.Status(seq & 0xFFFF, t_us, frame // 14, frame, 0, 0, 0, 0, 0, int(rng.integers(-32768, 32768)), 65535))
            seq += 1
        if frame % 50 == 0:
            out.append(codec.Info(seq & 0xFFFF, codec.PROTOCOL_VERSION, codec.DEFINITION_HASH, 1, 2, 3, f"carpet-{frame}",
                                  96, 96, 1, 1, 12, 1, -1, 14000, 3))
            seq += 1
        if frame % 20 == 7:
            ack = codec.Ack(seq & 0xFFFF, 0x86, frame & 0xFFFF, int(rng.integers(2**32)))
            nak = codec.Nak(seq & 0xFFFF, 0x85, frame & 0xFFFF, 5)
            out.append(ack if frame % 40 == 7 else nak)
            seq += 1
        frame += 1
    return out[:n]


def corrupt(rng: np.random.Generator, wire: bytes, n_events: int, n_long: int = 3) -> tuple[bytes, np.ndarray, np.ndarray]:
    """Damage ``wire``. Returns (damaged stream, per-byte "touched" mask, per-position "inserted before" mask)."""
    n = len(wire)
    xor = np.zeros(n, np.uint8)
    keep = np.ones(n, bool)
    inserted_before = np.zeros(n + 1, bool)
    inserts: dict[int, bytes] = {}
    delims = np.flatnonzero(np.frombuffer(wire, np.uint8) == 0)
    events = list(rng.choice(["flip", "flip_delim", "garbage", "garbage0", "drop"], size=n_events, p=[0.34, 0.08, 0.22, 0.08, 0.28]))
    for kind in events + ["long"] * n_long:
        if kind == "flip":  # 1–3 flipped bits within a few bytes
            p = int(rng.integers(n))
            for _ in range(int(rng.integers(1, 4))):
                q = min(n - 1, p + int(rng.integers(0, 4)))
                xor[q] ^= np.uint8(1 << int(rng.integers(8)))
        elif kind == "flip_delim":  # a delimiter turned into data: two packets merge
            xor[delims[int(rng.integers(len(delims)))]] ^= np.uint8(1 << int(rng.integers(8)))
        elif kind in ("garbage", "garbage0", "long"):
            p = int(rng.integers(n + 1))
            if kind == "garbage":  # random bytes (an occasional 0x00 among them)
                burst = rng.integers(0, 256, size=int(rng.integers(1, 200)), dtype=np.uint8)
            elif kind == "garbage0":  # zero-rich: many short chunks, some of them empty
                burst = rng.choice(np.array([0, 0, 0, 1, 2, 0x55, 0xFF], np.uint8), size=int(rng.integers(1, 40)))
            else:  # a stretch longer than any legal packet, with no delimiter at all
                burst = rng.integers(1, 256, size=int(rng.integers(5000, 20000)), dtype=np.uint8)
            inserts[p] = inserts.get(p, b"") + burst.tobytes()
            inserted_before[p] = True
        else:  # a chunk lost by the UART/USB stack
            p = int(rng.integers(n))
            keep[p : p + int(rng.integers(1, 300))] = False
    data = np.frombuffer(wire, np.uint8) ^ xor
    parts, prev = [], 0
    for p in sorted(inserts):
        parts.append(data[prev:p][keep[prev:p]].tobytes())
        parts.append(inserts[p])
        prev = p
    parts.append(data[prev:][keep[prev:]].tobytes())
    touched = (xor != 0) | ~keep
    return b"".join(parts), touched, inserted_before


def undamaged(lengths: np.ndarray, touched: np.ndarray, inserted_before: np.ndarray) -> np.ndarray:
    """Per packet: none of its bytes, its delimiter or the one before touched; nothing inserted inside."""
    ends = np.cumsum(lengths)  # one past each packet's delimiter
    starts = ends - lengths
    t = np.concatenate([[0], np.cumsum(touched)])
    i = np.concatenate([[0], np.cumsum(inserted_before)])
    hit = t[ends] - t[np.maximum(starts - 1, 0)]  # bytes starts-1 (the previous delimiter) … ends-1
    ins = i[ends] - i[starts]  # insertions before bytes starts … ends-1 (before our own delimiter)
    return (hit == 0) & (ins == 0)


def random_reads(rng: np.random.Generator, data: bytes):
    """Yield ``data`` in read sizes from 1 byte to 8 KB, as a serial or USB stack would."""
    i = 0
    while i < len(data):
        r = rng.random()
        size = int(rng.integers(1, 17)) if r < 0.25 else int(rng.integers(17, 513)) if r < 0.7 else int(rng.integers(513, 8193))
        yield data[i : i + size]
        i += size


def test_corrupted_stream_keeps_every_undamaged_packet_and_accepts_nothing_false():
    t0 = time.perf_counter()
    rng = np.random.default_rng(SEED)
    sent = make_packets(rng, N_PACKETS)
    encoded = [codec.encode(p) for p in sent]
    wire = b"".join(encoded)
    index = {p: i for i, p in enumerate(sent)}
    assert len(index) == len(sent), "test packets must be distinct"

    damaged_stream, touched, inserted_before = corrupt(rng, wire, n_events=6000)
    clean = undamaged(np.array([len(e) for e in encoded]), touched, inserted_before)
    stream = damaged_stream + b"\x00"  # flush: ends whatever chunk the damage left open

    dec = codec.StreamDecoder()
    got = []
    for chunk in random_reads(rng, stream):
        got += dec.feed(chunk)
    st = dec.stats

    # zero false accepts, in order
    idx = [index.get(p, -1) for p in got]
    false = [p for p, i in zip(got, idx) if i < 0]
    assert not false, f"{len(false)} false accepts, first: {false[0]!r}"
    assert all(a < b for a, b in zip(idx, idx[1:])), "packets came out of order or twice"

    # every undamaged packet recovered
    recovered = np.zeros(len(sent), bool)
    recovered[idx] = True
    lost = np.flatnonzero(clean & ~recovered)
    assert lost.size == 0, f"{lost.size} undamaged packets lost, first at index {lost[0]}: {sent[lost[0]]!r}"

    # the counters add up
    chunks = [c for c in stream.split(b"\x00")[:-1] if c]
    over_long = sum(len(c) > dec._max_encoded for c in chunks)
    assert st.bytes_in == len(stream)
    assert st.packets == len(got)
    assert st.packets + sum(st.dropped.values()) == len(chunks)
    assert st.dropped["too_long"] == over_long
    assert st.missed == idx[-1] - idx[0] + 1 - len(idx)  # seq gaps < 32768 here, wrap included
    assert st.repeated == 0
    assert st.by_type == Counter(type(p).NAME for p in got)
    past_crc = st.dropped["unknown_type"] + st.dropped["bad_length"] + st.dropped["insane"]
    assert past_crc <= 3, f"{past_crc} damaged chunks passed the CRC: {dict(st.dropped)}"
    assert 0 < st.dropped_bytes < st.bytes_in

    # the test itself exercised what it claims to
    damaged = int((~clean).sum())
    assert len(sent) >= 100_000
    assert 0.03 * len(sent) < damaged < 0.2 * len(sent), damaged
    assert st.dropped["bad_crc"] > 1000 and st.dropped["bad_cobs"] > 100 and st.dropped["too_short"] > 100
    assert over_long >= 3
    assert np.count_nonzero(recovered & ~clean) > 0  # some "damaged" packets survived (e.g. a burst ending in 0x00)
    elapsed = time.perf_counter() - t0
    print(
        f"\n{len(sent)} packets, {len(stream)} bytes, {damaged} damaged, {int(recovered.sum())} decoded, "
        f"dropped {dict(st.dropped)}, missed {st.missed}, {elapsed:.1f} s"
    )
