"""What the scene hands to inference (edge/scene/handover.py): the filled frame BEFORE the filters, the
confirmed people, and every track it still holds (coasting ones too), and nothing for an invalid frame."""

import numpy as np
from scene_worlds import render

from edge.scene import SceneConfig, SceneTracker

PITCH = 0.01905
STAND = {"centre_m": (0.9, 0.9), "heading_rad": 0.0, "mass_kg": 70}


def test_the_handover_is_the_filled_frame_before_the_filters():
    st = SceneTracker(96, 96, PITCH, SceneConfig(noise_kpa=0.05))
    p = render(96, 96, PITCH, [STAND])
    masks = np.zeros((96, 96), bool)
    r, c = np.argwhere(p > 1.0)[0]
    masks[r, c] = True  # a dead sensel under the foot
    dead = p.copy()
    dead[r, c] = 0.0
    for k in range(4):
        out = st.update(dead, k / 14, masks=masks)
    h = out.handover
    assert out.valid and len(h.people) == 1 and h.people[0].track_id in h.held_track_ids
    assert h.filled_kpa.dtype == np.float32 and h.filled_kpa.shape == (96, 96)
    around = dead[r - 1:r + 2, c - 1:c + 2]
    neighbours = np.delete(around.ravel(), 4)
    assert np.isclose(h.filled_kpa[r, c], neighbours.mean(), rtol=1e-5)  # filled from its 8 neighbours
    unmasked = ~masks
    assert np.array_equal(h.filled_kpa[unmasked], dead[unmasked])  # no median, Gaussian or EMA: raw sensels
    assert not np.allclose(out.pressure_kpa, h.filled_kpa)  # the filtered frame is another one


def test_a_coasting_track_is_held_but_not_a_person_and_an_invalid_frame_hands_nothing():
    st = SceneTracker(96, 96, PITCH, SceneConfig(noise_kpa=0.05))
    p = render(96, 96, PITCH, [STAND])
    for k in range(4):
        out = st.update(p, k / 14)
    (tid,) = [q.track_id for q in out.people]
    zeros = np.zeros((96, 96), np.float32)
    seen = [st.update(zeros, k / 14).handover for k in range(4, 4 + 28)]  # two seconds off the carpet
    coasting = [h for h in seen if not h.people and h.held_track_ids]
    assert coasting and all(h.held_track_ids == {tid} for h in coasting)  # gone from view, window still held
    assert seen[-1].people == () and seen[-1].held_track_ids == frozenset()  # past coast_s: lost
    late = st.update(zeros, 4 / 14)  # an old timestamp: refused
    assert not late.valid and late.handover is None
