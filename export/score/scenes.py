"""The fixed scene sets of `cavatar score`.

- ``quick`` (tests, a first look: seconds): one person, one 5-second scene.
- ``standard`` (the committed score, ``make score``): one person on three carpets for 40 s each
  (four 10-s scenes per carpet; seeds 2, 9 and 109 draw all eleven live activities between
  them, lying ones included: sit-up on 2, push-up on 9), two people on two carpets and three
  people on two carpets for 30 s each (lying activities are left out with several people).

Seeds were chosen from what the virtual carpet draws (``sim.live.place_chunk``: the activities
of scene c of seed s come from ``default_rng((s, c))``) and kept only where every scene can be
placed; three people do not fit together on many seeds (the simulator gives up placing them),
which the score reports as a failed scene instead of stopping.
"""

from __future__ import annotations

from export.score.capture import Scene

SETS: dict[str, tuple[Scene, ...]] = {
    "quick": (Scene(people=1, seed=3, seconds=5.0),),
    "standard": (
        Scene(people=1, seed=2, seconds=40.0),
        Scene(people=1, seed=9, seconds=40.0),
        Scene(people=1, seed=109, seconds=40.0),
        Scene(people=2, seed=4, seconds=30.0),
        Scene(people=2, seed=8, seconds=30.0),
        Scene(people=3, seed=12, seconds=30.0),
        Scene(people=3, seed=17, seconds=30.0),
    ),
}
