"""The spool owns its files: nothing else in its directory is read or sent, a full disk leaves no half
record, every drop is counted, a bound below two segments is refused (issue 18, findings 3 and 5)."""

import errno
import json
import os

import pytest
from sink_helpers import DEVICE, body_record

import edge.sinks.spool as spool_module
from edge.sinks import open_sink
from edge.sinks.spool import Spool, min_bytes


def line(seq: int, device: str = DEVICE) -> str:
    return json.dumps(body_record(seq, device=device))


def claimed(spool):
    out = []
    while (got := spool.claim()) is not None:
        seg, lines = got
        out += lines
        spool.remove(seg)
    return out


def test_a_symlink_in_the_spool_is_never_followed(tmp_path):
    secret = tmp_path / "shadow"
    secret.write_text(line(666) + "\n")  # even a file that looks like a record
    folder = tmp_path / "spool"
    folder.mkdir(mode=0o700)
    (folder / "0000001000000000.spool").symlink_to(secret)
    spool = Spool(folder, max_bytes=10**6, device=DEVICE)
    assert spool.foreign == 1 and len(spool) == 0 and claimed(spool) == []
    spool.append(line(1))
    spool.seal()
    assert [json.loads(x)["seq"] for x in claimed(spool)] == [1]
    assert secret.read_text() == line(666) + "\n" and (folder / "0000001000000000.spool").is_symlink()


def test_files_dropped_in_the_spool_are_validated_before_anything_is_sent(tmp_path):
    folder = tmp_path / "spool"
    folder.mkdir(mode=0o700)
    (folder / "0000000999999990.spool").write_text("root:x:0:0:root:/root:/bin/bash\n" + line(5, device="other") + "\n"
                                                   + line(7) + "\n" + '{"schema":"cavatar.bodies/1","pressure_kpa":[1]}\n')
    (folder / "notes.txt").write_text(line(8) + "\n")
    spool = Spool(folder, max_bytes=10**6, device=DEVICE)
    got = claimed(spool)
    assert [json.loads(x)["seq"] for x in got] == [7]  # only a valid record of this device
    assert spool.refused == 3 and spool.foreign == 1
    assert (folder / "notes.txt").exists()  # not ours: never read, never deleted


@pytest.mark.parametrize("damage", ["symlink", "others_write"])
def test_a_spool_directory_not_owned_is_refused(tmp_path, damage):
    real = tmp_path / "real"
    real.mkdir(mode=0o700)
    folder = tmp_path / "spool"
    if damage == "symlink":
        folder.symlink_to(real)
    else:
        folder.mkdir()
        folder.chmod(0o777)
    with pytest.raises(OSError, match="symbolic link|writable by others"):
        Spool(folder, max_bytes=10**6)


class FullDisk:
    """``os`` whose write() stores half of what it is given, then fails as a full disk does."""

    def __init__(self):
        self.full = False

    def __getattr__(self, name):
        return getattr(os, name)

    def write(self, fd, data):
        if not self.full:
            return os.write(fd, data)
        os.write(fd, bytes(data[: len(data) // 2]))
        raise OSError(errno.ENOSPC, "No space left on device")


def test_a_full_disk_never_leaves_a_half_record_and_counts_the_drop(tmp_path, monkeypatch, caplog):
    disk = FullDisk()
    monkeypatch.setattr(spool_module, "os", disk)
    spool = Spool(tmp_path, max_bytes=10**6, segment_records=100, device=DEVICE)
    assert spool.append(line(0))
    disk.full = True
    assert [spool.append(line(seq)) for seq in range(1, 4)] == [False] * 3
    disk.full = False
    assert spool.append(line(4))
    spool.seal()
    assert spool.dropped == 3 and "could not be written" in caplog.text
    assert [json.loads(x)["seq"] for x in claimed(spool)] == [0, 4] and spool.refused == 0 and spool.torn == 0


def test_the_open_segment_is_dropped_oldest_first_when_it_alone_fills_the_bound(tmp_path, caplog):
    size = len(line(0)) + 1
    spool = Spool(tmp_path, max_bytes=min_bytes(4), segment_records=4, device=DEVICE)
    n = 4 * (min_bytes(4) // size)
    for seq in range(n):
        spool.append(line(seq))
    spool.seal()
    kept = [json.loads(x)["seq"] for x in claimed(spool)]
    assert kept == list(range(n - len(kept), n)) and spool.dropped == n - len(kept) > 0
    assert "dropped" in caplog.text


def test_a_bound_below_two_segments_is_a_configuration_error(tmp_path):
    with pytest.raises(ValueError, match=r"spool_mb >= 0\.786432"):
        Spool(tmp_path, max_bytes=100_000)
    with pytest.raises(ValueError, match="spool_mb"):
        open_sink(f"mqtt://127.0.0.1:1/c?qos=1&spool={tmp_path / 's'}&spool_mb=0.1", device=DEVICE)
