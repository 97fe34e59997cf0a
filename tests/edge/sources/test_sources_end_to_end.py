"""Sources end to end through the real protocol: virtual carpet, replay, record/inspect, mismatch."""

import time

import numpy as np
import pytest

from edge.cli import main
from edge.sources import CommandRefused, open_source
from firmware_protocol import codec


def take(source, n, timeout_s=10.0):
    frames, deadline = [], time.monotonic() + timeout_s
    for frame in source.frames(timeout_s=timeout_s):
        frames.append(frame)
        if len(frames) >= n or time.monotonic() > deadline:
            break
    return frames


def test_virtual_carpet_frames_arrive_whole_and_in_order():
    with open_source("sim://?world=footsteps&people=2&seed=7&speed=0") as source:
        frames = take(source, 30)
        info = source.info
        stats = source.stats()
    assert (info.rows, info.cols, info.adc_bits, info.rate_mhz) == (96, 96, 12, 14000)
    assert len(frames) == 30
    assert [f.index for f in frames] == list(range(frames[0].index, frames[0].index + 30))
    assert all(f.counts.shape == (96, 96) and f.counts.dtype == np.uint16 for f in frames)
    assert np.diff([f.t_s for f in frames]) == pytest.approx(1 / 14, abs=2e-3)
    loaded = (frames[-1].counts < 2000).sum()
    assert 20 < loaded < 2000, "two people's feet should load some sensels"
    assert stats["decoder"]["dropped_total"] == 0 and stats["frames"].get("torn_dropped", 0) == 0


def test_line_noise_is_counted_and_frames_keep_flowing():
    with open_source("sim://?world=footsteps&people=1&seed=3&speed=0&faults=1") as source:
        frames = take(source, 120)
        stats = source.stats()
    assert len(frames) == 120
    lost = stats["decoder"]["dropped_total"] + stats["frames"].get("torn_dropped", 0) + stats["frames"].get("crc_mismatch", 0)
    assert lost > 0, stats
    assert frames[-1].index - frames[0].index >= 119


def test_commands_are_acknowledged_or_refused_with_a_reason():
    with open_source("sim://?world=footsteps&speed=0") as source:
        ack = source.command("PING", token=0xC0FFEE)
        assert isinstance(ack, codec.Ack) and ack.value == 0xC0FFEE
        with pytest.raises(CommandRefused, match="out_of_range"):
            source.command("SET_RATE", rate_mhz=10_000_000)


def test_record_then_inspect_then_replay_gives_the_same_frames(tmp_path, capsys):
    out = tmp_path / "capture.bin"
    assert main(["record", "--source", "sim://?world=footsteps&people=1&seed=5&speed=0", "--frames", "12", str(out)]) == 0
    assert not (tmp_path / "capture.bin.part").exists()
    assert main(["inspect", "--json", str(out)]) == 0
    import json

    summary = json.loads(capsys.readouterr().out.split("\n", 1)[1])
    assert summary["info"]["device_id"] == "sim-5"
    assert summary["frames"] >= 12
    assert summary["rate_hz"] == pytest.approx(14.0, rel=0.02)
    with open_source(f"replay://{out}?speed=0") as replay:
        replayed = take(replay, 100)
    with open_source("sim://?world=footsteps&people=1&seed=5&speed=0") as live:
        fresh = take(live, len(replayed))
    assert len(replayed) >= 12
    for a, b in zip(replayed, fresh):
        np.testing.assert_array_equal(a.counts, b.counts)


def test_record_refuses_to_overwrite_and_leaves_nothing_on_failure(tmp_path, capsys):
    out = tmp_path / "c.bin"
    out.write_bytes(b"keep me")
    assert main(["record", "--source", "sim://?world=footsteps&speed=0", "--frames", "2", str(out)]) == 2
    assert out.read_bytes() == b"keep me"
    assert "--force" in capsys.readouterr().err
    missing = tmp_path / "d.bin"
    assert main(["record", "--source", "serial:///dev/ttyNOPE", "--frames", "2", str(missing)]) == 2
    assert not missing.exists() and not (tmp_path / "d.bin.part").exists()


def test_replay_paces_frames_by_device_time(tmp_path):
    out = tmp_path / "c.bin"
    assert main(["record", "--source", "sim://?world=footsteps&speed=0", "--frames", "8", str(out)]) == 0
    t0 = time.monotonic()
    with open_source(f"replay://{out}?speed=4") as replay:
        frames = take(replay, 8)
    elapsed = time.monotonic() - t0
    span = frames[-1].t_s - frames[0].t_s
    assert elapsed >= 0.8 * span / 4


def test_a_device_of_another_protocol_version_is_refused_naming_both(tmp_path):
    foreign = codec.Info(0, 2, 0x1234, 9, 9, 9, "future", 96, 96, 3, 3, 12, 1, -1, 14000, 0)
    path = tmp_path / "future.bin"
    path.write_bytes(codec.encode(foreign) * 3)
    with pytest.raises(codec.ProtocolMismatchError) as err:
        open_source(f"replay://{path}").start()
    msg = str(err.value)
    assert "v2" in msg and f"v{codec.PROTOCOL_VERSION}" in msg and "0x1234" in msg


def test_a_slow_consumer_gets_the_newest_frame_not_a_growing_backlog():
    with open_source("sim://?world=footsteps&speed=4", queue_frames=2) as source:
        first = source.read_frame(timeout_s=3)
        time.sleep(1.5)  # ~84 frames are produced meanwhile at 4x real time
        later = source.read_frame(timeout_s=3)
        dropped = source.stats()["source"].get("dropped_slow_consumer", 0)
    assert first is not None and later is not None
    assert dropped > 50
    assert later.index - first.index > 50
