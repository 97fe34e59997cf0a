"""Hostile configurations and folders: huge counts and deep nesting are problems, not a hang or a traceback;
a failed status write leaves nothing behind (issue 18, item 10)."""

import pytest

from edge.runtime.config import ConfigError, load_config


def test_huge_counts_are_refused_with_their_bounds(tmp_path):
    p = tmp_path / "cavatar.toml"
    p.write_text("[model]\nthreads = 100000\n[source]\nqueue_frames = 10000000\n[sinks]\nqueue_records = 10000000000\n")
    with pytest.raises(ConfigError) as exc:
        load_config(p)
    text = str(exc.value)
    assert "model.threads: must be ≤ 64" in text and "source.queue_frames: must be ≤ 1024" in text
    assert "sinks.queue_records: must be ≤ 100000" in text


def test_a_deeply_nested_file_is_one_problem(tmp_path):
    p = tmp_path / "cavatar.toml"
    p.write_text("x = " + "[" * 100_000 + "]" * 100_000 + "\n")
    with pytest.raises(ConfigError, match="nested too deeply"):
        load_config(p)


def test_a_failed_status_write_leaves_no_temporary_file(tmp_path):
    from edge.runtime.status import write_status

    target = tmp_path / "status.json"
    target.mkdir()  # os.replace fails, as a full or broken folder would make it
    with pytest.raises(OSError):
        write_status(target, {"state": "running"})
    assert sorted(p.name for p in tmp_path.iterdir()) == ["status.json"]
