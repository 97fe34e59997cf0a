"""`cavatar doctor`: a good setup passes; each broken part gives its own FAIL or warn line and the right exit code."""

import json
import os
import shutil

from deploy_helpers import run_cli


def doctor(capsys, config, *extra):
    code, out = run_cli(["doctor", "--config", str(config), *extra], capsys)
    return code, out.splitlines()


def line(lines, check):
    """The finding line of ``check`` (exactly one)."""
    found = [ln for ln in lines if ln[6:].startswith(f"{check}:")]
    assert len(found) == 1, f"{check!r} in:\n" + "\n".join(lines)
    return found[0]


def levels(lines):
    """check → level of every finding line (check names never hold ": ", messages follow it)."""
    return {ln[6:].split(": ", 1)[0]: ln[:4].strip() for ln in lines if ln[:4].strip() in ("ok", "warn", "FAIL")}


def test_a_good_setup_passes_every_check(capsys, config):
    code, lines = doctor(capsys, config())
    assert code == 0, "\n".join(lines)
    got = levels(lines)
    for check in ("python", "packages", "onnxruntime", "torch", "config", "source", "calibration", "calibration age",
                  "calibration vs board", "model bundle", "body model", "model vs carpet", "status file"):
        assert got.get(check) == "ok", (check, "\n".join(lines))
    assert "not required" in line(lines, "torch")
    assert "SHA-256" in line(lines, "calibration") and "verified" in line(lines, "calibration")
    sink = [c for c in got if c.startswith("sink jsonl://")]
    assert len(sink) == 1 and got[sink[0]] == "ok" and "GB free" in line(lines, sink[0])
    assert lines[-1].startswith("doctor: ") and "0 FAIL" in lines[-1]


def test_json_output_lists_the_findings(capsys, config):
    code, out = run_cli(["doctor", "--config", str(config()), "--json"], capsys)
    data = json.loads(out)
    assert code == 0 and data["ok"] is True and data["schema"] == "cavatar.doctor/1"
    assert {f["level"] for f in data["findings"]} <= {"ok", "warn", "FAIL"}
    assert data["counts"]["FAIL"] == 0 and any(f["check"] == "model bundle" for f in data["findings"])


def test_a_bad_config_is_a_finding_and_ends_the_checks(capsys, config):
    code, lines = doctor(capsys, config(runtime={"bogus_key": 1}, sinks={"urls": ["ftp://x"]}))
    assert code == 1
    cfg = line(lines, "config")
    assert cfg.startswith("FAIL") and "runtime.bogus_key: unknown key" in cfg and "sinks.urls" in cfg
    assert "source" not in levels(lines) and "python" in levels(lines)


def test_a_missing_calibration_file_fails_and_says_how_to_calibrate(capsys, config, tmp_path):
    code, lines = doctor(capsys, config(calibration={"file": str(tmp_path / "nowhere.npz")}))
    assert code == 1
    cal = line(lines, "calibration")
    assert cal.startswith("FAIL") and "no calibration file" in cal and "cavatar calibrate --source" in cal
    assert levels(lines)["model bundle"] == "ok"  # the other checks still run


def test_a_damaged_calibration_fails_on_its_hash(capsys, config, calibration):
    import io
    import json as _json

    import numpy as np

    path = calibration("damaged.npz")  # not the fixture's default name, which config() saves again
    with np.load(path) as z:
        arrays = {k: z[k] for k in z.files}
    meta = _json.loads(str(arrays["meta"]))
    meta["pitch_m"] = 0.02  # edited after saving: the recorded SHA-256 no longer matches
    arrays["meta"] = np.array(_json.dumps(meta))
    buf = io.BytesIO()
    np.savez_compressed(buf, **arrays)
    path.write_bytes(buf.getvalue())
    code, lines = doctor(capsys, config(calibration={"file": str(path)}))
    assert code == 1 and "is damaged" in line(lines, "calibration")


def test_an_old_calibration_is_a_warning_not_a_failure(capsys, config, calibration):
    old = calibration("old.npz", created="2020-01-01T00:00:00+00:00")
    code, lines = doctor(capsys, config(calibration={"file": str(old), "max_age_days": 30}))
    age = line(lines, "calibration age")
    assert code == 0, "\n".join(lines)
    assert age.startswith("warn") and "due for recalibration" in age and "max_age_days (30)" in age
    code, lines = doctor(capsys, config(calibration={"max_age_days": 1e-9}))  # brand new, but a tiny limit
    assert code == 0 and line(lines, "calibration age").startswith("warn")


def test_a_calibration_of_another_carpet_fails_against_the_board(capsys, config, calibration):
    other = calibration("other.npz", device_id="hall-carpet")
    code, lines = doctor(capsys, config(calibration={"file": str(other)}))
    assert code == 1
    vs = line(lines, "calibration vs board")
    assert vs.startswith("FAIL") and "'hall-carpet' in the file" in vs and "cavatar calibrate" in vs


def test_a_bundle_for_another_grid_fails(capsys, config, calibration):
    small = calibration("small.npz", grid=32)
    code, lines = doctor(capsys, config(calibration={"file": str(small)}, source={"url": "sim://?seed=7&grid=32"}))
    assert code == 1
    assert line(lines, "model vs carpet").startswith("FAIL") and "96×96" in line(lines, "model vs carpet")


def test_a_tampered_bundle_fails_on_its_hash(capsys, config, tmp_path):
    from edge.runtime.config import default_bundle_path

    bundle = tmp_path / "bundle"
    shutil.copytree(default_bundle_path(), bundle)
    head = bundle / "head.onnx"
    data = bytearray(head.read_bytes())
    data[len(data) // 2] ^= 0x01
    head.write_bytes(bytes(data))
    code, lines = doctor(capsys, config(model={"bundle": str(bundle)}))
    assert code == 1
    b = line(lines, "model bundle")
    assert b.startswith("FAIL") and "SHA-256 mismatch" in b and "head.onnx" in b and "install.sh" in b


def test_a_serial_port_that_does_not_exist_fails_and_the_board_is_not_probed(capsys, config, tmp_path):
    code, lines = doctor(capsys, config(source={"url": f"serial://{tmp_path}/ttyNOPE"}))
    assert code == 1
    src = line(lines, "source")
    assert src.startswith("FAIL") and "does not exist" in src and "cavatar devices" in src and "/dev/cavatar-carpet" in src
    assert "board" not in levels(lines) and "calibration vs board" not in levels(lines)


def test_a_serial_board_is_asked_for_its_info_and_checked_against_the_calibration(capsys, config, calibration):
    from firmware_protocol.pty_board import PtyBoard
    from firmware_protocol.virtual_board import VirtualBoard

    with PtyBoard(VirtualBoard(96, 96, device_id="sim-7", sign=-1)) as pty:
        code, lines = doctor(capsys, config(source={"url": f"serial://{pty.port}"}))
        assert code == 0, "\n".join(lines)
        assert line(lines, "source").startswith("ok") and "readable and writable" in line(lines, "source")
        assert line(lines, "board").startswith("ok") and "sim-7 answered: 96×96, 12-bit, 14 Hz" in line(lines, "board")
        assert "sign, firmware" in line(lines, "calibration vs board")
        other = calibration("other.npz", device_id="hall-carpet")
        code, lines = doctor(capsys, config(source={"url": f"serial://{pty.port}"}, calibration={"file": str(other)}))
        assert code == 1 and line(lines, "calibration vs board").startswith("FAIL")
        code, lines = doctor(capsys, config(source={"url": f"serial://{pty.port}"}), "--no-open")
        assert code == 0 and "--no-open" in line(lines, "board") and "calibration vs board" not in levels(lines)


def test_a_silent_serial_port_fails_within_the_timeout(capsys, config):
    import time

    master, slave = os.openpty()  # a port nobody answers on
    try:
        t0 = time.monotonic()
        code, lines = doctor(capsys, config(source={"url": f"serial://{os.ttyname(slave)}"}))
        assert time.monotonic() - t0 < 8
    finally:
        os.close(master)
        os.close(slave)
    board = line(lines, "board")
    assert code == 1 and board.startswith("FAIL") and "no bytes from the board within 2.0 s" in board


def test_a_board_in_use_by_a_running_runtime_is_left_alone(capsys, config, tmp_path):
    from edge.runtime.status import SCHEMA, write_status
    from firmware_protocol.pty_board import PtyBoard
    from firmware_protocol.virtual_board import VirtualBoard

    board = {"device_id": "sim-7", "rows": 96, "cols": 96, "adc_bits": 12}
    write_status(tmp_path / "out" / "status.json", {"schema": SCHEMA, "state": "running", "pid": os.getppid(),
                                                    "source": {"board": board}})
    with PtyBoard(VirtualBoard(96, 96, device_id="sim-7")) as pty:
        code, lines = doctor(capsys, config(source={"url": f"serial://{pty.port}"}))
        assert pty.bytes_received == 0  # doctor sent the board nothing
    assert code == 0, "\n".join(lines)
    assert f"(pid {os.getppid()}) is using it" in line(lines, "board")
    assert line(lines, "calibration vs board").startswith("ok")


def test_a_usb_board_is_found_and_probed_through_pyusb(config):
    from edge.runtime.doctor import diagnose
    from edge.sources.usb_virtual import VirtualUsbBackend
    from firmware_protocol.virtual_board import VirtualBoard

    backend = VirtualUsbBackend(VirtualBoard(96, 96, device_id="usb-01"))
    found = {f.check: f for f in diagnose(config(source={"url": "usb://1209:CA7A?serial=usb-01"}), usb_backend=backend)}
    assert found["source"].level == "ok" and "1209:ca7a present" in found["source"].message
    assert found["board"].level == "ok" and "usb-01 answered" in found["board"].message
    assert found["calibration vs board"].level == "FAIL"  # the calibration is sim-7's
    missing = {f.check: f for f in diagnose(config(source={"url": "usb://1234:5678"}), usb_backend=backend)}
    assert missing["source"].level == "FAIL" and "no USB device 1234:5678" in missing["source"].message
    assert "1209:ca7a" in missing["source"].message  # what is there instead


def test_an_unreachable_broker_fails(capsys, config, tmp_path):
    from sink_helpers import free_port

    port = free_port()  # bound and released: nobody listens there
    code, lines = doctor(capsys, config(sinks={"urls": [f"mqtt://cavatar@127.0.0.1:{port}/cavatar"]}))
    assert code == 1
    sink = line(lines, f"sink mqtt://cavatar@127.0.0.1:{port}/cavatar")
    assert sink.startswith("FAIL") and f"127.0.0.1:{port} not reachable" in sink


def test_a_broker_login_is_checked_with_the_password_from_the_environment(capsys, config, make_broker, monkeypatch):
    secret = "s3cr3t-pw-do-not-print"
    broker = make_broker(users={"cavatar": secret})
    url = broker.url(user="cavatar", query="qos=1")
    monkeypatch.setenv("CAVATAR_MQTT_PASSWORD", secret)
    code, lines = doctor(capsys, config(sinks={"urls": [url]}))
    assert code == 0, "\n".join(lines)
    assert "MQTT login accepted (user 'cavatar')" in line(lines, f"sink {url}")
    monkeypatch.setenv("CAVATAR_MQTT_PASSWORD", "wrong-" + secret)
    code, lines = doctor(capsys, config(sinks={"urls": [url]}))
    assert code == 1
    sink = line(lines, f"sink {url}")
    assert sink.startswith("FAIL") and "refused the MQTT login of user 'cavatar'" in sink
    assert "$CAVATAR_MQTT_PASSWORD (set here" in sink
    assert all(secret not in ln for ln in lines)
    monkeypatch.delenv("CAVATAR_MQTT_PASSWORD")
    code, lines = doctor(capsys, config(sinks={"urls": [url]}))
    assert code == 1 and "NOT set" in line(lines, f"sink {url}")


def test_an_anonymous_broker_passes_and_the_spool_folder_is_checked(capsys, config, make_broker, tmp_path):
    broker = make_broker()
    url = broker.url(query=f"qos=1&spool={tmp_path}/spool")
    code, lines = doctor(capsys, config(sinks={"urls": [url]}))
    assert code == 0, "\n".join(lines)
    assert "login accepted (anonymous)" in line(lines, f"sink {url}")
    assert line(lines, f"sink {url} spool").startswith("ok")


def test_the_status_folder_of_the_service_is_fine_before_systemd_made_it(capsys, config, tmp_path, monkeypatch):
    from edge import health

    run_dir = tmp_path / "run" / "cavatar"  # stands for /run/cavatar, which systemd creates at start
    monkeypatch.setattr(health, "SERVICE_DIRS", {str(run_dir): "RuntimeDirectory=cavatar"})
    code, lines = doctor(capsys, config(runtime={"status_file": str(run_dir / "status.json")}))
    assert code == 0 and "RuntimeDirectory=cavatar" in line(lines, "status file")


def test_a_port_or_folder_this_user_may_not_use_fails_saying_what_to_do(capsys, config, tmp_path, monkeypatch):
    """The tests run as root, for whom everything is accessible: os.access is narrowed to what a user would see."""
    import grp

    master, slave = os.openpty()
    port, out = os.ttyname(slave), tmp_path / "out"
    os.chown(port, -1, grp.getgrnam("dialout").gr_gid)  # as a CDC-ACM port is
    os.chmod(port, 0o660)
    out.mkdir()
    real_access = os.access
    monkeypatch.setattr(os, "access",
                        lambda p, mode: False if str(p) in (port, str(out)) else real_access(p, mode))
    try:
        code, lines = doctor(capsys, config(source={"url": f"serial://{port}"}))
    finally:
        os.close(master)
        os.close(slave)
    assert code == 1
    src = line(lines, "source")
    assert src.startswith("FAIL") and "is not readable and writable by user" in src
    assert "add the user to the group dialout (sudo usermod -aG dialout" in src and "99-cavatar.rules" in src
    status = line(lines, "status file")
    assert status.startswith("FAIL") and f"{out} (" in status and "not writable" in status


def test_a_board_is_not_probed_when_the_status_file_cannot_be_read(capsys, config, tmp_path, monkeypatch):
    """As a user outside the service's group: the runtime may hold the board, so doctor does not open it."""
    from edge.runtime.status import SCHEMA, write_status
    from firmware_protocol.pty_board import PtyBoard
    from firmware_protocol.virtual_board import VirtualBoard

    status = tmp_path / "out" / "status.json"
    write_status(status, {"schema": SCHEMA, "state": "stopped", "pid": 1})
    real_access = os.access
    monkeypatch.setattr(os, "access",
                        lambda p, mode: False if str(p) == str(status) and mode & os.R_OK else real_access(p, mode))
    with PtyBoard(VirtualBoard(96, 96, device_id="sim-7")) as pty:
        code, lines = doctor(capsys, config(source={"url": f"serial://{pty.port}"}))
        assert pty.bytes_received == 0
    board = line(lines, "board")
    assert code == 0 and board.startswith("warn") and "not opened" in board and "systemctl stop cavatar" in board


def test_doctor_passes_on_a_board_without_torch(config):
    """In a fresh interpreter where importing torch fails (as on the board): doctor still passes, torch 'not required'."""
    import subprocess
    import sys

    from test_edge_without_torch import BLOCK_TORCH

    code = BLOCK_TORCH + (
        "import sys\n"
        "from edge.cli import main\n"
        f"sys.exit(main(['doctor', '--config', {str(config())!r}, '--no-open']))\n")
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert "ok    torch: not required (not installed)" in proc.stdout


def test_a_package_that_requires_torch_fails(capsys, config, monkeypatch):
    from edge.runtime import install_check

    monkeypatch.setattr(install_check, "_requires", lambda dist: ["numpy>=1.26", "torch==2.13.0"])
    code, lines = doctor(capsys, config())
    assert code == 1 and line(lines, "torch").startswith("FAIL") and "export extra" in line(lines, "torch")
