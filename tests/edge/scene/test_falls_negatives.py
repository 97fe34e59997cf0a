"""The fall detector's hard negatives: going down on purpose, floor exercises, sitting, pets and bags raise nothing."""

import numpy as np
import pytest
from fall_scripts import FEET, KNEEL, LONG, LYING, RATE, SEATED, SITTING, body, kinds, run

from edge.scene.falls import FallDetector, Observation


def test_a_push_up_short_for_its_first_frame_only_is_no_collapse():
    """Down onto hands and feet and straight into the plank: 1.0 m for the first frame on the floor, then longer
    every frame. The first frame is an edge, not a dip between longer ones: it touched down short."""
    a = np.array([0.9, 0.6])
    script = [(3.0, [body([1], a, **FEET)]), (0.2, [])]
    script += [(1 / RATE, [body([2], a + (0.15, 0.25), **dict(LONG, length_m=n))]) for n in (1.0, 1.27, 1.58, 1.9)]
    ev, _ = run(script + [(34.0, [body([2], a + (0.15, 0.25), **dict(LONG, length_m=2.1))])])
    assert ev == []


@pytest.mark.parametrize("case", ["kneel_long", "sit_first", "short", "plank", "still_standing"])
def test_going_down_in_place_without_collapsing_is_no_fall(case):
    """In place, but: low for longer before lying (a deliberate lie-down), the body sitting rather than at full
    length, a push-up (short on hands and feet first, then stretched into the plank), or the feet of someone
    still standing inside what lies there."""
    a = np.array([0.9, 0.6])
    lying = body([1, 2], a + (0.15, 0.25), **LONG)
    if case == "kneel_long":
        script = [(3.0, [body([1], a, **FEET)]), (5.0, [body([1], a, **KNEEL)]), (0.1, []), (34.0, [lying])]
    elif case == "sit_first":
        script = [(3.0, [body([1], a, **FEET)]), (1.5, [body([1], a + (0, 0.2), **SITTING)]), (34.0, [lying])]
    elif case == "plank":  # down onto hands and feet, then stretched into a push-up's plank: as long as lying
        crouch = body([1], a + (0.05, 0.1), force_n=650.0, area_m2=0.057, length_m=0.65)
        script = [(3.0, [body([1], a, **FEET)]), (0.4, [crouch]), (34.0, [body([1], a + (0.15, 0.25), **LONG)])]
    elif case == "short":
        script = [(3.0, [body([1], a, **FEET)]), (0.3, []), (34.0, [body([1, 2], a + (0.15, 0.25), **dict(LONG, length_m=1.1))])]
    else:  # a bag beside the feet of someone who has stood there all along: a long print, no fall
        def point(tid, force_n, area_m2, xy):  # an observation whose pressure sits at one point
            x, y = xy
            return Observation(tid, force_n, area_m2, np.asarray(xy, float),
                               force_n * np.array([1.0, x, y, x * x, y * y, x * y]))

        feet, bag = point(1, 650.0, 0.035, a), point(2, 300.0, 0.06, a + (0.8, 0.0))
        # merged: 950 N on 0.095 m², 1.49 m long, its centre 0.25 m from the feet: in place, at full length
        det, out, t = FallDetector(), [], 0.0
        for k in range(int(40 * RATE)):
            out += [e for e in det.step_observations(t, [feet] if k < 3 * RATE else [feet, bag], {})
                    if e["state"] == "raised"]
            t += 1 / RATE
        assert out == []
        return
    ev, _ = run(script)
    assert ev == []


def test_lying_down_slowly_is_no_fall_and_no_person_down():
    """Kneel, sit, lie back over 7 s (an exercise mat) and stay 40 s."""
    a = np.array([0.9, 0.4])
    script = [(3.0, [body([1], a, **FEET)]), (7.0, [body([1], a + (0, 0.4), **SITTING)]),
              (40.0, [body([1], a + (0, 0.9), **LYING)])]
    ev, _ = run(script)
    assert ev == []


def sit_ups(a, seconds):
    """Lying, curling up and back every 2 s: the area and the centre change."""
    out = []
    for i in range(int(seconds / 2)):
        out.append((1.0, [body([2], a + (0, 0.9), **LYING)]))
        out.append((1.0, [body([2], a + (0, 0.75), force_n=650.0, area_m2=0.065, length_m=0.6)]))
    return out


def test_floor_exercises_never_raise_person_down():
    """Someone drops fast to the floor for sit-ups (the model says sit_up, the body moves): no person_down."""
    a = np.array([0.9, 0.4])
    script = [(3.0, [body([1], a, **FEET)]), (0.5, [])] + sit_ups(a, 40.0)
    ev, _ = run(script, activities={2: "sit_up"})
    assert ("person_down", "raised") not in [(k, s) for k, s, _, _ in ev]


def test_sitting_kneeling_and_planks_are_not_on_the_floor():
    a = np.array([0.9, 0.4])
    plank = dict(force_n=650.0, area_m2=0.03, length_m=1.3)
    for pose in (SITTING, plank):
        ev, _ = run([(3.0, [body([1], a, **FEET)]), (0.3, []), (40.0, [body([1], a + (0, 0.3), **pose)])])
        assert ev == []


def test_a_dropped_bag_or_a_pet_beside_someone_standing_raises_nothing():
    a = np.array([0.9, 0.4])
    bag = [(3.0, [body([1], a, **FEET)]), (20.0, [body([1, 2], a + (0.1, 0.05), force_n=800, area_m2=0.12, length_m=1.1)])]
    assert run(bag)[0] == []
    # a 30 kg dog trots (four small paws), then lies down where it stands: a big footprint, but the load hardly moved
    dog = [(3.0, [body([5], a, force_n=290, area_m2=0.01, length_m=0.4)]),
           (40.0, [body([5], a + (0.1, 0.05), force_n=290, area_m2=0.12, length_m=0.5)])]
    assert run(dog)[0] == []
    # a cat (5 kg) is too light to be anyone on the floor, wherever it lies
    cat = [(3.0, [body([6], a, force_n=49, area_m2=0.004, length_m=0.3)]),
           (40.0, [body([6], a + (0.6, 0.0), force_n=49, area_m2=0.06, length_m=0.3)])]
    assert run(cat)[0] == []


def test_a_squat_with_a_hand_going_down_then_lying_is_no_fall():
    """A light footprint (saturated forefeet, a hand) that keeps moving is no one seated: lying down beside it is
    deliberate, as is the same after a still seat whose load the lying body does not exceed 3.5 times."""
    a = np.array([0.9, 0.4])
    squat = [(1 / RATE, [body([1], a + (0, 0.002 * k), force_n=200.0 * (1 + 0.35 * np.sin(2 * np.pi * k / RATE)),
                              area_m2=0.012, length_m=0.3)]) for k in range(42)]  # weight shifting onto a hand
    ev, _ = run(squat + [(34.0, [body([2], a + (0, 0.3), force_n=800.0, area_m2=0.09, length_m=0.75)])])
    assert ev == []
    heavy_seat = dict(SEATED, force_n=300.0)
    ev, _ = run([(6.0, [body([1], a, **heavy_seat)]), (0.5, []), (34.0, [body([2], a + (0, 0.3), **LYING)])])
    assert ev == []


def test_a_deep_lunge_is_long_but_not_lying():
    """Two feet 0.8 m apart print 1.6 m long at ≈ 15 kPa; a body that long lying spreads its weight (≈ 8 kPa)."""
    a = np.array([0.9, 0.4])
    lunge = dict(force_n=500.0, area_m2=0.032, length_m=1.65)
    assert run([(3.0, [body([1], a, **FEET)]), (30.0, [body([1], a + (0, 0.5), **lunge)])])[0] == []
    long_lying = dict(force_n=280.0, area_m2=0.035, length_m=1.65)
    ev, _ = run([(3.0, [body([1], a, **FEET)]), (0.5, []), (34.0, [body([2], a + (0, 0.8), **long_lying)])])
    assert kinds(ev) == [("fall", "raised"), ("person_down", "raised")]


def test_a_heavy_dog_trotting_over_and_lying_down_is_not_a_person():
    """30 kg trots in from 0.7 m away and lies down: 290 N over 0.12 m² (≈ 2.4 kPa) is no adult lying."""
    a = np.array([0.9, 0.4])
    trot = [(0.2, [body([5], a + (0.0, 0.1 * k), force_n=290, area_m2=0.01, length_m=0.4)]) for k in range(8)]
    assert run(trot + [(40.0, [body([5], a + (0.0, 0.8), force_n=290, area_m2=0.12, length_m=0.5)])])[0] == []


def test_lying_back_from_sitting_on_the_floor_is_no_fall():
    """A sit-up's start, squeezed: stand, sit down on the floor (a buttocks-and-feet print that reads like feet,
    carrying 400 N), lie back. The centre of pressure slides onto the floor (0.05 m a frame) while the seat still
    carries most of the weight; the body comes to rest 0.5 m from where they stood — far enough for a fall, but
    nothing was in the air."""
    a = np.array([0.9, 0.4])
    seat = dict(force_n=400.0, area_m2=0.033, length_m=0.65)
    script = [(2.0, [body([1], a, **FEET)]), (0.6, [body([1], a + (0, 0.1), **seat)])]
    script += [(1 / RATE, [body([1], a + (0, 0.1 + 0.05 * k), **seat)]) for k in range(1, 4)]
    script += [(1 / RATE, [body([1], a + (0, 0.25 + 0.05 * k), force_n=550.0, area_m2=0.06 + 0.01 * k, length_m=0.8)])
               for k in range(1, 6)]
    ev, _ = run(script + [(10.0, [body([1], a + (0, 0.55), force_n=550.0, area_m2=0.1, length_m=1.15)])])
    assert ev == []


def test_a_push_up_from_a_crouch_straight_into_a_long_plank_is_no_fall():
    """Down onto hands and feet (a crouch that reads like feet, carrying the whole load), then the feet hop back:
    the plank is 1.65 m long from its first frame on the floor, in place — a collapse's print — but the hands
    carried the body all the way and the centre of pressure slid 0.05 m."""
    a = np.array([0.9, 0.6])
    crouch = dict(force_n=640.0, area_m2=0.045, length_m=0.8)
    plank = dict(force_n=650.0, area_m2=0.052, length_m=1.65)
    script = [(3.0, [body([1], a, **FEET)]), (1.0, [body([1], a + (0, 0.1), **crouch)]),
              (1 / RATE, [body([1], a + (0, 0.15), **plank)]), (20.0, [body([1], a + (0, 0.3), **plank)])]
    ev, _ = run(script)
    assert ev == []


def test_a_long_hard_print_that_keeps_moving_is_not_lying():
    """The same long, hard print that shifts every half second (a lunge, a plank's reps) never lies still."""
    a = np.array([0.9, 0.4])
    sparse = dict(force_n=300.0, area_m2=0.022, length_m=2.0)
    script = [(3.0, [body([1], a, force_n=300.0, area_m2=0.025, length_m=0.6)]),
              (0.4, [body([1], a, force_n=150.0, area_m2=0.012, length_m=0.3)])]
    script += [(0.5, [body([1], a + (0.1, 0.6 + 0.05 * (k % 2)), **sparse)]) for k in range(60)]
    assert run(script)[0] == []


def test_a_long_lunge_pressed_like_a_lying_body_is_no_fall():
    """The feet of a long lunge can print 1.6 m on 0.035 m² at 8–9 kPa, like a lying body (held-out lunge-s7-3):
    the body never left the floor on the way (every frame carries ≥ 250 N of its 330), so it is not lying."""
    a = np.array([0.7, 0.9])
    script = [(1.5, [body([1], a, force_n=420.0, area_m2=0.047, length_m=0.66)])]
    script += [(1 / RATE, [body([1], a + (0.04 * k, 0.01 * k), force_n=260.0, area_m2=0.03, length_m=0.7 + 0.07 * k)])
               for k in range(1, 13)]  # the front foot goes forward: the print lengthens, the weight stays on it
    script.append((20.0, [body([1], a + (0.52, 0.13), force_n=326.0, area_m2=0.04, length_m=1.62)]))
    assert run(script)[0] == []


def test_a_dog_that_trots_over_and_lies_down_far_off_is_no_fall():
    """A 23 kg dog's paws read light while it trots (its steps look like feet in the air), then it lies down
    0.5 m away and stays dead still, but on 0.1 m² at 2.2 kPa (the print of held-out pet-s6, which alarmed while
    a compact print lying still counted whatever its pressure): no event."""
    a = np.array([1.2, 1.2])
    script = [(0.2 * (k % 2 + 1), [body([1], a - (0, 0.1 * k), force_n=190.0 - 95.0 * (k % 2), area_m2=0.012,
                                        length_m=0.85)]) for k in range(6)]
    script.append((20.0, [body([1], a - (0, 0.55), force_n=225.0, area_m2=0.101, length_m=0.59)]))
    assert run(script)[0] == []
