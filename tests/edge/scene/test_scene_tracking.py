"""Tracking: simulated 2- and 3-person walks against ground truth, people close on the same rows,
stepping out and back, stillness, and bad frames in the middle of a scene."""

import numpy as np
import pytest
from scene_worlds import footstep_scene, noisy, render

from edge.scene import SceneConfig, SceneTracker, score_tracking

PITCH = 0.01905
# FootstepCarpet walkers that start closer than 0.6 m never move (its avoidance rule
# blocks every step), so these seeds start them apart and they really walk.
SCENES = [(2, 1), (2, 4), (3, 24), (3, 20)]


@pytest.mark.parametrize("people, seed", SCENES)
def test_walking_scenes_few_switches_and_misses(people, seed):
    st = SceneTracker(96, 96, PITCH)
    truth, reported = [], []
    for t_s, p, true in footstep_scene(people, seed, frames=280, salt=5):
        out = st.update(p, t_s)
        truth.append(true)
        reported.append({q.track_id: q.cop_m for q in out.people})
    score = score_tracking(truth, reported, gate_m=0.5)
    assert score.id_switches <= 3
    assert score.missed_fraction < 0.03  # the birth delay alone is 2 frames per person
    assert score.false_positives <= 0.01 * score.true_people
    assert score.mean_error_m < 0.12


def _walk(x0, y0, vx, t_s, mass_kg, speed=1.0):
    return {"centre_m": (x0 + vx * t_s, y0), "heading_rad": 0.0 if vx >= 0 else np.pi, "mass_kg": mass_kg,
            "phase": (t_s * speed / 1.1) % 1.0}


def test_people_approaching_on_the_same_rows_keep_their_ids():
    st = SceneTracker(96, 96, PITCH, SceneConfig(noise_kpa=0.05))
    rng = np.random.default_rng(0)
    ids_seen = []
    for i in range(40):
        t = i / 14
        a = _walk(0.2, 0.9, min(0.35, 0.5 * t) / max(t, 1e-9) if t else 0.5, t, 70)  # walks right, stops at 0.55 m
        b = _walk(1.6, 0.9, -min(0.45, 0.5 * t) / max(t, 1e-9) if t else -0.5, t, 80)  # walks left, stops at 1.15 m
        out = st.update(noisy(render(96, 96, PITCH, [a, b]), rng), t)
        if i >= 3:
            assert len(out.people) == 2, i
            ids_seen.append(tuple(q.track_id for q in sorted(out.people, key=lambda q: q.cop_m[0])))
    assert set(ids_seen) == {ids_seen[0]}
    left, right = sorted(out.people, key=lambda q: q.cop_m[0])
    assert abs(left.force_n - 70 * 9.81) < 0.1 * 70 * 9.81 and abs(right.force_n - 80 * 9.81) < 0.1 * 80 * 9.81


def _step_out_scene(config):
    st = SceneTracker(96, 96, PITCH, config)
    rng = np.random.default_rng(1)
    stay = {"centre_m": (1.3, 1.3), "heading_rad": 0.0, "mass_kg": 75}
    log = []
    for i in range(100):
        t = i / 14
        people = [stay]
        if not 2.0 <= t < 4.0:  # off the carpet for 2 s, back near where they left
            people.append({"centre_m": (0.3, 0.4), "heading_rad": 1.0, "mass_kg": 60})
        out = st.update(noisy(render(96, 96, PITCH, people), rng), t)
        log.append({q.track_id: q.cop_m for q in out.people})
    return log, out


def test_stepping_out_and_back_in():
    log, out = _step_out_scene(SceneConfig(noise_kpa=0.05))
    ids_before, ids_away, ids_after = log[20], log[40], log[-1]
    assert len(ids_before) == 2 and len(ids_away) == 1 and len(ids_after) == 2
    assert ids_before.keys() == ids_after.keys()  # re-identified
    assert out.counters["reidentified"] == 1 and out.counters["tracks_lost"] == 1
    log, out = _step_out_scene(SceneConfig(noise_kpa=0.05, reid_s=0))
    assert len(log[-1]) == 2 and log[20].keys() != log[-1].keys()  # without re-id: a new id


def test_stillness_flag():
    st = SceneTracker(96, 96, PITCH, SceneConfig(noise_kpa=0.05))
    rng = np.random.default_rng(2)
    person = {"centre_m": (0.9, 0.9), "heading_rad": 0.0, "mass_kg": 70}
    flags = []
    for i in range(30):
        moved = dict(person, centre_m=(0.9 + (0.05 if i >= 20 else 0.0), 0.9))
        out = st.update(noisy(render(96, 96, PITCH, [moved]), rng), i / 14)
        flags.append(out.people[0].still if out.people else None)
    assert all(flags[4:20]) and flags[20] is False and all(flags[24:])  # the EMA settles in ~3 frames
    assert out.still and out.counters["still"] >= 20


def test_bad_frames_mid_scene_are_counted_and_tracks_survive():
    st = SceneTracker(96, 96, PITCH, SceneConfig(noise_kpa=0.05))
    rng = np.random.default_rng(3)
    person = {"centre_m": (0.9, 0.9), "heading_rad": 0.0, "mass_kg": 70}
    bad = 0
    for i in range(60):
        p = noisy(render(96, 96, PITCH, [person]), rng)
        if i % 5 == 4:
            p = p.copy()
            p[rng.integers(0, 96, 500), rng.integers(0, 96, 500)] = [np.nan, np.inf, 1e12, -1e12][i % 4]
            bad += 1
        out = st.update(p, i / 14)
        if out.valid and i > 3:
            assert [q.track_id for q in out.people] == [1]
    assert out.counters["valid"] == 60 - bad
    assert out.counters["rejected_non_finite"] + out.counters["rejected_out_of_range"] == bad
