"""seq never repeats for a device: reserved in blocks before use, one runtime per status file (issue 18, finding 4)."""

import json

import pytest
from runtime_helpers import read_jsonl

from edge.runtime import Runtime, SetupError
from edge.runtime.seq import SeqLedger, SeqLedgerBusy, SeqLedgerError


def test_a_crash_skips_to_the_end_of_the_reserved_block_never_back(tmp_path):
    status = tmp_path / "status.json"
    first = SeqLedger(status, "carpet-01", block=100)
    assert first.open() == 0
    for seq in range(250):  # published up to 249; the ledger said 300 before 200 was used
        first.reserve(seq)
    assert json.loads((tmp_path / "status.json.seq").read_text()) == {"carpet-01": 300}
    first.close()  # as a SIGKILL would leave it: no clean hand-back
    again = SeqLedger(status, "carpet-01", block=100)
    assert again.open() == 300
    again.close(next_seq=312)  # a clean stop gives the rest back
    assert SeqLedger(status, "carpet-01").open() == 312


def test_a_second_holder_of_one_status_file_is_refused(tmp_path):
    status = tmp_path / "status.json"
    holder = SeqLedger(status, "carpet-01")
    holder.open()
    try:
        with pytest.raises(SeqLedgerBusy, match=r"pid \d+.*own \[runtime\] status_file"):
            SeqLedger(status, "carpet-01").open()
    finally:
        holder.close()
    SeqLedger(status, "carpet-01").open()  # free again


def test_a_damaged_ledger_is_a_clear_error(tmp_path):
    (tmp_path / "status.json.seq").write_text("{\"carpet-01\": -4}")
    with pytest.raises(SeqLedgerError, match="damaged"):
        SeqLedger(tmp_path / "status.json", "carpet-01").open()


def test_seq_is_never_reused_after_a_crash_that_left_an_old_last_seq(config, tmp_path):
    Runtime(config(people=0), say=lambda text: None).run_for(frames=30)
    used = [r["seq"] for r in read_jsonl(tmp_path / "bodies.jsonl")]
    # SIGKILL: the status file (written once a second) still says an earlier seq, the ledger is mid-block
    status = json.loads((tmp_path / "status.json").read_text())
    status["publish"]["last_seq"] = 0
    status["state"] = "running"
    (tmp_path / "status.json").write_text(json.dumps(status))
    ledger = tmp_path / "status.json.seq"
    ledger.write_text(json.dumps({"carpet-01": 1024}))
    Runtime(config(people=0), say=lambda text: None).run_for(frames=30)
    seqs = [r["seq"] for r in read_jsonl(tmp_path / "bodies.jsonl")]
    later = seqs[len(used):]
    assert later and min(later) == 1024 and len(set(seqs)) == len(seqs)


def test_a_second_runtime_on_the_same_status_file_is_refused(config, tmp_path):
    first = Runtime(config(people=0), say=lambda text: None)
    first.setup()
    try:
        with pytest.raises(SetupError, match="another runtime"):
            Runtime(config(people=0), say=lambda text: None).setup()
    finally:
        first.stop()
