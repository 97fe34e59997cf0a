"""Contact detection with hysteresis, and the same physical answers on 96×96, 48×48 and 32×32 carpets."""

import numpy as np
import pytest
from scene_worlds import noisy, render

from edge.scene import SceneConfig, SceneTracker, detect_contacts
from edge.scene.contacts import sensel_centres_m

PITCH = 0.01905


def test_two_thresholds_keep_seeded_components_only():
    p = np.zeros((20, 20), np.float32)
    p[2:5, 2:5] = 0.2  # above grow (0.15), no seed: not a contact
    p[10:14, 10:14] = 0.2
    p[11, 11] = 0.5  # seed: the whole 4×4 plateau grows from it
    p[17, 2] = 0.1  # below grow
    x, y = sensel_centres_m(20, 20, 0.02)
    labels, blobs = detect_contacts(p, 0.3, 0.15, 0.02, 1, x, y)
    (blob,) = blobs
    assert blob.area_m2 == pytest.approx(16 * 0.02**2)
    assert blob.force_n == pytest.approx((15 * 0.2 + 0.5) * 0.02**2 * 1e3, rel=1e-5)
    assert (labels > 0).sum() == 16 and labels[3, 3] == 0
    assert blob.bbox == (slice(10, 14), slice(10, 14))
    diagonal = np.zeros((6, 6), np.float32)
    diagonal[1, 1] = diagonal[2, 2] = diagonal[3, 3] = 1.0  # 8-connected: one blob
    assert len(detect_contacts(diagonal, 0.3, 0.15, 0.02, 1, *sensel_centres_m(6, 6, 0.02))[1]) == 1


def test_contacts_on_a_noisy_synthetic_frame():
    rng = np.random.default_rng(0)
    person = {"centre_m": (0.7, 1.1), "heading_rad": 1.2, "mass_kg": 80.0}
    true = render(96, 96, PITCH, [person])
    st = SceneTracker(96, 96, PITCH)  # noise estimated online
    for i in range(5):
        out = st.update(noisy(true, rng, 0.08, salt=20), i / 14)
    assert 0.06 < out.noise_kpa < 0.1
    (p,) = out.people
    assert p.contacts == 2
    assert np.linalg.norm(p.cop_raw_m - np.array(person["centre_m"])) < 0.01
    assert abs(p.force_raw_n - 80 * 9.81) / (80 * 9.81) < 0.04
    true_area_m2 = 2 * np.pi * 0.125 * 0.045
    assert 0.9 * true_area_m2 < p.area_m2 < 1.4 * true_area_m2


CARPETS = [(96, 96, 0.01905), (48, 48, 0.0381), (32, 32, 0.028575)]  # 1.83 m, 1.83 m, 0.91 m


def _answers(rows, cols, pitch_m, people, frames=5):
    rng = np.random.default_rng(1)
    st = SceneTracker(rows, cols, pitch_m, SceneConfig(noise_kpa=0.05))
    true = render(rows, cols, pitch_m, people)
    for i in range(frames):
        out = st.update(noisy(true, rng), i / 14)
    return sorted(out.people, key=lambda q: q.cop_raw_m[0])


@pytest.mark.parametrize("rows, cols, pitch_m", CARPETS)
def test_same_physical_answers_at_any_pitch(rows, cols, pitch_m):
    person = {"centre_m": (0.45, 0.5), "heading_rad": 0.3, "mass_kg": 65.0}
    (p,) = _answers(rows, cols, pitch_m, [person])
    assert np.linalg.norm(p.cop_raw_m - person["centre_m"]) < 0.01
    assert abs(p.force_raw_n - 65 * 9.81) / (65 * 9.81) < 0.04
    assert abs(p.force_n - 65 * 9.81) / (65 * 9.81) < 0.04
    true_area_m2 = 2 * np.pi * 0.125 * 0.045
    assert 0.9 * true_area_m2 < p.area_m2 < 1.9 * true_area_m2  # edge sensels count whole: coarser is larger


@pytest.mark.parametrize("rows, cols, pitch_m", CARPETS[:2])
def test_two_people_on_the_same_rows_are_separated(rows, cols, pitch_m):
    people = [{"centre_m": (0.45, 0.9), "heading_rad": np.pi / 2, "mass_kg": 60.0},
              {"centre_m": (1.35, 0.9), "heading_rad": np.pi / 2, "mass_kg": 90.0}]
    found = _answers(rows, cols, pitch_m, people)
    assert len(found) == 2
    for p, truth in zip(found, people):
        assert np.linalg.norm(p.cop_raw_m - truth["centre_m"]) < 0.02
        assert abs(p.force_raw_n - truth["mass_kg"] * 9.81) / (truth["mass_kg"] * 9.81) < 0.05
        assert not (found[0].mask & found[1].mask).any()
