"""Fixtures of the runtime tests: a calibration of the virtual carpet, configurations writing to tmp dirs.

The calibration is the one a perfect procedure would make for ``sim://?seed=7`` (from the
simulator's true parameters: milliseconds, where the scripted session takes ~10 s at 96×96;
the scripted session itself is tested on a 32×32 carpet).
"""

from pathlib import Path

import pytest
from runtime_helpers import MARK_COUNT, MARK_KPA, make_config, truth_calibration


@pytest.fixture(scope="session")
def sim_calibration(tmp_path_factory) -> Path:
    return truth_calibration(tmp_path_factory.mktemp("calibration"))


@pytest.fixture
def config(tmp_path, sim_calibration):
    """``config(people=2, **overrides)`` → a RuntimeConfig on sim:// at speed=0 writing into tmp_path."""

    def make(people: int = 2, **overrides):
        return make_config(tmp_path, sim_calibration, people, **overrides)

    return make




class MarkedSource:
    """Wraps a real source: every frame's sensel (0, 0) reads MARK_COUNT."""

    def __init__(self, inner):
        self.inner = inner

    def __getattr__(self, name):
        return getattr(self.inner, name)

    def frames(self, timeout_s=None):
        import dataclasses

        for frame in self.inner.frames(timeout_s):
            counts = frame.counts.copy()
            counts[0, 0] = MARK_COUNT
            yield dataclasses.replace(frame, counts=counts)


@pytest.fixture(scope="session")
def two_people_run(tmp_path_factory, sim_calibration):
    """One 60-frame run of the runtime on sim://?people=2&seed=7 at speed=0 into a JSON-lines file, with the
    privacy markers injected (raw and calibrated). Returns (out_dir, final status, outcomes, model inputs seen)."""
    import numpy as np

    from calibration.runtime import CalibratedFrames
    from edge.runtime import Runtime
    from edge.runtime.reader import open_timed_source

    out = tmp_path_factory.mktemp("two_people")
    cfg = make_config(out, sim_calibration, 2)
    original = CalibratedFrames.process

    def marked(self, counts, t_s, temperature_c=None):
        res = original(self, counts, t_s, temperature_c)
        if res.pressure_kpa is not None:
            i = np.unravel_index(np.argmax(res.pressure_kpa), res.pressure_kpa.shape)
            res.pressure_kpa[i] = MARK_KPA
        return res

    mp = pytest.MonkeyPatch()
    mp.setattr(CalibratedFrames, "process", marked)
    try:
        rt = Runtime(cfg, say=lambda text: None)
        rt.source = MarkedSource(open_timed_source(cfg.source.url, rt.times))
        outcomes, inputs = [], []
        rt.on_outcome.append(outcomes.append)
        rt.setup()
        encode = rt.bundle.encode
        rt.bundle.encode = lambda x: (inputs.append(np.array(x)), encode(x))[1]
        final = rt.run_for(frames=60)
    finally:
        mp.undo()
    return out, final, outcomes, inputs
