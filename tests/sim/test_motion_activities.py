"""sim.motion: every activity on the floor, feet locked, contacts present, scenes apart."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from edge.body import BodyModel
from sim.motion import ACTIVITIES, CONTACT_PARTS, Subject, Track, person_track, scene
from sim.motion.posture import SACRUM_DROP_M
from sim.motion.rig import LOCK_JOINT, Rig

RATE = 14.0
SECONDS = 8.0
MODEL = BodyModel.load("lite")



@pytest.fixture(scope="module")
def tracks() -> dict[str, tuple[Track, dict]]:
    out = {}
    for k, name in enumerate(a for a in ACTIVITIES if a != "standing"):
        tr = person_track(Subject.random(10 + k), [name], SECONDS, RATE, rng=k, model=MODEL, extend=True)  # as datasets make them
        res = MODEL.forward(tr.pose_aa, tr.betas, tr.transl_m, vertices=True)
        out[name] = (tr, res)
    return out


NAMES = [a for a in ACTIVITIES if a != "standing"]


def span_drift(track: Track, joints: np.ndarray, part: int) -> float:
    """Largest horizontal distance a locked point moves from where its contact span began (it may
    rise: a foot rolling from its heel onto its sole lowers its ball onto the floor)."""
    c = track.contact[:, part]
    pts = joints[:, LOCK_JOINT[part]]
    worst, start = 0.0, None
    for t in range(len(c)):
        if c[t] and (t == 0 or not c[t - 1]):
            start = pts[t]
        if c[t]:
            worst = max(worst, float(np.linalg.norm(pts[t, :2] - start[:2])))
    return worst


@pytest.mark.parametrize("name", NAMES)
def test_rate_length_finite_and_labels(tracks, name):
    tr, _ = tracks[name]
    n = len(tr)
    assert n >= int(round(SECONDS * RATE)) and tr.pose_aa.shape == (n, 72) and tr.transl_m.shape == (n, 3)
    assert tr.tempo is not None and 0.9 <= tr.tempo[0]  # given the time it needs, never squeezed
    assert tr.rate_hz == RATE and tr.contact.shape == (n, len(CONTACT_PARTS))
    assert np.isfinite(tr.pose_aa).all() and np.isfinite(tr.transl_m).all()
    labels = set(tr.activity_names)
    assert name in labels and labels <= {name, "standing"}
    assert (tr.activity == ACTIVITIES.index(name)).mean() > 0.6


@pytest.mark.parametrize("name", NAMES)
def test_nothing_below_floor_and_something_on_it(tracks, name):
    _, res = tracks[name]
    assert res["joints"][..., 2].min() > -0.01
    low = res["vertices"][..., 2].min(1)
    assert low.min() > -0.01
    assert low.max() < 0.01  # never floating: the lowest vertex touches the floor every frame


@pytest.mark.parametrize("name", NAMES)
def test_scheduled_contacts_touch_the_floor(tracks, name):
    tr, res = tracks[name]
    rig = Rig(MODEL, tr.betas)
    v = res["vertices"]
    for p in range(len(CONTACT_PARTS)):
        on = tr.contact[:, p]
        if on.any():
            low = v[on][:, rig.part_vertices[p], 2].min(1)
            # Supine, the heavy pelvis sinks deeper into its soft tissue than the back (posture.SACRUM_DROP_M):
            # the back's rigid surface may stay up to that much higher; the contact physics loads both.
            limit = 0.015 + (SACRUM_DROP_M if CONTACT_PARTS[p] == "back" else 0.0)
            assert low.max() < limit, f"{CONTACT_PARTS[p]} scheduled on the floor but {low.max() * 100:.1f} cm up"


@pytest.mark.parametrize("name", NAMES)
def test_stance_feet_and_hands_do_not_slide(tracks, name):
    tr, res = tracks[name]
    drift = max(span_drift(tr, res["joints"], p) for p in range(4))
    assert drift < 0.01, f"{name}: a locked foot/hand moved {drift * 100:.1f} cm"


def test_push_up_hands_on_floor(tracks):
    idx = {n: i for i, n in enumerate(CONTACT_PARTS)}
    tr, res = tracks["push_up"]
    hands = tr.contact[:, idx["left_hand"]] & tr.contact[:, idx["right_hand"]]
    assert hands.sum() > 20
    wrists = res["joints"][hands][:, [20, 21], 2]
    assert wrists.max() < 0.12  # wrists just above the floor


def test_expected_contacts(tracks):
    idx = {n: i for i, n in enumerate(CONTACT_PARTS)}
    tr, res = tracks["sitting"]
    sit = tr.contact[:, idx["buttocks"]]
    assert sit.sum() > 14 and res["joints"][sit, 0, 2].max() < 0.2  # pelvis low, a second or more (8 s: a paced sit-down and up take ~6)
    assert (tr.contact[sit][:, [idx["left_foot"], idx["right_foot"]]]).all()
    tr, res = tracks["sit_up"]
    lying = tr.contact[:, idx["back"]]
    assert lying.sum() > 5 and res["joints"][lying][:, 3, 2].max() < 0.2  # lower spine on the floor
    tr, res = tracks["lunge"]
    both = tr.contact[:, 0] & tr.contact[:, 1]
    pelvis = res["joints"][both, 0, 2]
    assert pelvis.max() - pelvis.min() > 0.12  # down with both feet planted (depth follows the person: 0.16–0.37 m over 12 subjects)


def test_determinism():
    a = person_track(Subject.random(5), ["squat", "walking"], 4.0, RATE, rng=9, model=MODEL)
    b = person_track(Subject.random(5), ["squat", "walking"], 4.0, RATE, rng=9, model=MODEL)
    c = person_track(Subject.random(5), ["squat", "walking"], 4.0, RATE, rng=10, model=MODEL)
    assert np.array_equal(a.pose_aa, b.pose_aa) and np.array_equal(a.transl_m, b.transl_m)
    assert not np.array_equal(a.transl_m, c.transl_m)


def test_subject_random_is_seeded_and_in_range():
    s = Subject.random(7)
    assert np.array_equal(s.betas, Subject.random(7).betas)
    assert np.abs(s.betas).max() <= 3.0
    assert not np.array_equal(s.betas, Subject.random(8).betas)


def test_upright_faces_minus_y_and_unknown_activity_refused():
    tr = person_track(Subject.random(1), ["standing"], 2.0, RATE, rng=0, model=MODEL)
    res = MODEL.forward(tr.pose_aa[:1], tr.betas, tr.transl_m[:1])
    j = res["joints"][0]
    assert j[15, 2] > j[0, 2] + 0.4  # head above pelvis
    with pytest.raises(ValueError):
        person_track(Subject.random(1), ["juggling"], 2.0, RATE, model=MODEL)


@pytest.mark.parametrize("people, names, gap", [
    (2, ["stepping", "squat", "walking", "twisting"], 0.15),
    (3, ["standing", "stepping", "squat"], 0.10),
])
def test_scene_people_apart_and_on_carpet(people, names, gap):
    from scipy.spatial import cKDTree

    subs = [Subject.random(i) for i in range(people)]
    sc = scene(subs, names, 3.0, RATE, (1.83, 1.83), rng=people, min_gap_m=gap, model=MODEL)
    assert len(sc.tracks) == people and sc.rate_hz == RATE
    n = sc.num_frames
    assert n == len(names) * 42 and all(len(t) == n for t in sc.tracks)
    verts = []
    for t in sc.tracks:
        v = MODEL.forward(t.pose_aa, t.betas, t.transl_m, vertices=True)["vertices"]
        assert v[..., 0].min() >= 0 and v[..., 1].min() >= 0
        assert v[..., 0].max() <= 1.83 and v[..., 1].max() <= 1.83
        assert v[..., 2].min() > -0.01
        verts.append(v[..., :2])
    for i in range(people):
        for k in range(i + 1, people):
            closest = min(cKDTree(verts[i][f]).query(verts[k][f])[0].min() for f in range(n))
            assert closest > gap - 0.03, f"people {i} and {k} come {closest * 100:.1f} cm close"  # raster of every other vertex


def test_scene_refuses_impossible():
    with pytest.raises(ValueError):
        scene([Subject.random(i) for i in range(3)], ["push_up"], 3.0, RATE, (1.0, 1.0), rng=0, tries=6, model=MODEL)


def test_sit_up_trunk_rises_and_lies_down_without_a_dip():
    """Around a sit-up's lying span the root keeps the lying correction (sim.motion.posture.rest_on_back) and
    lets it fade over the curl: the trunk's elevation rises steadily as the back leaves the floor
    and falls steadily as it lands. Before, the correction was refitted to the rising back and
    faded in four frames: the trunk dipped back ~9° in one frame (a 1 cm pelvis jump)."""
    back = CONTACT_PARTS.index("back")
    for s in range(3):
        tr = person_track(Subject.random(100 + s, 100 + s), ["sit_up"], 12.0, RATE, rng=np.random.default_rng((0, s)),
                          model=MODEL)
        elevation = np.degrees(np.arcsin(Rotation.from_rotvec(tr.pose_aa[:, :3]).as_matrix()[:, 2, 1]))
        c = tr.contact[:, back]
        leaves, lands = np.flatnonzero(c[:-1] & ~c[1:]), np.flatnonzero(~c[:-1] & c[1:])
        assert len(leaves) and len(lands)
        for e in leaves:
            assert np.diff(elevation[e:e + 8]).min() > -1.0
        for b in lands:
            assert np.diff(elevation[max(b - 7, 0):b + 2]).max() < 1.0


def test_each_activity_reports_how_much_its_keys_were_squeezed():
    """Track.tempo says, per activity, how long its keys last against the subject's own durations: a sit-up
    (getting down, a repetition, getting up) squeezed alone into 8 s runs well under 1; in a sequence it takes
    the time it needs from activities with time to spare; extend gives it that time alone; an upright
    activity that fits stretches by at most MAX_STRETCH."""
    from sim.motion.activities import MAX_STRETCH

    subject = Subject.random(3)
    alone = person_track(subject, ["sit_up"], 8.0, RATE, rng=1, model=MODEL)
    shared = person_track(subject, ["sit_up", "squat", "bending"], 11.0, RATE, rng=1, model=MODEL)
    extended = person_track(subject, ["sit_up"], 8.0, RATE, rng=1, model=MODEL, extend=True)
    assert alone.tempo is not None and alone.tempo.shape == (1,) and len(alone) == round(8.0 * RATE)
    assert alone.tempo[0] < 0.8
    assert len(shared) == 3 * round(11.0 * RATE)  # the sequence keeps its length; the sit-up takes from the others
    assert shared.tempo is not None and 0.9 <= shared.tempo.min() and shared.tempo.max() <= MAX_STRETCH + 1e-9
    sit_up = ACTIVITIES.index("sit_up")
    assert (shared.activity == sit_up).sum() > round(11.0 * RATE)
    assert extended.tempo is not None and 0.9 <= extended.tempo[0] <= MAX_STRETCH + 1e-9 and len(extended) > len(alone)
    exact = person_track(subject, ["sit_up", "squat"], 8.0, RATE, rng=1, model=MODEL, total_s=30.0)
    assert len(exact) == round(30.0 * RATE)


def test_an_extended_scene_gives_everyone_the_longest_need():
    """scene(extend=True): the sitter needs ~10 s to sit down, sit and get up at their own pace; the person
    stepping beside them is given as long (their steps and pauses fill it), so both tracks are equal."""
    sc = scene([Subject.random(21), Subject.random(22)], [["sitting"], ["stepping"]], 4.0, RATE, rng=3, model=MODEL,
               extend=True)
    a, b = sc.tracks
    assert len(a) == len(b) == sc.num_frames > 8 * RATE
    assert a.tempo is not None and b.tempo is not None and a.tempo[0] >= 0.9 and b.tempo[0] >= 0.9
    assert (b.activity == ACTIVITIES.index("stepping")).sum() > 4 * RATE
