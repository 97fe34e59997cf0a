"""The virtual board on a pseudo-terminal, read through real pyserial."""

from __future__ import annotations

import os
import threading
import time

import pytest
import serial

from firmware_protocol import codec
from firmware_protocol.pty_board import PtyBoard
from firmware_protocol.virtual_board import VirtualBoard

pytestmark = pytest.mark.timeout(30)


def cmd(name, seq=1, **fields):
    return codec.encode_command(name, seq, **fields)


def read_for(port, seconds, dec):
    out = []
    deadline = time.monotonic() + seconds
    while time.monotonic() < deadline:
        out += dec.feed(port.read(max(1, port.in_waiting)))
    return out


def complete_frames(pkts):
    rows, done = {}, []
    for p in pkts:
        if isinstance(p, codec.Row):
            rows.setdefault(p.frame_seq, set()).add(p.row)
        elif isinstance(p, codec.FrameEnd) and len(rows.get(p.frame_seq, ())) == p.rows:
            done.append(p.frame_seq)
    return done


def test_info_and_default_size_frames_arrive_through_pyserial():
    """The issue's check: 96×96, 12-bit, 14 Hz over a pty; complete frames arrive."""
    with PtyBoard(VirtualBoard(rows=96, cols=96, adc_bits=12, packing="packed12")) as pty:
        assert os.path.islink(pty.port) and os.readlink(pty.port).startswith("/dev/pts/")
        port = serial.Serial(pty.port, baudrate=2_000_000, timeout=0.05)
        try:
            port.write(cmd("GET_INFO", 0) + cmd("START", 1))
            dec = codec.StreamDecoder()
            pkts, t0 = [], time.monotonic()
            while len(complete_frames(pkts)) < 10 and time.monotonic() - t0 < 6.0:
                pkts += read_for(port, 0.05, dec)
            elapsed = time.monotonic() - t0
        finally:
            port.close()
    info = [p for p in pkts if isinstance(p, codec.Info)][-1]
    assert (info.rows, info.cols, info.adc_bits, info.rate_mhz) == (96, 96, 12, 14000)
    frames = complete_frames(pkts)
    assert len(frames) >= 10
    assert frames == list(range(frames[0], frames[0] + len(frames)))
    assert elapsed >= (len(frames) - 1) / 14  # paced in real time, not faster
    ends = {p.frame_seq: p.t_us for p in pkts if isinstance(p, codec.FrameEnd)}
    assert {ends[b] - ends[a] for a, b in zip(frames, frames[1:])} <= {71428, 71429}  # 14 Hz on the device clock
    assert dec.stats.missed == 0 and not dec.stats.dropped
    assert not os.path.lexists(pty.port)  # stop() removed the symlink
    assert pty.error is None


def test_unplug_fails_reads_and_removes_the_link_then_replug_streams_again():
    with PtyBoard(VirtualBoard(rows=32, cols=32)) as pty:
        port = serial.Serial(pty.port, timeout=0.05)
        port.write(cmd("START", 1))
        assert complete_frames(read_for(port, 0.3, codec.StreamDecoder()))
        first_pts = os.readlink(pty.port)

        pty.unplug()
        assert not os.path.lexists(pty.port) and not pty.connected
        with pytest.raises(serial.SerialException):
            for _ in range(1000):  # a pulled adapter: the read fails (it never just hangs)
                port.read(100)
        port.close()
        with pytest.raises(serial.SerialException):
            serial.Serial(pty.port)  # nothing behind the name while unplugged

        t0 = time.monotonic()
        pty.replug()
        assert os.path.islink(pty.port) and os.path.exists(os.readlink(pty.port))
        port = serial.Serial(pty.port, timeout=0.05)  # same name, maybe another /dev/pts/N than first_pts
        try:
            port.write(cmd("GET_INFO", 0) + cmd("START", 1))
            dec = codec.StreamDecoder()
            pkts = []
            while not complete_frames(pkts) and time.monotonic() - t0 < 2.0:
                pkts += read_for(port, 0.05, dec)
        finally:
            port.close()
        assert complete_frames(pkts), "frames must flow again within 2 s of the replug"
        assert any(isinstance(p, codec.Info) for p in pkts)
        assert pty.board.injected["unplugs"] == 1 and first_pts


def test_the_boards_own_unplug_flag_is_obeyed():
    with PtyBoard(VirtualBoard(rows=8, cols=8)) as pty:
        pty.board.unplug()
        deadline = time.monotonic() + 2
        while pty.connected and time.monotonic() < deadline:
            time.sleep(0.01)
        assert not pty.connected and not os.path.lexists(pty.port)
        pty.board.replug()
        while not pty.connected and time.monotonic() < deadline:
            time.sleep(0.01)
        assert pty.connected and os.path.islink(pty.port)


def test_faults_reach_the_host():
    with PtyBoard(VirtualBoard(rows=16, cols=16)) as pty:
        port = serial.Serial(pty.port, timeout=0.05)
        try:
            port.write(cmd("START", 1))
            dec = codec.StreamDecoder()
            pkts = read_for(port, 0.2, dec)
            pty.board.garbage(50, zeros=False)
            pty.board.skip_frames(2)
            after, deadline = [], time.monotonic() + 5.0  # a loaded machine may lag: wait for frames, not a fixed time
            while sum(isinstance(p, codec.FrameEnd) for p in after) < 3 and time.monotonic() < deadline:
                after += read_for(port, 0.05, dec)
            pkts += after
        finally:
            port.close()
    assert sum(dec.stats.dropped.values()) >= 1 and pty.board.injected["garbage_bytes"] == 50
    seen = {p.frame_seq for p in pkts if isinstance(p, (codec.Row, codec.FrameEnd))}
    assert len(set(range(min(seen), max(seen) + 1)) - seen) == 2  # the skipped frames


def test_a_custom_link_path_and_clean_shutdown(tmp_path):
    fds = len(os.listdir("/proc/self/fd"))
    threads = threading.active_count()
    link = str(tmp_path / "ttyCarpet")
    pty = PtyBoard(VirtualBoard(rows=8, cols=8), link_path=link)
    pty.start()
    assert pty.port == link and os.path.islink(link)
    pty.unplug()
    pty.replug()
    pty.stop()
    pty.stop()  # twice is harmless
    assert not os.path.lexists(link)
    assert threading.active_count() == threads
    assert len(os.listdir("/proc/self/fd")) == fds
