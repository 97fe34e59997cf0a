"""The session runner (resume, --redo), the CLI (sim and recordings), auto-range and the report."""

import json

import numpy as np
import pytest

from calibration.actor import Actor
from calibration.autorange import auto_range
from calibration.file import Calibration
from calibration.providers import RecordingProvider, SimProvider
from calibration.session import Session, SessionError
from calibration.terminal import render_map
from edge.cli import main
from sim.sensor import CarpetSensor


class CountingProvider(SimProvider):
    def __init__(self, actor):
        super().__init__(actor, out=lambda s: None)
        self.asked = []

    def capture(self, step, attempt, last):
        self.asked.append(step)
        return super().capture(step, attempt, last)


def test_session_resumes_after_each_step_and_redoes_one_step_alone(tmp_path):
    sensor = CarpetSensor.random(11, grid=32, faults=False)
    actor = Actor(sensor, mass_kg=80.0)
    work = tmp_path / "w"
    s1 = Session(work)
    s1.options.mass_kg = 80.0
    p1 = CountingProvider(actor)
    s1.run(p1, steps=("self_test", "empty", "walk"))
    assert p1.asked == ["self_test", "empty", "walk"]
    assert json.loads((work / "state.json").read_text())["done"] == ["self_test", "empty", "walk"]
    # a new process resumes: only the missing steps are asked for, the mass is remembered
    s2 = Session(work)
    assert s2.options.mass_kg == 80.0
    p2 = CountingProvider(actor)
    s2.run(p2)
    assert p2.asked == ["board", "stance", "holdout"]
    cal, val = s2.finish(tmp_path / "cal.npz")
    assert val.ok
    gain_before = s2.result("board").arrays["gain"].copy()
    # --redo board: that step alone, with a fresh capture
    p3 = CountingProvider(actor)
    Session(work).run(p3, redo="board")
    assert p3.asked == ["board"]
    assert not np.array_equal(Session(work).result("board").arrays["gain"], gain_before)
    with pytest.raises(ValueError, match="unknown step"):
        Session(work).run(p3, redo="nope")


def test_a_refused_recording_stops_the_session_with_the_reason(tmp_path):
    sensor = CarpetSensor.random(12, grid=32, faults=False)
    actor = Actor(sensor)
    actor.empty(seconds=1.0).save(tmp_path / "short.npz")
    with pytest.raises(SessionError, match="at least 5 s"):
        Session(tmp_path / "w").run(RecordingProvider({"empty": str(tmp_path / "short.npz")}, out=lambda s: None),
                                    steps=("empty",))


def test_cli_from_recordings_writes_calibration_and_report(tmp_path, capsys):
    sensor = CarpetSensor.random(13, grid=32, faults=False)
    actor = Actor(sensor, mass_kg=70.0)
    caps = actor.session()
    args = []
    for name, cap in caps.items():
        cap.save(tmp_path / f"{name}.npz")
        args += [f"--{name}", str(tmp_path / f"{name}.npz")]
    out = tmp_path / "cal.npz"
    rc = main(["calibrate", *args, "--mass", "70", "--work", str(tmp_path / "w"), "--out", str(out)])
    text = capsys.readouterr().out
    assert rc == 0, text
    cal = Calibration.load(out)
    assert cal.device["device_id"] == "sim-13" and cal.validation["ok"]
    assert (tmp_path / "cal.png").stat().st_size > 10_000
    summary = (tmp_path / "cal.txt").read_text()
    assert "force_error" in summary and "gain spread" in summary
    assert "coverage map" in text


def test_cli_sim_mode_and_bad_arguments(tmp_path, capsys):
    out = tmp_path / "cal.npz"
    rc = main(["calibrate", "--sim", "--grid", "32", "--seed", "4", "--intruder", "walking", "--no-map",
               "--work", str(tmp_path / "w"), "--out", str(out)])
    text = capsys.readouterr().out
    assert rc in (0, 1) and out.exists(), text
    assert "== Empty capture" in text and "[validation]" in text
    assert main(["calibrate", "--work", str(tmp_path / "empty-work")]) == 2
    assert "give a source" in capsys.readouterr().err


def test_cli_without_matplotlib_still_writes_the_calibration_and_text_report(tmp_path, capsys, monkeypatch):
    import sys

    monkeypatch.setitem(sys.modules, "matplotlib", None)  # a board installed without the viz extra
    out = tmp_path / "cal.npz"
    rc = main(["calibrate", "--sim", "--grid", "32", "--seed", "4", "--no-map", "--work", str(tmp_path / "w"), "--out", str(out)])
    text = capsys.readouterr().out
    assert rc in (0, 1) and out.exists() and (tmp_path / "cal.txt").exists(), text
    assert not (tmp_path / "cal.png").exists() and "no PNG: matplotlib is not installed" in text


def test_auto_range_picks_the_highest_gain_with_at_most_1_percent_at_the_rail():
    from edge.peripherals import open_chip
    from edge.peripherals.fakebus import FakeBus, FakeMCP4018

    bus = FakeBus({0x2F: FakeMCP4018()})
    pot = open_chip("mcp4018", bus)
    rng = np.random.default_rng(0)
    h = w = 16
    base = np.full((h, w), 512.0)
    noise = np.full((h, w), 1.5)
    load = np.zeros((h, w))
    load[4:10, 4:8] = np.linspace(0.1, 1.0, 24).reshape(6, 4)  # a foot, relative response

    def capture(step):
        gain = 200 + 8 * step  # counts per unit load at this wiper step
        frames = base + gain * load + rng.normal(0, 1.5, (5, h, w))
        return np.clip(np.rint(frames), 0, 1023)

    res = auto_range(pot, capture, base, noise, +1, 1023, np.ones((h, w), bool))
    step = res.numbers["step"]
    assert res.ok and pot.wiper() == step
    assert 200 + 8 * step <= 511 < 200 + 8 * (step + 1) + 8  # the last step before the foot's peak hits the rail


def test_terminal_map_draws_coverage_and_faults():
    m = np.zeros((96, 96))
    m[:48] = 1
    faults = np.zeros((96, 96), bool)
    faults[:, 90:] = True
    text = render_map(m, title="coverage", faults=faults)
    lines = text.splitlines()
    assert lines[0] == "coverage" and lines[1].startswith("┌") and len(lines[2]) == 50
    assert "█" in lines[2] and "x" in lines[2] and lines[-3].strip("│x ") == ""


def test_live_provider_and_a_recorded_byte_stream_go_through_the_real_decoder(tmp_path, capsys):
    from calibration.capture import Capture
    from calibration.providers import LiveProvider
    from edge.cli.calibrate import open_frames  # calibration reads frames through the opener the runtime passes in

    url = "sim://?world=footsteps&people=0&grid=32&bits=12&speed=0"
    live = LiveProvider(url, open_frames, ask=lambda prompt: "", out=lambda s: None)
    cap = live.capture("self_test", 0, None)
    assert cap.frames.shape[1:] == (32, 32) and cap.device["rows"] == 32 and cap.device["adc_bits"] == 12
    assert cap.frames.shape[0] == 42 and abs(cap.rate_hz - 14.0) < 1e-6
    bin_path = tmp_path / "empty.bin"
    assert main(["record", str(bin_path), "--source", url, "--frames", "80"]) == 0
    with pytest.raises(ValueError, match="pass open_frames"):
        Capture.load(bin_path)  # calibration alone has no decoder: it says what it needs
    rec = Capture.load(bin_path, open_frames=open_frames)
    assert rec.frames.shape[0] >= 80 and rec.shape == (32, 32) and rec.device["device_id"] == cap.device["device_id"]
