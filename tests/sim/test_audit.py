"""`cavatar sim audit`: the fidelity report measures the generator's own output and flags what is out of range."""


import numpy as np

from edge.body import BodyModel
from edge.cli import main
from sim.audit import markdown, run_audit
from sim.audit.checks import _check
from sim.audit.measure import REGIONS, _hull_distance, contact_area, vertex_regions


def test_a_check_is_in_range_only_inside_its_bounds():
    assert _check("x", "x", 50, "%", 40, 60, "s")["ok"]
    assert not _check("x", "x", 39.9, "%", 40, 60, "s")["ok"]
    assert not _check("x", "x", float("nan"), "%", 40, 60, "s")["ok"]  # nothing measured is not a pass


def test_hull_distance_is_negative_inside_and_the_gap_outside():
    square = np.array([[0, 0], [1, 0], [1, 1], [0, 1]], float)
    assert _hull_distance(square, np.array([0.5, 0.5])) < 0
    assert abs(_hull_distance(square, np.array([1.2, 0.5])) - 0.2) < 1e-9


def test_vertex_regions_put_the_feet_at_the_bottom_and_the_back_above_the_buttocks():
    body = BodyModel.load("lite")
    reg = vertex_regions(body)
    y = body.arrays.v_template[:, 1]  # canonical: Y up
    for name in ("left_foot", "right_foot"):
        assert y[reg == REGIONS.index(name)].max() < y.min() + 0.2
    assert np.median(y[reg == REGIONS.index("back")]) > np.median(y[reg == REGIONS.index("buttocks")])


def test_audit_of_one_activity_writes_its_checks(tmp_path):
    report = run_audit(subjects=1, seconds=6.0, seed=1, activities=("stepping",), spread_subjects=2)
    ids = {c["id"] for c in report["checks"]}
    assert {"force.stepping", "balance.stepping", "toe_off.stepping", "weight_shift.stepping",
            "spread.stepping", "law.airborne", "lying.supine_area", "lying.supine_mean_kpa"} <= ids
    assert "support.stepping" not in ids  # stepping never stands still: nothing to judge, no check
    force = next(c for c in report["checks"] if c["id"] == "force.stepping")
    assert force["value"] is not None and 0 <= force["value"] <= 100
    area = next(c for c in report["checks"] if c["id"] == "lying.supine_area")["value"]
    assert 200 < area < 3000  # cm²: a body lying, not feet and not the carpet
    assert report["summary"]["total"] == len(report["checks"])
    assert markdown(report).count("\n| ") == len(report["checks"]) + 1


def test_contact_area_counts_the_sensels_above_the_contact_threshold():
    p = np.zeros((8, 8))
    p[2:4, 2:5] = 6.0
    p[0, 0] = 0.4  # below 0.5 kPa: not in contact
    area, mean = contact_area(p, 0.02)
    assert abs(area - 6 * 0.02 ** 2) < 1e-12 and mean == 6.0
    assert contact_area(np.zeros((4, 4)), 0.02) == (0.0, 0.0)


def test_cli_audit_refuses_too_short_sequences(tmp_path, capsys):
    assert main(["sim", "audit", "--out", str(tmp_path), "--seconds", "2"]) != 0
    assert "--seconds" in capsys.readouterr().err
    assert not any(tmp_path.iterdir())


def test_a_value_just_outside_its_range_is_not_shown_rounded_into_it():
    report = {"settings": {"subjects": 1, "seconds_per_activity": 8.0, "seed": 0, "spread_subjects": 2},
              "summary": {"in_range": 1, "total": 2},
              "checks": [{"what": "near miss", "value": 98.95, "unit": "%", "range": [99, 100], "ok": False, "source": "s"},
                         {"what": "plain", "value": 63.912, "unit": "%", "range": [50, 75], "ok": True, "source": "s"}]}
    text = markdown(report)
    assert "| near miss | 98.95 % | 99–100 | **no** |" in text
    assert "| plain | 63.9 % | 50–75 | yes |" in text
