"""cavatar_common.atomic (issue 17): a file is the old one or the whole new one, never half — the one helper for the status
file, the calibration session's state, captures and step results."""

import os

import numpy as np
import pytest

from cavatar_common.atomic import atomic_path, write_atomic


def test_the_new_content_replaces_the_old_and_nothing_is_left_beside_it(tmp_path):
    target = tmp_path / "state.json"
    target.write_text("old")
    write_atomic(target, '{"done": ["empty"]}')
    assert target.read_text() == '{"done": ["empty"]}' and sorted(p.name for p in tmp_path.iterdir()) == ["state.json"]


def test_a_writer_that_fails_leaves_the_old_file_and_no_temporary(tmp_path):
    target = tmp_path / "capture.npz"
    target.write_bytes(b"old capture")
    with pytest.raises(RuntimeError):
        with atomic_path(target) as tmp:
            tmp.write_bytes(b"half of a new cap")
            raise RuntimeError("disk full")
    assert target.read_bytes() == b"old capture" and sorted(p.name for p in tmp_path.iterdir()) == ["capture.npz"]


def test_writers_that_add_a_suffix_get_one_already(tmp_path):
    target = tmp_path / "walk.npz"
    with atomic_path(target) as tmp:
        np.savez(tmp, a=np.arange(3))  # np.savez appends .npz to a name without it
    with np.load(target) as z:
        assert z["a"].tolist() == [0, 1, 2]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["walk.npz"]


def test_durable_writes_fsync_the_file_and_the_folder(tmp_path, monkeypatch):
    synced = []
    real = os.fsync
    monkeypatch.setattr(os, "fsync", lambda fd: (synced.append(os.readlink(f"/proc/self/fd/{fd}")), real(fd)))
    write_atomic(tmp_path / "a.json", "{}")
    assert len(synced) == 2 and synced[0].endswith(".part.json") and synced[1] == str(tmp_path)
    synced.clear()
    write_atomic(tmp_path / "status.json", "{}", durable=False)
    assert synced == []


def test_two_threads_writing_one_target_never_collide(tmp_path):
    """The runtime's status thread and its stop() may write the status file at the same moment: each write
    has its own temporary file, so neither rename finds its file taken by the other."""
    import threading

    from cavatar_common.atomic import write_atomic

    target, errors = tmp_path / "status.json", []

    def writer(k: int) -> None:
        try:
            for i in range(300):
                write_atomic(target, f"{k} {i}\n", durable=False)
        except OSError as exc:  # FileNotFoundError when two writes shared one temporary name
            errors.append(exc)

    threads = [threading.Thread(target=writer, args=(k,)) for k in range(4)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert not errors
    assert target.read_text().split()[1] == "299" and not list(tmp_path.glob(".*.part*"))
