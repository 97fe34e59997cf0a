"""Board unplugged → Home Assistant must not keep saying "Occupied" (issue 17, finding 1).

The runtime reads ``serial://`` from a virtual board behind a real pseudo-terminal and publishes
to a real mosquitto. The cable is pulled: within ``board_timeout_s`` (+ a second) the retained
board topic says "offline" — so the carpet's Home Assistant entities, available only while status
AND board are "online", go unavailable — presence is withdrawn (count 0, also for a subscriber that
connects afterwards), the journal says so once at WARNING, the summary line says there are no
frames instead of "people 1". Plugged back: "online" again, presence again, said once.
"""

import json
import logging
import time

from integration_helpers import premade_board, wait_until
from runtime_helpers import make_config

from edge.cli.run import summary_line
from edge.runtime import Runtime, RuntimeConfig
from edge.topics import DeviceTopics
from firmware_protocol.pty_board import PtyBoard

TIMEOUT_S = 1.0


def last(sub, topic):
    got = sub.on(topic)
    return got[-1][0] if got else None


def presence_count(sub, topic):
    payload = last(sub, topic)
    return None if payload is None else json.loads(payload)["count"]


def test_unplugged_board_goes_unavailable_and_presence_is_withdrawn(tmp_path, sim_calibration, one_person_frames,
                                                                    mqtt_broker, subscribe, caplog):
    broker = mqtt_broker()
    t = DeviceTopics("cavatar", "carpet-01")
    sub = subscribe(broker.port, [t.board, t.presence, t.status])
    caplog.set_level(logging.WARNING, logger="edge.runtime.loop")
    with PtyBoard(premade_board(one_person_frames)) as pty:
        base = make_config(tmp_path, sim_calibration, 1, source=f"serial://{pty.port}?baud=2000000",
                           sinks=[broker.url("qos=1")], device="carpet-01").to_dict()
        base["source"]["board_timeout_s"] = TIMEOUT_S
        rt = Runtime(RuntimeConfig.from_dict(base), say=lambda text: None)
        try:
            rt.start()
            assert wait_until(lambda: last(sub, t.board) == b"online", 15), (sub.messages, rt.snapshot()["publish"])
            assert wait_until(lambda: (presence_count(sub, t.presence) or 0) >= 1, 20), sub.on(t.presence)
            pty.unplug()
            t_unplug = time.monotonic()
            # within the timeout plus the watcher's step (0.2 s) and the trip to the broker; slack for a loaded machine
            assert wait_until(lambda: last(sub, t.board) == b"offline", TIMEOUT_S + 3.0), sub.on(t.board)
            offline_after_s = time.monotonic() - t_unplug
            assert wait_until(lambda: presence_count(sub, t.presence) == 0, 3.0), sub.on(t.presence)
            assert last(sub, t.status) == b"online"  # the runtime itself is fine
            snap = rt.snapshot()
            assert snap["board_health"]["connected"] is False and snap["people"] == 0
            line = summary_line(snap, None, 0.0)
            assert "BOARD" in line and "link dropped" in line and "people" not in line, line
            late = subscribe(broker.port, [t.board, t.presence])  # what Home Assistant sees when it connects now
            assert late.wait_for(t.board, b"offline", 5)
            assert late.wait_for(t.presence, None, 5) and json.loads(late.on(t.presence)[-1][0])["present"] is False
            time.sleep(1.0)
            pty.replug()
            assert wait_until(lambda: last(sub, t.board) == b"online", 20), sub.on(t.board)
            assert wait_until(lambda: (presence_count(sub, t.presence) or 0) >= 1, 20), sub.on(t.presence)
        finally:
            final = rt.stop()
    assert final["error"] is None
    assert wait_until(lambda: last(sub, t.board) == b"offline", 5)  # a stopped runtime reads no frames
    warnings = [r.getMessage() for r in caplog.records if r.levelno == logging.WARNING]
    lost = [w for w in warnings if "reported unavailable" in w]
    back = [w for w in warnings if "reported available" in w]
    assert len(lost) == 1 and len(back) == 1, warnings
    print(f"\nboard offline on MQTT {offline_after_s:.2f} s after the unplug (timeout {TIMEOUT_S} s); {lost[0]}")
    assert offline_after_s < TIMEOUT_S + 3.0


def test_a_board_whose_frames_all_fail_their_crc_is_lost_too_and_says_why(tmp_path, sim_calibration, one_person_frames,
                                                                         caplog):
    """Bytes keep arriving but every frame is damaged (a bad cable, interference): the same unavailability, and the
    reason says it is the checks, not silence."""
    import threading

    caplog.set_level(logging.WARNING, logger="edge.runtime.loop")
    with PtyBoard(premade_board(one_person_frames)) as pty:
        base = make_config(tmp_path, sim_calibration, 1, source=f"serial://{pty.port}?baud=2000000").to_dict()
        base["source"]["board_timeout_s"] = TIMEOUT_S
        rt = Runtime(RuntimeConfig.from_dict(base), say=lambda text: None)
        noisy = threading.Event()

        def interference():
            while noisy.is_set():
                pty.board.flip_bits(200)
                time.sleep(0.005)

        try:
            rt.start()
            assert wait_until(lambda: rt.snapshot()["frames"]["frames_in"] >= 14, 15)
            noisy.set()
            threading.Thread(target=interference, daemon=True).start()
            assert wait_until(lambda: rt.snapshot()["board_health"]["connected"] is False, TIMEOUT_S + 3)
            reason = rt.snapshot()["board_health"]["reason"]
            noisy.clear()
            assert wait_until(lambda: rt.snapshot()["board_health"]["connected"] is True, 10)
        finally:
            noisy.clear()
            rt.stop()
    assert "failed their checks" in reason, reason
    said = [r.getMessage() for r in caplog.records if "reported unavailable" in r.getMessage()]
    assert len(said) == 1 and "bad CRC" in said[0]
