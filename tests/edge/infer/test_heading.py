"""edge.infer.heading: the foot-shape cue, the yaw convention, the half turn and the per-track resolver."""

from __future__ import annotations

import json

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from edge.infer import heading
from edge.infer.heading import HeadingParams, HeadingResolver, cue_yaw_rad, frame_cue, turn_half, yaw_rad

PITCH = 0.01905
R0 = Rotation.from_rotvec([np.pi / 2, 0, 0])  # upright, facing −y


def upright(yaw: float) -> np.ndarray:
    """(72,) a pose: upright, yaw ``yaw``, some local pose that must survive untouched."""
    pose = np.linspace(-0.3, 0.3, 72).astype(np.float32)
    pose[:3] = (Rotation.from_rotvec([0, 0, yaw]) * R0).as_rotvec()
    return pose


def feet(toes: str, heel_kpa: float = 10.0, toe_kpa: float = 6.0) -> np.ndarray:
    """(96,96) two parallel feet 13 sensels long (25 cm), 5 wide, heel-heavy (CoP 11 mm behind the centroid),
    toes toward −y ("up") or +y ("down")."""
    p = np.zeros((96, 96), np.float32)
    ramp = np.linspace(toe_kpa, heel_kpa, 13)[:, None]  # row 0 of the foot is its toe
    if toes == "down":
        ramp = ramp[::-1]
    for c0 in (40, 50):
        p[40:53, c0:c0 + 5] = ramp
    return p


def test_yaw_of_an_upright_body_and_the_half_turn():
    for yaw in (0.0, 0.7, -2.0, 3.0):
        pose = upright(yaw)
        assert yaw_rad(pose[:3]) == pytest.approx(yaw, abs=1e-6)
        turned = turn_half(pose)
        assert abs(((yaw_rad(turned[:3]) - yaw - np.pi) + np.pi) % (2 * np.pi) - np.pi) < 1e-5
        np.testing.assert_array_equal(turned[3:], pose[3:])  # the local pose is not touched
        # still upright: the body's up (canonical +y) stays carpet +z
        up = Rotation.from_rotvec(turned[:3]).apply([0, 1, 0])
        np.testing.assert_allclose(up, [0, 0, 1], atol=1e-6)
    assert cue_yaw_rad(np.array([0.0, -1.0])) == pytest.approx(0.0)  # facing −y is yaw 0
    assert cue_yaw_rad(np.array([1.0, 0.0])) == pytest.approx(np.pi / 2)


def test_heel_heavy_feet_point_to_their_toes():
    params = HeadingParams()
    (up, on_feet), (down, _) = frame_cue(feet("up"), PITCH, params), frame_cue(feet("down"), PITCH, params)
    assert on_feet
    assert up[1] < 0 and abs(up[0]) < 1e-6 * abs(up[1]) + 1e-9
    np.testing.assert_allclose(down, -up, atol=1e-9)
    # no cue: uniform blobs (no heel), a round blob, or a seat carrying most of the weight
    flat = feet("up", 8.0, 8.0)
    assert not frame_cue(flat, PITCH, params)[0].any()
    round_blob = np.zeros((96, 96), np.float32)
    round_blob[40:48, 40:48] = np.linspace(4, 12, 8)[:, None]
    assert not frame_cue(round_blob, PITCH, params)[0].any()
    # an extreme offset (22 mm: a forefoot or toes carrying the weight, as in bending) is not a vote
    assert not frame_cue(feet("up", 12.0, 4.0), PITCH, params)[0].any()
    seat = feet("up")
    seat[60:80, 30:60] = 10.0
    cue, on_feet = frame_cue(seat, PITCH, params)
    assert not cue.any() and not on_feet  # the seat carries the weight: not on their feet


def test_the_resolver_turns_a_backwards_body_and_keeps_a_right_one():
    params = HeadingParams(decay=0.9, max_evidence=5.0, min_evidence=0.3)
    right, wrong = HeadingResolver(params), HeadingResolver(params)
    for t in range(10):
        out_right = right.resolve(upright(0.1), feet("up"), PITCH)
        out_wrong = wrong.resolve(upright(0.1 + np.pi), feet("up"), PITCH)
    assert yaw_rad(out_right[:3]) == pytest.approx(0.1, abs=1e-5) and right.flips == 0
    assert yaw_rad(out_wrong[:3]) == pytest.approx(0.1, abs=1e-5) and wrong.flips >= 9
    # the model changes its mind (its yaw jumps 180°) while the feet go quiet: the published yaw stays put
    out = wrong.decide(upright(0.1), np.zeros(2))
    assert yaw_rad(out[:3]) == pytest.approx(0.1, abs=1e-5)
    # and with no cue ever, the model's own answer is published
    fresh = HeadingResolver(params)
    assert yaw_rad(fresh.decide(upright(2.5), np.zeros(2))[:3]) == pytest.approx(2.5, abs=1e-5)


def test_without_evidence_hold_last_keeps_the_published_half_turn():
    for hold, expect in ((1.0, 0.1), (0.0, 0.1 + np.pi)):
        r = HeadingResolver(HeadingParams(decay=0.5, max_evidence=5.0, min_evidence=0.5, hold_last=hold))
        for _ in range(5):
            r.resolve(upright(0.1), feet("up"), PITCH)
        for _ in range(10):  # the feet go quiet, the evidence fades, the model keeps its answer
            out = r.decide(upright(0.1), np.zeros(2))
        out = r.decide(upright(0.1 + np.pi), np.zeros(2))  # … then swings round
        assert abs(((yaw_rad(out[:3]) - expect) + np.pi) % (2 * np.pi) - np.pi) < 1e-5


def test_a_turning_person_is_followed():
    r = HeadingResolver(HeadingParams(decay=0.8, max_evidence=5.0, min_evidence=0.5))
    rot = np.array([[0.0, -1.0], [1.0, 0.0]])  # +90° on the carpet
    for _ in range(10):
        r.resolve(upright(0.0), feet("up"), PITCH)
    for _ in range(15):  # now facing yaw +90°: feet toward +x; the model says so too, then backwards
        r.decide(upright(np.pi / 2), rot @ frame_cue(feet("up"), PITCH, r.params)[0])
    out = r.decide(upright(-np.pi / 2), rot @ frame_cue(feet("up"), PITCH, r.params)[0])
    assert yaw_rad(out[:3]) == pytest.approx(np.pi / 2, abs=1e-5)


def test_evidence_fades_faster_off_the_feet():
    r = HeadingResolver(HeadingParams(decay=1.0, off_feet_decay=0.5, max_evidence=5.0, min_evidence=0.5))
    for _ in range(5):
        r.resolve(upright(0.0), feet("up"), PITCH)
    r.decide(upright(0.0), np.zeros(2), on_feet=True)
    held = np.hypot(*r.evidence)
    r.decide(upright(0.0), np.zeros(2), on_feet=False)
    assert held == pytest.approx(5.0) and np.hypot(*r.evidence) == pytest.approx(2.5)


def test_activity_weights_silence_the_cue_where_it_is_not_trusted():
    params = HeadingParams(min_evidence=0.3)
    weights = np.array([1.0, 0.0])
    r = HeadingResolver(params, weights)
    for _ in range(10):
        out = r.resolve(upright(np.pi), feet("up"), PITCH, np.array([0.0, 1.0]))  # an untrusted activity
    assert r.flips == 0 and abs(yaw_rad(out[:3])) > np.pi - 1e-4  # published as the model said
    out = r.resolve(upright(np.pi), feet("up"), PITCH, np.array([1.0, 0.0]))
    assert r.flips == 1 and yaw_rad(out[:3]) == pytest.approx(0.0, abs=1e-5)


def test_the_packaged_parameters_load_and_bad_files_are_one_clear_error(tmp_path):
    params, weights = heading.load(activities=["standing", "no-such-activity"])
    assert isinstance(params, HeadingParams) and weights.shape == (2,) and weights[1] == 0.0 and weights[0] > 0.5
    bad = tmp_path / "h.json"
    bad.write_text("{nope")
    with pytest.raises(ValueError, match="unreadable heading parameters"):
        HeadingParams.load(bad)
    bad.write_text(json.dumps({"params": {"decay": 0.9, "colour": 1}}))
    with pytest.raises(ValueError, match="unknown field"):
        HeadingParams.load(bad)
    bad.write_text(json.dumps({"params": {"decay": "fast"}}))
    with pytest.raises(ValueError, match="must be a number"):
        HeadingParams.load(bad)


def outline_feet(toes: str, kpa: float = 14.0) -> np.ndarray:
    """(96,96) two saturated feet (every sensel at ``kpa``: no CoP offset at all) whose forefoot is
    7 sensels wide and heel 3, toes toward −y ("up") or +y ("down")."""
    foot = np.zeros((14, 7), np.float32)
    foot[:8] = kpa           # forefoot: rows 0–7, full width
    foot[8:, 2:5] = kpa      # heel: rows 8–13, narrow
    if toes == "down":
        foot = foot[::-1]
    p = np.zeros((96, 96), np.float32)
    for c0 in (40, 50):
        p[40:54, c0:c0 + 7] = foot
    return p


def test_a_saturated_foot_points_to_its_toes_by_its_outline():
    cop = HeadingParams()
    outline = HeadingParams(outline=1.0, min_skew=0.05)
    for toes, sign in (("up", -1.0), ("down", 1.0)):
        p = outline_feet(toes)
        assert not frame_cue(p, PITCH, cop)[0].any()  # flat pressure: the CoP cue has nothing to say
        cue, on_feet = frame_cue(p, PITCH, outline)
        assert on_feet and np.sign(cue[1]) == sign and abs(cue[0]) < 1e-6 * abs(cue[1]) + 1e-9
    # a symmetric blob (no wide end) gives no vote
    ellipse = np.zeros((96, 96), np.float32)
    ellipse[40:54, 40:45] = 14.0
    assert not frame_cue(ellipse, PITCH, outline)[0].any()


def test_a_saturated_blob_gives_no_cop_vote():
    heel_heavy = feet("up")
    params = HeadingParams(max_plateau_share=0.15)
    assert frame_cue(heel_heavy, PITCH, params)[0].any()
    assert not frame_cue(np.minimum(heel_heavy, 7.0), PITCH, params)[0].any()  # half the foot at the clip level


def test_a_half_turn_of_the_model_is_published_only_once_it_lasts():
    r = HeadingResolver(HeadingParams(confirm_flip_frames=5))
    assert yaw_rad(r.decide(upright(0.2), np.zeros(2))[:3]) == pytest.approx(0.2, abs=1e-5)
    for _ in range(4):  # the model swings round for four frames: held
        out = r.decide(upright(0.2 + np.pi), np.zeros(2))
        assert yaw_rad(out[:3]) == pytest.approx(0.2, abs=1e-5)
    assert yaw_rad(r.decide(upright(0.2), np.zeros(2))[:3]) == pytest.approx(0.2, abs=1e-5)  # and back: nothing shown
    for k in range(5):  # now it keeps the other answer: published on the fifth frame
        out = r.decide(upright(0.2 + np.pi), np.zeros(2))
    assert abs(abs(yaw_rad(out[:3]) - 0.2) - np.pi) < 1e-4
    # a gradual turn is followed frame by frame, never held
    r = HeadingResolver(HeadingParams(confirm_flip_frames=5))
    for yaw in np.linspace(0, np.pi, 20):
        out = r.decide(upright(yaw), np.zeros(2))
        assert abs(((yaw_rad(out[:3]) - yaw) + np.pi) % (2 * np.pi) - np.pi) < 1e-4


def test_a_lying_body_is_not_turned_by_the_feet():
    lying = upright(np.pi)
    lying[:3] = (Rotation.from_rotvec([0, 0, np.pi]) * Rotation.from_rotvec([0.1, 0, 0])).as_rotvec()  # supine-ish
    for gate, turned in ((0.5, False), (-1.0, True)):
        r = HeadingResolver(HeadingParams(min_evidence=0.3, min_upright=gate))
        for _ in range(5):
            r.resolve(upright(0.0), feet("up"), PITCH)  # evidence: facing yaw 0
        out = r.decide(lying, np.zeros(2), on_feet=False)
        assert (r.flips == 1) == turned
        assert np.allclose(out[:3], lying[:3]) != turned


def feet_facing(angle_rad: float, centre_m=(0.9, 0.9)) -> np.ndarray:
    """(96,96) two heel-heavy feet 25 × 9 cm, 18 cm apart, toes toward (cos a, sin a) in (column, row)."""
    ys, xs = (np.mgrid[0:96, 0:96] + 0.5) * PITCH
    fwd, side = np.array([np.cos(angle_rad), np.sin(angle_rad)]), np.array([-np.sin(angle_rad), np.cos(angle_rad)])
    p = np.zeros((96, 96), np.float32)
    for sgn in (1, -1):
        cx, cy = np.asarray(centre_m) + sgn * 0.09 * side
        u = (xs - cx) * fwd[0] + (ys - cy) * fwd[1]
        v = (xs - cx) * side[0] + (ys - cy) * side[1]
        inside = (np.abs(u) <= 0.125) & (np.abs(v) <= 0.045)
        p[inside] = (8.0 - 16.0 * u[inside])  # heel (−u) heavier: the CoP ~10 mm behind the centroid
    return p


@pytest.mark.parametrize("follow", [0.0, 30.0])
def test_turning_on_the_spot_the_evidence_turns_with_the_feet(follow):
    """A person faces +x for 3 s, then turns on the spot by 180° in 1.5 s while the model follows them
    exactly: evidence that only decays lags behind and turns the model's right answer backwards;
    evidence that turns with the feet's axis keeps it."""
    params = HeadingParams(decay=0.99, max_evidence=30.0, min_evidence=0.5, follow_axis_deg=follow)
    r = HeadingResolver(params)
    angles = [0.0] * 42 + list(np.linspace(0.0, np.pi, 21)) + [np.pi] * 14
    wrong = 0
    for a in angles:
        truth = cue_yaw_rad(np.array([np.cos(a), np.sin(a)]))
        out = r.resolve(upright(truth), feet_facing(a), PITCH)
        wrong += abs((yaw_rad(out[:3]) - truth + np.pi) % (2 * np.pi) - np.pi) > np.pi / 2
    if follow:
        assert wrong == 0
    else:
        assert wrong >= 5  # the lag this parameter exists to remove (11 frames today)


def test_the_feet_axis_is_their_long_axis_and_none_when_they_disagree():
    params = HeadingParams()
    for a in (0.0, 0.6, -1.2, 2.0):
        axis = heading.frame_evidence(feet_facing(a), PITCH, params)[2]
        assert abs((axis - a + np.pi / 2) % np.pi - np.pi / 2) < 0.05
    crossed = np.maximum(feet_facing(0.0, (0.5, 0.5)), feet_facing(np.pi / 2, (1.3, 1.3)))
    assert np.isnan(heading.frame_evidence(crossed, PITCH, params)[2])


def test_a_track_whose_centre_jumps_starts_its_heading_afresh():
    """The tracker hands a track to a body 1 m away (or the same body is put down elsewhere): the
    evidence of the feet that were there must not turn the new body's right answer backwards."""
    params = HeadingParams(decay=0.99, max_evidence=30.0, min_evidence=0.5)
    r = HeadingResolver(params)
    for _ in range(40):  # facing +x (toes along +column), evidence saturated
        r.resolve(upright(cue_yaw_rad(np.array([1.0, 0.0]))), feet_facing(0.0), PITCH, cop_m=(0.9, 0.9))
    truth = cue_yaw_rad(np.array([-1.0, 0.0]))  # the body now there faces −x
    out = r.resolve(upright(truth), feet_facing(np.pi, (0.9, 1.6)), PITCH, cop_m=(0.9, 1.6))
    assert abs((yaw_rad(out[:3]) - truth + np.pi) % (2 * np.pi) - np.pi) < 0.1
    assert r.resets == 1
    stay = HeadingResolver(params)  # the same without the jump: the old evidence wins (what the reset avoids)
    for _ in range(40):
        stay.resolve(upright(cue_yaw_rad(np.array([1.0, 0.0]))), feet_facing(0.0), PITCH, cop_m=(0.9, 0.9))
    out = stay.resolve(upright(truth), feet_facing(np.pi, (0.9, 1.6)), PITCH, cop_m=(0.9, 1.0))
    assert abs((yaw_rad(out[:3]) - truth + np.pi) % (2 * np.pi) - np.pi) > np.pi / 2


def test_a_walker_faces_the_way_they_go_and_sitting_down_is_no_walk():
    """The feet say nothing (a walking foot rolls heel to toe) and the model faces backwards: a track that went
    0.7 m along +x in the last second, seen walking, is published facing +x. Sitting down moves the centre
    0.4 m backwards too; seen sitting, it turns nothing."""
    params = HeadingParams(decay=0.97, max_evidence=30.0, min_evidence=0.5, travel_weight=1.0)
    walking, sitting = np.array([0.0, 1.0]), np.array([1.0, 0.0])  # activity probabilities over (sitting, walking)
    ahead = cue_yaw_rad(np.array([1.0, 0.0]))

    def run(probs, travel_table, centre):
        r = HeadingResolver(params, None, travel_table)
        for k in range(30):
            out = r.resolve(upright(ahead + np.pi), np.zeros((96, 96)), PITCH, probs, cop_m=centre(k))
        return r, abs((yaw_rad(out[:3]) - ahead + np.pi) % (2 * np.pi) - np.pi)

    def walk(k):  # 0.7 m/s at 14 Hz, swaying 5 cm side to side with the steps
        return (0.3 + 0.05 * k, 0.9 + 0.05 * (k % 2))

    table = np.array([0.0, 1.0])  # the travel vote's weight: walking only
    assert run(walking, table, walk)[1] < 0.1
    assert run(walking, None, walk)[1] > np.pi / 2  # no travel table: the model's answer stands
    assert run(sitting, table, walk)[1] > np.pi / 2
    r, _ = run(sitting, table, lambda k: (0.9 + 0.4 * min(max(k - 10, 0), 7) / 7, 0.9))
    assert r.flips == 0


def test_the_packaged_travel_vote_is_for_walkers_and_a_refit_keeps_it(tmp_path):
    from edge.infer.heading import travel_weights
    from export.heading_cue import travel_settings
    w = travel_weights(None, ["sitting", "walking", "standing"])
    assert w is not None and w[1] > 0 and w[0] == 0 and w[2] == 0  # sitting down moves the centre too
    assert heading.HeadingParams.load().travel_weight > 0
    params, table = travel_settings(heading.PARAMS_FILE)  # what `make heading` carries over to its refit
    assert params["travel_weight"] > 0 and table["travel_weight"]["walking"] > 0
    assert travel_settings(tmp_path / "none.json") == ({}, {})
