"""The runtime's setup checks and its info payload, each on its own (edge.runtime.setup, edge.runtime.telemetry)."""

import pytest

from edge.record import check_telemetry
from edge.runtime.config import RuntimeConfig
from edge.runtime.errors import SetupError
from edge.runtime.loop import Runtime
from edge.runtime.setup import check_status_writable, previous_seq
from edge.runtime.status import SCHEMA, write_status
from edge.runtime.telemetry import info_payload


def test_previous_seq_continues_only_this_devices_own_status(tmp_path):
    status = tmp_path / "status.json"
    assert previous_seq(status, "carpet-01") == -1  # no file yet
    write_status(status, {"schema": SCHEMA, "device": "carpet-01", "publish": {"last_seq": 41}})
    assert previous_seq(status, "carpet-01") == 41
    assert previous_seq(status, "carpet-02") == -1  # another board's numbers are not ours
    write_status(status, {"schema": SCHEMA, "device": "carpet-01", "publish": {"last_seq": None}})
    assert previous_seq(status, "carpet-01") == -1
    status.write_text("{not json")
    assert previous_seq(status, "carpet-01") == -1


def test_status_folder_is_made_or_refused_naming_the_key(tmp_path):
    status = tmp_path / "run" / "cavatar" / "status.json"
    check_status_writable(status)
    assert status.parent.is_dir()
    blocker = tmp_path / "a-file"
    blocker.write_text("")
    with pytest.raises(SetupError, match=r"cannot create its folder.*\[runtime\] status_file"):
        check_status_writable(blocker / "status.json")


def test_info_payload_of_a_runtime_not_yet_set_up_is_telemetry_only(tmp_path):
    cfg = RuntimeConfig.from_dict({"runtime": {"status_file": str(tmp_path / "status.json")}})
    snap = Runtime(cfg).snapshot()
    info = info_payload(snap, ["walk", "squat"], state="stopped")
    check_telemetry(info)
    assert info["state"] == "stopped" and info_payload(snap, None)["state"] == "new"
    assert info["activities"] == ["walk", "squat"] and info["grid"] is None and info["board_connected"] is None
    assert info["health"]["frames_in"] == 0
