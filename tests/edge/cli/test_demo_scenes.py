"""`make run`'s virtual carpet ends its run in the middle of a scene, so the picture's last column never
falls where everyone moves elsewhere at once (a simulator's scene change, which no real carpet has)."""

import pytest

from edge.cli.demo import demo_scene_s, demo_url
from edge.sources import source_options


@pytest.mark.parametrize("seconds", [5.0, 10.0, 20.0, 25.0, 60.0, 300.0])
def test_the_run_ends_half_way_through_its_last_scene(seconds):
    scene_s = demo_scene_s(seconds)
    scenes = seconds / scene_s
    assert abs(scenes - (int(scenes) + 0.5)) < 0.01, (seconds, scene_s)  # half a scene from either change
    assert seconds < 15 or 6.5 <= scene_s <= 14.0  # scenes of about 10 s once there is room for two


def test_the_url_carries_the_scene_length_the_truth_is_drawn_with():
    opts = source_options(demo_url(2, 7, 20.0) + "&speed=0")
    assert opts["people"] == 2 and opts["seed"] == 7
    assert opts["scene_s"] == pytest.approx(demo_scene_s(20.0))
