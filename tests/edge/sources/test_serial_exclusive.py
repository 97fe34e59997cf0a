"""Two readers on one serial port corrupt each other's frames (issue 17, finding 3): the serial source takes the port
exclusively, and the second reader is refused with one line that names the holder."""

import os
import subprocess
import sys

import pytest

from edge.sources import SourceError, open_source
from firmware_protocol.pty_board import PtyBoard
from firmware_protocol.virtual_board import VirtualBoard

HOLD = "import serial, sys, time; s = serial.Serial(sys.argv[1], exclusive=True); print('held', flush=True); time.sleep(60)"


def test_a_second_reader_in_another_process_is_refused_naming_the_holder():
    with PtyBoard(VirtualBoard(rows=32, cols=32)) as pty:
        holder = subprocess.Popen([sys.executable, "-c", HOLD, pty.port], stdout=subprocess.PIPE, text=True)
        try:
            assert holder.stdout.readline().strip() == "held"
            with pytest.raises(SourceError) as refused:
                open_source(f"serial://{pty.port}").start()
        finally:
            holder.kill()
            holder.wait()
    text = str(refused.value)
    assert "\n" not in text and f"serial port {pty.port} is in use by another program" in text
    assert f"held by pid {holder.pid} (" in text and "serial.Serial" in text  # the holder and its command line
    assert "sudo systemctl stop cavatar" in text


def test_a_second_source_on_a_streaming_port_is_refused_and_the_first_keeps_its_frames():
    with PtyBoard(VirtualBoard(rows=32, cols=32)) as pty, open_source(f"serial://{pty.port}") as first:
        next(first.frames(timeout_s=5))
        with pytest.raises(SourceError, match=f"in use by another program \\(held by this process, pid {os.getpid()}"):
            open_source(f"serial://{pty.port}").start()
        got = [f for _, f in zip(range(5), first.frames(timeout_s=5))]
        assert len(got) == 5
        stats = first.stats()
        assert stats["frames"].get("crc_mismatch", 0) == 0 and stats["frames"].get("torn_dropped", 0) == 0
