"""Line faults, shorts, mux banks and the sign convention, found by the empty capture and the walk."""

from calibration.actor import Actor
from calibration.empty import empty_capture
from calibration.file import FAULT, UNUSABLE
from calibration.walk import coverage_walk
from sim.sensor import CarpetSensor, FaultConfig, LineFault, MuxBankFault, ShortFault


def run(faults, seed=5, sign=None, grid=96):
    s = CarpetSensor.random(seed, grid=grid, faults=faults, sign=sign)
    a = Actor(s)
    e = empty_capture(a.empty())
    assert e.ok, e.findings
    w = coverage_walk(a.walk(), e.arrays["baseline_counts"], e.arrays["noise_counts"], e.arrays["fault"])
    return s, e, w


def test_dead_row_only_after_the_walk_half_dead_stuck_column_and_short():
    faults = FaultConfig(lines=(LineFault("dead", "row", 40), LineFault("half_dead", "col", 20, factor=0.3),
                                LineFault("stuck", "col", 70)), shorts=(ShortFault(10, 33),))
    s, e, w = run(faults)
    ef, wf = e.arrays["fault"], w.arrays["fault"]
    # empty capture: stuck column and short, but the open row is invisible
    assert (ef[:, 70] & FAULT["stuck"]).all() and ((ef & FAULT["stuck"]) > 0).sum() == 96
    assert ef[10, 33] & FAULT["short"] and not (ef[10, :33] & UNUSABLE).any() and not (ef[:10, 33] & UNUSABLE).any()
    assert not (ef[40] & FAULT["dead"]).any()
    # walk: the dead row, and the half-dead column as weak; nothing else
    assert (wf[40] & FAULT["dead"]).all()
    assert (wf[:, 20] & FAULT["weak"]).mean() > 0.9
    dead_lines = [(lf["axis"], lf.get("index")) for lf in w.numbers["line_faults"] if lf["kind"] == "dead"]
    assert dead_lines == [("row", 40)]
    assert [lf["index"] for lf in w.numbers["line_faults"] if lf["kind"] == "weak"] == [20]
    assert w.numbers["coverage_fraction"] > 0.85


def test_dead_mux_bank_of_16_lines():
    s, e, w = run(FaultConfig(mux_banks=(MuxBankFault("row", 16, 16),)), seed=8, grid=48)
    banks = [lf for lf in w.numbers["line_faults"] if lf["kind"] == "mux_bank"]
    assert banks == [{"kind": "mux_bank", "axis": "row", "start": 16, "size": 16, "found_by": "walk"}]
    assert (w.arrays["fault"][16:32] & FAULT["dead"]).all()
    assert not (w.arrays["fault"][:16] & FAULT["dead"]).any() and not (w.arrays["fault"][32:] & FAULT["dead"]).any()
    assert any("multiplexer bank" in f for f in w.findings)


def test_flipped_sign_carpet_works_and_a_board_reporting_the_wrong_sign_is_refused():
    s, e, w = run(FaultConfig(), seed=9, sign=-1, grid=48)
    assert w.ok and w.numbers["measured_sign"] == -1
    # the same carpet behind a board whose INFO claims +1
    a = Actor(s, t_s=1000.0)
    a.device["sign"] = +1
    e2 = empty_capture(a.empty())
    walk = a.walk()
    w2 = coverage_walk(walk, e2.arrays["baseline_counts"], e2.arrays["noise_counts"], e2.arrays["fault"])
    assert not w2.ok and not w2.retry
    assert "sign +1" in w2.findings[-1] and "sign -1" in w2.findings[-1]


def test_a_walk_with_nobody_walking_is_refused():
    s = CarpetSensor.random(2, grid=32, faults=False)
    a = Actor(s)
    e = empty_capture(a.empty())
    w = coverage_walk(a.empty(seconds=20), e.arrays["baseline_counts"], e.arrays["noise_counts"], e.arrays["fault"])
    assert not w.ok and "walking" in w.findings[-1]
