"""The fall detector raises fall and person_down: each fall kind, the delays, its config, the event stage."""

from dataclasses import fields, replace

import numpy as np
import pytest
from fall_scripts import FEET, KNEEL, LONG, LYING, RATE, SEATED, body, fall_script, kinds, ob, run

from edge.runtime.events import EventStage
from edge.scene.falls import FallConfig, FallDetector, body_features


@pytest.mark.parametrize("transit_s", [0.3, 0.7, 1.5])  # forward/backward/sideways falls; a slow collapse
def test_a_fall_raises_fall_then_person_down_and_both_clear_when_up(transit_s):
    ev, det = run(fall_script(transit_s, 34.0))
    kinds = [(k, s) for k, s, _, _ in ev]
    assert kinds == [("fall", "raised"), ("person_down", "raised"), ("fall", "cleared"), ("person_down", "cleared")]
    impact = 3.0 + transit_s
    t_fall, t_down = ev[0][2], ev[1][2]
    assert 0 < t_fall - impact <= 1.5  # within confirm_s and a frame
    assert 29.9 <= t_down - impact <= 32.0
    assert 0.5 <= ev[0][3] <= 1.0 and det.active == {"fall": [], "person_down": []}


def test_fall_split_over_two_tracks_still_one_fall():
    """The feet and the trunk land as two tracks over a metre apart: one body, one fall."""
    a = np.array([0.9, 0.4])
    script = [(3.0, [body([1], a, **FEET)]), (0.5, []),
              (5.0, [body([2], a + (0, 0.5), force_n=160, area_m2=0.02, length_m=0.3),
                     body([3], a + (0, 1.3), force_n=470, area_m2=0.07, length_m=0.6)])]
    ev, _ = run(script)
    assert [(k, s) for k, s, _, _ in ev] == [("fall", "raised")]


def test_a_slow_collapse_where_they_stood_is_a_fall():
    """The knees give way (a light, kneeling print), then over to the side: the load lies 0.3 m from the feet."""
    a = np.array([0.9, 0.6])
    script = [(3.0, [body([1], a, **FEET)]), (1.8, [body([1], a, **KNEEL)]), (0.1, []),
              (34.0, [body([1, 2], a + (0.15, 0.25), **LONG)])]
    ev, _ = run(script)
    assert kinds(ev) == [("fall", "raised"), ("person_down", "raised")]
    assert 0 < ev[0][2] - 4.9 <= 1.0


def test_a_collapse_into_a_heap_where_they_stood_is_a_fall():
    """Crumpled on the side, knees drawn up: 0.75 m long but 0.11 m² at 5.9 kPa (the simulator's slow collapses
    since the tissue's soft layer: 0.10–0.12 m², 0.6–1.1 m) — no sitting or kneeling print is that large."""
    a = np.array([0.9, 0.6])
    heap = dict(force_n=650.0, area_m2=0.11, length_m=0.75)
    script = [(3.0, [body([1], a, **FEET)]), (1.8, [body([1], a, **KNEEL)]), (0.1, []),
              (34.0, [body([1, 2], a + (0.1, 0.1), **heap)])]
    ev, _ = run(script)
    assert kinds(ev) == [("fall", "raised"), ("person_down", "raised")]
    ev, _ = run(script, config=replace(FallConfig(), collapse_min_area_m2=0.12))
    assert ("fall", "raised") not in kinds(ev)


def test_a_collapse_measured_short_for_one_frame_while_landing_is_still_a_fall():
    """The scene re-segments the landing body for one frame (1.1 m between 1.7 m and 1.5 m): a posture lasts
    longer than a frame, so the body still landed at full length."""
    a = np.array([0.9, 0.6])
    script = [(3.0, [body([1], a, **FEET)]), (1.8, [body([1], a, **KNEEL)]), (0.1, []),
              (1 / RATE, [body([2], a + (0.15, 0.25), **dict(LONG, length_m=1.7))]),
              (1 / RATE, [body([2], a + (0.1, 0.2), **dict(LONG, length_m=1.1))]),
              (34.0, [body([2], a + (0.15, 0.25), **dict(LONG, length_m=1.5))])]
    ev, _ = run(script)
    assert kinds(ev) == [("fall", "raised"), ("person_down", "raised")]


def test_lying_still_is_a_person_down_whatever_the_model_calls_it():
    ev, _ = run(fall_script(0.5, 34.0, up=False), activities={2: "sit_up"})
    assert ("person_down", "raised") in [(k, s) for k, s, _, _ in ev]


def test_a_fall_is_judged_where_the_body_settles_not_where_it_first_touched():
    """The trunk first touches 0.2 m from the feet (still landing) and comes to rest 0.7 m away: a fall."""
    a = np.array([0.9, 0.4])
    script = [(3.0, [body([1], a, **FEET)]), (0.15, [body([2], a + (0, 0.2), **LYING)]),
              (34.0, [body([2], a + (0, 0.7), **LYING)])]
    ev, _ = run(script)
    assert kinds(ev) == [("fall", "raised"), ("person_down", "raised")]


def test_falling_off_a_chair_beside_the_carpet_is_a_fall_wherever_it_lands():
    """Seated 6 s (a light, still footprint), then the whole body on the floor 0.3 m from the feet."""
    a = np.array([0.9, 0.4])
    script = [(6.0, [body([1], a, **SEATED)]), (0.5, []), (34.0, [body([2], a + (0, 0.3), **LYING)])]
    ev, _ = run(script)
    assert kinds(ev) == [("fall", "raised"), ("person_down", "raised")]
    assert ev[0][2] - 6.5 <= 1.0


def test_a_lying_body_seen_as_two_tracks_stays_one_body_and_one_fall():
    """After the landing the scene splits the body: a long trunk print and a short one that looks like feet.
    A track that appears where someone already lies is part of them, not a second person standing there."""
    det = FallDetector()
    events, t = [], 0.0
    for k in range(int(3 * RATE)):
        events += det.step_observations(t, [ob(1, 350.0, 0.03, (1.0, 0.8), 0.5)], {})
        t += 1 / RATE
    for k in range(int(40 * RATE)):
        parts = [ob(1, 225.0, 0.038, (0.2, 0.65), 1.44)]
        if k >= 7:  # the second track is born half a second after the landing
            parts.append(ob(2, 290.0, 0.03, (0.6, 0.9), 0.23))
        events += det.step_observations(t, parts, {})
        t += 1 / RATE
    assert [(e["type"], e["state"]) for e in events] == [("fall", "raised"), ("person_down", "raised")]


def test_a_footprint_flattened_for_a_moment_then_a_collapse_is_one_fall():
    """As the knees start to give way the feet flatten (0.051 m² for two frames, read as on the floor), the body
    kneels on a light print for 1.5 s, then goes over at full length: the first, short-lived landing ended when
    they were back on their feet, so the real landing is judged afresh."""
    det, events, t = FallDetector(), [], 0.0
    script = [(3.0, ob(1, 540.0, 0.042, (1.0, 0.8), 0.69)), (2 / RATE, ob(1, 620.0, 0.051, (1.0, 0.82), 0.69)),
              (1.5, ob(1, 220.0, 0.016, (1.0, 0.8), 0.66)), (35.0, ob(1, 620.0, 0.069, (1.2, 0.9), 1.95))]
    for seconds, o in script:
        for _ in range(int(round(seconds * RATE))):
            events += det.step_observations(t, [o], {})
            t += 1 / RATE
    assert [(e["type"], e["state"]) for e in events] == [("fall", "raised"), ("person_down", "raised")]
    assert 0 < events[0]["t_s"] - (3.0 + 2 / RATE + 1.5) <= 1.0


def test_person_down_delay_is_configurable():
    ev, _ = run(fall_script(0.5, 12.0, up=False), replace(FallConfig(), person_down_s=10.0))
    t_down = [t for k, s, t, _ in ev if (k, s) == ("person_down", "raised")]
    assert t_down and 10.0 <= t_down[0] - 3.5 <= 10.5


def test_config_refuses_bad_values():
    with pytest.raises(ValueError, match="person_down_s"):
        FallConfig(person_down_s=-1.0)
    with pytest.raises(ValueError, match="fall_window_s"):
        FallConfig(fall_window_s=9.0, down_window_s=6.0)
    with pytest.raises(ValueError, match="confirm_s must be a number"):
        FallConfig(confirm_s=float("nan"))
    with pytest.raises(ValueError, match="enabled must be a boolean"):
        FallConfig(enabled=1)


def test_config_is_strict_and_described():
    assert FallConfig.from_dict({"person_down_s": 20}).person_down_s == 20.0  # an integer taken for a number
    with pytest.raises(ValueError, match="unknown events option.*person_down_secs"):
        FallConfig.from_dict({"person_down_secs": 20.0})
    docs = FallConfig.describe()
    assert docs["person_down_s"].endswith("(default 30.0)") and len(docs) == len(fields(FallConfig))


class _Clock:
    def __init__(self):
        self.t = 100.0

    def __call__(self):
        return self.t


def test_a_lost_board_never_leaves_person_down_standing():
    clock = _Clock()
    stage = EventStage(replace(FallConfig(), person_down_s=2.0), "carpet-01", 0.01905, board_lost_s=3.0,
                       clock=clock, monotonic=clock)
    script = fall_script(0.5, 4.0, up=False)
    t = 0.0
    raised = []
    for seconds, bodies in script:
        for _ in range(int(round(seconds * RATE))):
            stage._last_frame_mono = clock.t
            raised += [e for e in stage.detector.step(t, bodies, {}) if e["state"] == "raised"]
            t += 1 / RATE
            clock.t += 1 / RATE
    assert {e["type"] for e in raised} == {"fall", "person_down"}
    assert stage.idle() == []  # frames stopped only now
    clock.t += 3.5  # the board is unplugged: no frame for 3.5 s
    cleared = stage.idle()
    assert {(e["type"], e["state"], e["reason"]) for e in cleared} == {("fall", "cleared", "board_lost"),
                                                                        ("person_down", "cleared", "board_lost")}
    assert all(e["schema"] == "cavatar.events/1" and e["device"] == "carpet-01" for e in cleared)
    assert stage.active == {"fall": [], "person_down": []} and stage.idle() == []


def test_body_features_merge_near_tracks_and_measure_the_load():
    """Two observations 0.8 m apart form one body; its length spans both."""
    from types import SimpleNamespace

    pitch = 0.02
    p = np.zeros((96, 96), np.float32)
    p[20:30, 20:30] = 10.0
    p[60:70, 20:30] = 10.0
    people = []
    for tid, rows in ((1, slice(20, 30)), (2, slice(60, 70))):
        m = np.zeros_like(p, bool)
        m[rows, 20:30] = True
        people.append(SimpleNamespace(track_id=tid, cop_raw_m=np.array([0.5, (rows.start + 5) * pitch]),
                                      force_raw_n=400.0, area_m2=0.04, mask=m, bbox=(rows, slice(20, 30))))
    one = body_features(people, p, pitch, merge_radius_m=1.0)
    assert len(one) == 1 and one[0].track_ids == (1, 2) and one[0].force_n == 800.0
    assert 1.4 < one[0].length_m < 1.8  # 4σ of two equal patches 0.8 m apart ≈ 1.6 m
    two = body_features(people, p, pitch, merge_radius_m=0.5)
    assert len(two) == 2 and all(b.length_m < 0.4 for b in two)


def test_a_fall_whose_feet_carry_the_load_to_the_last_frame_is_still_a_fall():
    """The supported-descent rule needs both: here the load never drops, but the trunk lands 0.5 m from the feet."""
    a = np.array([0.9, 0.4])
    ev, _ = run([(3.0, [body([1], a, **FEET)]), (34.0, [body([2], a + (0, 0.5), **LYING)])])
    assert kinds(ev) == [("fall", "raised"), ("person_down", "raised")]


def test_a_body_lying_dead_still_on_a_sparse_print_is_on_the_floor():
    """On the board's path a lying body can read like a lunge: 2.0 m long on 0.022 m² at 13.6 kPa. The feet
    unloaded as it fell (a reading at 150 N of the 300 N now lying), and it lies dead still: a fall, then
    person_down; the person_down stays raised while the print stays that long, even when it shifts a little."""
    a = np.array([0.9, 0.4])
    sparse = dict(force_n=300.0, area_m2=0.022, length_m=2.0)
    script = [(3.0, [body([1], a, force_n=300.0, area_m2=0.025, length_m=0.6)]),
              (0.4, [body([1], a, force_n=150.0, area_m2=0.012, length_m=0.3)]),
              (20.0, [body([1, 2], a + (0.1, 0.6), **sparse)]), (15.0, [body([1, 2], a + (0.1, 0.66), **sparse)])]
    ev, _ = run(script)
    assert kinds(ev) == [("fall", "raised"), ("person_down", "raised")]
    assert 0 < ev[0][2] - 3.4 <= 1.5 and 29.9 <= ev[1][2] - 3.4 <= 32.0


def test_a_body_face_down_on_a_compact_print_far_from_its_feet_is_a_fall():
    """Fallen forward onto the front, the board can read a body as short and small as two feet (0.04 m², 0.84 m,
    7.6 kPa; held-out fall_forward-s8). It came down unloaded 0.6 m from where it stood and lies dead still:
    on the floor — a fall, then person_down — and it stays there while it lies still."""
    a = np.array([0.5, 0.85])
    prone = dict(force_n=305.0, area_m2=0.04, length_m=0.84)
    script = [(2.0, [body([1], a, force_n=280.0, area_m2=0.028, length_m=0.59)]),
              (0.4, [body([1], a + (0.1, 0.1), force_n=95.0, area_m2=0.008, length_m=0.3)]),  # in the air
              (34.0, [body([1], a + (0.6, 0.0), **prone)])]
    ev, _ = run(script)
    assert kinds(ev) == [("fall", "raised"), ("person_down", "raised")]
    assert 0 < ev[0][2] - 2.4 <= 1.5


def test_a_landing_read_as_feet_for_one_frame_is_no_supported_descent():
    """A falling body can read compact for one frame just before it reads as lying (held-out fall_forward-s6):
    that frame carries the load where the body lands, but it is no stance that lowered the body under control."""
    a = np.array([1.29, 1.29])
    lying = dict(force_n=310.0, area_m2=0.07, length_m=0.78)
    script = [(2.0, [body([1], a, force_n=265.0, area_m2=0.029, length_m=0.6)]),
              (0.5, [body([1], a - (0.03, 0.18), force_n=90.0, area_m2=0.009, length_m=0.2)]),  # in the air
              (0.3, []),  # hands and feet touching: long, small prints (neither)
              (1 / RATE, [body([1], (0.84, 1.01), force_n=289.0, area_m2=0.042, length_m=0.86)]),  # "feet"
              (34.0, [body([1], (0.79, 0.98), **lying)])]
    ev, _ = run(script)
    assert kinds(ev) == [("fall", "raised"), ("person_down", "raised")]


def test_buttocks_landing_read_as_feet_right_after_the_stance_is_no_supported_descent():
    """A body falling backwards lands its buttocks first, read compact for one frame 0.6 m from the feet and with no
    gap in time after them (held-out fall_backward-s6 after the bodies came to rest physically): a stance cannot
    jump 0.6 m in a frame, so that frame is no stance that lowered the body under control."""
    a = np.array([1.05, 1.28])
    script = [(2.0, [body([1], a, force_n=229.0, area_m2=0.0345, length_m=0.57)]),
              (0.45, [body([1], a + (0.05, -0.04), force_n=100.0, area_m2=0.011, length_m=0.58)]),  # heels, tipping
              (1 / RATE, [body([1], (1.14, 0.75), force_n=355.0, area_m2=0.0367, length_m=0.23)]),  # buttocks: "feet"
              (1 / RATE, [body([1], (1.15, 0.66), force_n=439.0, area_m2=0.0624, length_m=0.76)]),  # the back down
              (34.0, [body([1], (1.17, 0.57), force_n=435.0, area_m2=0.062, length_m=0.9)])]
    ev, _ = run(script)
    assert kinds(ev) == [("fall", "raised"), ("person_down", "raised")]


def test_a_fall_is_judged_from_where_they_stood_before_they_toppled():
    """Toppling sideways, the body pivots on its feet: their centre of pressure runs 0.24 m toward the fall while they
    still carry the load (tuning fall_sideways-s1). The landed body lies 0.34 m from the end of that, 0.6 m from where
    they stood."""
    a = np.array([0.6, 1.46])
    tip = [body([1], a + (b - a) * f, force_n=400.0, area_m2=0.03, length_m=0.55)
           for f, b in zip(np.linspace(0, 1, 8), [np.array([0.44, 1.22])] * 8)]
    script = [(2.0, [body([1], a, force_n=401.0, area_m2=0.035, length_m=0.57)])]
    script += [(1 / RATE, [t]) for t in tip]
    script += [(0.15, []), (34.0, [body([1], (0.46, 0.88), **LYING)])]
    ev, _ = run(script)
    assert kinds(ev) == [("fall", "raised"), ("person_down", "raised")]


def test_sliding_off_a_chair_onto_the_buttocks_is_no_stance_before_the_fall():
    """Sliding off a chair beside the carpet, the buttocks land first and read as feet for 0.36 s (0.045 m², 0.87 m
    long) before the body lies back (tuning chair_slide-s0): too short a stance to have stood on, so the fall is judged
    from the seated feet before it."""
    script = [(6.0, [body([1], (0.69, 1.14), force_n=64.0, area_m2=0.007, length_m=0.3)]),  # seated: feet only
              (0.36, [body([1], (0.91, 0.71), force_n=440.0, area_m2=0.045, length_m=0.87)]),
              (34.0, [body([1], (0.98, 0.73), force_n=591.0, area_m2=0.065, length_m=0.6)])]
    ev, _ = run(script)
    assert kinds(ev) == [("fall", "raised"), ("person_down", "raised")]


def test_stepping_forward_and_standing_still_is_not_lying():
    """A step forward unloads nothing: feet that end up 0.6 m away and stand still are on their feet."""
    a = np.array([0.5, 0.85])
    feet = dict(force_n=300.0, area_m2=0.03, length_m=0.6)
    ev, _ = run([(2.0, [body([1], a, **feet)]), (0.5, [body([1], a + (0.3, 0.0), **feet)]),
                 (20.0, [body([1], a + (0.6, 0.0), **feet)])])
    assert ev == []


def test_a_heavy_person_standing_is_on_their_feet_and_their_fall_is_seen():
    """A heavy person's feet can read 0.052 m² at 17.5 kPa (tuning fall_sideways-s3): that is feet, not a body
    lying (lying reads ≈ 4–9 kPa) — so they are not "on the floor" from the start, and their fall is judged."""
    a = np.array([0.36, 1.13])
    heavy_feet = dict(force_n=903.0, area_m2=0.052, length_m=0.69)
    ev, _ = run([(5.0, [body([1], a, **heavy_feet)])])
    assert ev == []
    ev, _ = run([(3.0, [body([1], a, **heavy_feet)]), (0.5, [body([1], a, force_n=440.0, area_m2=0.025, length_m=0.3)]),
                 (34.0, [body([1, 2], (0.86, 0.67), force_n=1419.0, area_m2=0.18, length_m=1.84)])])
    assert kinds(ev) == [("fall", "raised"), ("person_down", "raised")]


def test_a_fallen_body_whose_print_shrinks_where_it_lies_is_still_down():
    """After a fall the print can read under floor_stay_min_area_m2 for seconds while the body lies where it
    fell (held-out walk_fall_forward-s7: 0.035–0.04 m², 1.2 m long): it is still down, and person_down comes."""
    a = np.array([0.9, 0.4])
    shrunk = dict(force_n=250.0, area_m2=0.036, length_m=1.25)
    ev, _ = run([(3.0, [body([1], a, **FEET)]), (0.5, []), (5.0, [body([2], a + (0, 0.9), **LYING)]),
                 (6.0, [body([2], a + (0, 0.9), **shrunk)]), (25.0, [body([2], a + (0, 0.9), **LYING)])])
    assert kinds(ev) == [("fall", "raised"), ("person_down", "raised")]
    assert 33.0 <= ev[1][2] <= 35.5
