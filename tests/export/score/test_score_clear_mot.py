"""CLEAR MOT on hand-made sequences whose misses, extras and switches are known."""

from __future__ import annotations

import pytest

from export.score.clear_mot import clear_mot


def test_perfect_tracking_scores_one():
    frames = [({"a": (0.0, 0.0), "b": (1.0, 0.0)}, {7: (0.05, 0.0), 9: (1.0, 0.1)})] * 5
    r = clear_mot(frames, 0.5)
    assert (r.matches, r.misses, r.extras, r.idsw, r.mota) == (10, 0, 0, 0, 1.0)
    assert r.motp_m == pytest.approx(0.075)


def test_extra_track_and_far_track():
    frames = [({"a": (0.0, 0.0)}, {1: (0.1, 0.0), 2: (0.3, 0.3)}),  # a split: one extra
              ({"a": (0.0, 0.0)}, {1: (0.9, 0.0)})]  # too far: a miss and an extra
    r = clear_mot(frames, 0.5)
    assert (r.matches, r.misses, r.extras, r.idsw) == (1, 1, 2, 0)
    assert r.mota == pytest.approx(1 - 3 / 2)
    assert r.frames[0].extra == [2] and r.frames[1].missed == ["a"]


def test_swapped_ids_count_one_switch_each():
    a, b = (0.0, 0.0), (1.0, 0.0)
    frames = [({"a": a, "b": b}, {1: a, 2: b}), ({"a": a, "b": b}, {2: a, 1: b}), ({"a": a, "b": b}, {2: a, 1: b})]
    r = clear_mot(frames, 0.5)
    assert r.idsw == 2 and r.frames[1].switches == ["a", "b"] and r.frames[2].switches == []


def test_a_kept_pair_is_not_swapped_for_a_nearer_track():
    frames = [({"a": (0.0, 0.0)}, {1: (0.2, 0.0)}), ({"a": (0.0, 0.0)}, {1: (0.2, 0.0), 2: (0.01, 0.0)})]
    r = clear_mot(frames, 0.5)
    assert r.frames[1].pairs[0][1] == 1 and r.frames[1].extra == [2] and r.idsw == 0


def test_reacquired_after_a_gap_with_a_new_id_is_a_switch():
    frames = [({"a": (0.0, 0.0)}, {1: (0.0, 0.0)}), ({"a": (0.0, 0.0)}, {}), ({"a": (0.0, 0.0)}, {5: (0.0, 0.0)})]
    r = clear_mot(frames, 0.5)
    assert (r.misses, r.idsw) == (1, 1)


def test_minimum_total_distance_assignment():
    # greedy nearest-first would pair a with 2 (0.1 m) and leave b unmatched (0.6 m to 1)
    frames = [({"a": (0.0, 0.0), "b": (0.45, 0.0)}, {1: (-0.15, 0.0), 2: (0.1, 0.0)})]
    r = clear_mot(frames, 0.5)
    assert sorted((t, p) for t, p, _ in r.frames[0].pairs) == [("a", 1), ("b", 2)]


def test_bad_threshold_and_empty():
    with pytest.raises(ValueError, match="threshold"):
        clear_mot([], 0.0)
    assert clear_mot([({}, {})], 0.5).mota is None
