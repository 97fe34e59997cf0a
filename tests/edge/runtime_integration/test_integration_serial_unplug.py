"""The runtime reading ``serial://`` from a virtual board behind a real pseudo-terminal: the cable is
pulled for 1 s mid-run and plugged back. Publishing resumes by itself — records of frames made
after the replug arrive, the source's reconnect counter goes up (and the status file shows it),
the seq stream has no gap and nothing failed.

The board (firmware_protocol/pty_board.py) answers as ``sim://?seed=7`` and streams pre-made frames
of that virtual carpet with one person in real time at 14 Hz; unplugging closes the pty and
removes its symlink, so pyserial's reads fail exactly as when a USB adapter is pulled (as in
tests/edge/sources/test_serial_usb_sources.py); the bus-powered board reboots on replug.
"""

import threading
import time

from integration_helpers import premade_board, wait_until
from runtime_helpers import make_config, read_jsonl

from edge.runtime import Runtime
from edge.runtime.status import read_status
from firmware_protocol.pty_board import PtyBoard


def test_unplug_for_a_second_and_replug_publishing_resumes_by_itself(tmp_path, sim_calibration, one_person_frames):
    seen = []  # (monotonic, frame host time, record seq) of every record, from the pipeline thread
    lock = threading.Lock()

    def on_outcome(out):
        if out.record is not None:
            with lock:
                seen.append((time.monotonic(), out.frame.host_time_s, out.record["seq"]))

    def records_after(t_wall):
        with lock:
            return [s for s in seen if s[1] > t_wall]

    with PtyBoard(premade_board(one_person_frames)) as pty:
        cfg = make_config(tmp_path, sim_calibration, 1, source=f"serial://{pty.port}?baud=2000000")
        rt = Runtime(cfg, say=lambda text: None)
        rt.on_outcome.append(on_outcome)
        try:
            rt.start()
            assert wait_until(lambda: len(seen) >= 14, 15), f"no records from the board: {rt.snapshot()['source']}"
            pty.unplug()
            t_unplug = time.monotonic()
            time.sleep(1.0)
            assert len(records_after(time.time() - 0.5)) == 0  # nothing while unplugged
            t_replug_wall, t_replug = time.time(), time.monotonic()
            pty.replug()
            assert wait_until(lambda: len(records_after(t_replug_wall)) >= 1, 10), \
                f"no record after the replug: {rt.snapshot()['source']}"
            resumed_s = records_after(t_replug_wall)[0][0] - t_replug
            assert wait_until(lambda: len(records_after(t_replug_wall)) >= 14, 10)  # and it keeps going
            # the status file (rewritten every second) shows the reconnection
            status_file = tmp_path / "status.json"
            assert wait_until(lambda: read_status(status_file)["source"]["queue"].get("reconnects", 0) >= 1, 5)
            live = read_status(status_file)
            assert live["state"] == "running" and live["source"]["queue"]["disconnects"] >= 1
        finally:
            final = rt.stop()
    print(f"\nunplugged {t_replug - t_unplug:.2f} s; first record of a new frame {resumed_s:.3f} s after the replug; "
          f"source {final['source']['queue']}; frames {final['frames']}")
    assert resumed_s < 3.0
    assert final["state"] == "stopped" and final["error"] is None
    assert final["source"]["queue"]["reconnects"] == 1 and final["source"]["queue"]["disconnects"] == 1
    assert final["frames"]["frames_failed"] == 0
    records = read_jsonl(tmp_path / "bodies.jsonl")
    seqs = [r["seq"] for r in records]
    assert seqs == list(range(len(seqs))) and len(records) == final["publish"]["published"]  # no gap, no crash
    assert sum(1 for r in records if r["time"] > t_replug_wall and r["people"]) >= 10  # bodies again, not heartbeats
