"""Simulated falls and look-alikes: their truth matches the motion, the virtual carpet streams them, and
the runtime's scene + fall detector gives the expected events on short scripted scenes."""

from dataclasses import replace

import numpy as np
import pytest

from edge.body import BodyModel
from sim.motion import Subject
from sim.motion.falls import FALLS, LOOKALIKES, fall_track, on_carpet

RATE = 14.0


@pytest.fixture(scope="module")
def body():
    return BodyModel.load("lite")


@pytest.mark.parametrize("name", FALLS)
def test_a_fall_goes_from_upright_to_lying_at_its_truth(name, body):
    rng = np.random.default_rng(3)
    ft = fall_track(Subject.random(3, rng), name, RATE, rng, body, lie_s=3.0, get_up=False)
    t = ft.truth
    z = ft.track.transl_m[:, 2]
    k = lambda s: int(round(s * RATE))  # noqa: E731
    assert t["fall"] and t["start_s"] < t["impact_s"] < t["floor_s"][1] <= t["seconds"]
    assert z[k(t["start_s"]) - 1] > 0.45  # standing, or seated on a chair
    assert z[k(t["impact_s"]) + 1: k(t["floor_s"][1])].max() < 0.3  # the pelvis on the floor from impact on
    assert t["impact_s"] - t["start_s"] < 4.0


@pytest.mark.parametrize("name", LOOKALIKES)
def test_look_alikes_have_no_fall_and_lying_down_is_slow(name, body):
    rng = np.random.default_rng(4)
    ft = fall_track(Subject.random(4, rng), name, RATE, rng, body, lie_s=3.0)
    assert not ft.truth["fall"] and ft.truth["impact_s"] is None
    z = ft.track.transl_m[:, 2]
    if name.startswith("lie_down"):
        low = np.flatnonzero(z < 0.3)
        assert len(low) and low[0] / RATE > 4.0  # several seconds from standing to lying


def test_every_scenario_fits_on_the_carpet(body):
    rng = np.random.default_rng(5)
    ft = on_carpet(fall_track(Subject.random(5, rng), "walk_fall_forward", RATE, rng, body, lie_s=2.0), (1.83, 1.83),
                   rng, body)
    v = body.forward(ft.track.pose_aa[::5], ft.track.betas, ft.track.transl_m[::5], vertices=True)["vertices"]
    assert v[..., :2].min() >= 0.0 and v[..., :2].max() <= 1.83


def test_the_virtual_carpet_streams_a_fall_scenario(body):
    from sim.live import place_chunk
    from sim.motion import Subject as S

    sc = place_chunk([S.random(0, 1)], ("fall_backward",), 1, 0, 20.0, RATE, 1.83, True, body)  # a scenario keeps its length
    assert sc.num_frames == int(20 * RATE)
    z = sc.tracks[0].transl_m[:, 2]
    assert z[0] > 0.8 and z[-1] < 0.3


def _events(name, body, config, seed=2, lie_s=4.0):
    from edge.scene.falls import FallDetector
    from edge.scene.pipeline import SceneTracker
    from sim.contact import ContactModel, subject_mass_kg, tissue_stiffness

    rng = np.random.default_rng(seed)
    subject = Subject.random(seed, rng)
    ft = on_carpet(fall_track(subject, name, RATE, rng, body, lie_s=lie_s, get_up=False), (1.83, 1.83), rng, body)
    tr = ft.track
    v = body.forward(tr.pose_aa, tr.betas, tr.transl_m, vertices=True)["vertices"]
    carpet, mass, tissue = ContactModel(96, 96, pitch_m=0.01905), subject_mass_kg(body, tr.betas), tissue_stiffness(body)
    scene, det = SceneTracker(96, 96, 0.01905), FallDetector(config, 0.01905)
    out = []
    for k in range(len(tr)):
        p = carpet.pressure_kpa(v[k], body.faces, mass * ft.load_fraction[k], static=True,
                                tissue_kpa_per_mm=tissue).pressure_kpa
        out += det.update(scene.update(p, k / RATE))
    return ft.truth, [(e["type"], e["state"], e["t_s"]) for e in out]


def test_a_simulated_backward_fall_raises_fall_and_person_down(body):
    from edge.scene.falls import FallConfig

    truth, ev = _events("fall_backward", body, replace(FallConfig(), person_down_s=3.0))
    raised = {k: t for k, s, t in ev if s == "raised"}
    assert set(raised) == {"fall", "person_down"}
    assert 0 <= raised["fall"] - truth["impact_s"] <= 3.0
    # person_down_s after the body first lay on the floor, which can come a little before the truth's impact
    # (the end of the toppling key): a hip or a shoulder lands first
    assert 2.5 <= raised["person_down"] - truth["impact_s"] <= 5.0


def test_lying_down_on_purpose_raises_nothing(body):
    from edge.scene.falls import FallConfig

    _, ev = _events("lie_down", body, replace(FallConfig(), person_down_s=3.0), lie_s=6.0)
    assert ev == []


def test_objects_press_with_their_weight_and_a_pet_lies_down_now_and_then():
    from sim.objects import G_M_S2, DroppedBag, Pet

    rng = np.random.default_rng(0)
    pitch, n = 0.01905, 96
    bag = DroppedBag.random(rng, drop_s=2.0)
    assert bag.pressure_kpa(1.0, n, n, pitch).sum() == 0  # not dropped yet
    force = bag.pressure_kpa(3.0, n, n, pitch).sum() * 1000 * pitch * pitch
    assert abs(force - bag.mass_kg * G_M_S2) < 1e-3 * bag.mass_kg * G_M_S2
    pet = Pet.random(rng, seconds=120.0)
    assert 5 <= pet.mass_kg <= 30 and pet.lie_spans_s
    a, _ = pet.lie_spans_s[0]
    for t in (0.1, 0.37, a + 0.1):
        p = pet.pressure_kpa(t, n, n, pitch)
        assert abs(p.sum() * 1000 * pitch * pitch - pet.mass_kg * G_M_S2) < 0.01 * pet.mass_kg * G_M_S2
    standing = (pet.pressure_kpa(0.1, n, n, pitch) > 0).sum()
    lying = (pet.pressure_kpa(a + 0.1, n, n, pitch) > 0).sum()
    assert lying > 3 * standing  # four paws, then the body's outline


def test_sim_url_takes_fall_scenarios_and_names_the_known_ones():
    from edge.sources import open_link

    assert open_link("sim://?activities=fall_forward,lie_down,squat&speed=0").opts["activities"] == (
        "fall_forward", "lie_down", "squat")
    with pytest.raises(ValueError, match="known: .*slow_collapse"):
        open_link("sim://?activities=tumbling")
