"""One scene through the real runtime, and the simulator's truth for every frame of it.

    run = capture(Scene(people=2, seed=11, seconds=20), work=Path("out/score"))
    run.status            # "scored", "partial" (the stream ended early) or "failed" (with run.reason)
    run.published[k]      # the people of the record published for simulator frame k ([] when none)

The runtime is :class:`edge.runtime.Runtime` — ``cavatar run``'s own reader, pipeline and
publisher threads — on ``sim://?people=P&seed=S&speed=0`` (the virtual carpet through the wire
protocol, as fast as frames can be made, none dropped), publishing into a JSON-lines sink;
what is scored is read back from that file, so it is exactly what was published. The
calibration is the runtime's own choice: with no file it runs the scripted installer session on
the virtual carpet and caches it as ``<work>/calibration-sim-<seed>-96.npz`` (a later score
reuses it); ``calibration="truth"`` uses the one a perfect procedure would make instead, to
separate calibration error from the rest.

Records carry no frame index; ``Runtime.on_outcome`` tells which board frame (= simulator frame)
each record came from and how long the pipeline took for it (the ``frame`` stage). The truth is
a second :class:`sim.live.LiveCarpet` of the same people, seed and scene length (its scenes are
a pure function of those), as `make run`'s picture does.
"""

from __future__ import annotations

import json
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable

from edge.runtime.counters import StageTimes

GRID = 96
RATE_HZ = 14.0


@dataclass(frozen=True)
class Scene:
    people: int
    seed: int
    seconds: float
    scene_s: float = 10.0  # the virtual carpet's least scene length (longer where an activity needs it): then others

    @property
    def name(self) -> str:
        return f"p{self.people}-s{self.seed}"

    @property
    def frames(self) -> int:
        return int(round(self.seconds * RATE_HZ))

    def url(self) -> str:
        return f"sim://?people={self.people}&seed={self.seed}&speed=0&scene_s={self.scene_s:g}"


@dataclass
class SceneRun:
    scene: Scene
    status: str  # scored | partial | failed
    reason: str = ""
    published: list[list[dict]] = field(default_factory=list)  # per frame: the published people
    kinds: list[str] = field(default_factory=list)  # per frame: people, empty, unconfirmed, invalid, lost
    frame_ms: list[float | None] = field(default_factory=list)  # per frame: the pipeline's milliseconds
    truth: list[list[dict]] = field(default_factory=list)  # per frame: the true people (see sim.live)
    calibration: str = ""
    runtime_s: float = 0.0
    model: str = ""


class _FrameTimes(StageTimes):
    """The runtime's stage times, also keeping the last ``frame`` milliseconds for the outcome callback."""

    last_frame_ms: float | None = None

    def add(self, stage: str, ms: float) -> None:
        super().add(stage, ms)
        if stage == "frame":
            self.last_frame_ms = float(ms)


def _config(scene: Scene, work: Path, calibration: str, base: Any):
    from edge.runtime.config import RuntimeConfig

    cfg = base or RuntimeConfig()
    cal_file = ""
    if calibration == "truth":
        cal_file = str(truth_calibration(scene.seed, work))
    elif calibration != "installer":
        cal_file = calibration
    return cfg.with_overrides(source=scene.url(), sinks=[f"jsonl://{work / scene.name}.bodies.jsonl?rotate_mb=0"],
                              status_file=str(work / f"{scene.name}.status.json"), seconds=0, device="score",
                              calibration=cal_file or None)


def truth_calibration(seed: int, work: Path) -> Path:
    """The calibration a perfect procedure would make for ``sim://?seed=SEED`` (milliseconds), saved in ``work``."""
    from calibration.from_truth import calibration_from_truth
    from sim.live import live_sensor

    path = work / f"calibration-truth-{seed}-{GRID}.npz"
    if not path.exists():
        calibration_from_truth(live_sensor(seed, GRID), device_id=f"sim-{seed}").save(path)
    return path


def capture(scene: Scene, work: Path, calibration: str = "installer", config: Any = None,
            say: Callable[[str], None] = print) -> SceneRun:
    """Run ``scene`` through the runtime and collect what was published and the truth (see the module doc)."""
    from edge.runtime import Runtime, SetupError

    work.mkdir(parents=True, exist_ok=True)
    for old in (work / f"{scene.name}.bodies.jsonl", work / f"{scene.name}.status.json"):
        old.unlink(missing_ok=True)  # a fresh run: seq from 0, no records of an earlier one
    run = SceneRun(scene, "failed")
    try:
        cfg = _config(scene, work, calibration, config)
    except ValueError as exc:  # a bad --config or calibration path: the whole score stops, said plainly
        raise SetupError(str(exc)) from None
    rt = Runtime(cfg, say=lambda text: say(f"  {scene.name}: {text}"))
    times = _FrameTimes(cfg.runtime.timing_window)
    rt.times = times  # before setup: the source and the stages take it from here
    outcomes: dict[int, tuple[str, int | None, float | None]] = {}

    def note(out: Any) -> None:
        seq = out.record["seq"] if out.record is not None and out.record["people"] else None
        outcomes[int(out.frame.frame_seq)] = (out.kind, seq, times.last_frame_ms if out.kind != "invalid" else None)

    rt.on_outcome.append(note)
    t0 = time.monotonic()
    try:
        rt.setup()
    except SetupError as exc:  # e.g. the installer's calibration did not validate (REDO), people that never fit
        run.reason = str(exc)
        return run
    run.calibration = "truth" if calibration == "truth" else str(rt.chosen.path.name)
    run.model = rt.bundle.version
    final = rt.run_for(frames=scene.frames, timeout_s=max(120.0, scene.seconds * 30))
    run.runtime_s = time.monotonic() - t0
    records = _read_records(work / f"{scene.name}.bodies.jsonl")
    done = final["frames"]["frames_in"]
    run.status = "scored" if done >= scene.frames else "partial"
    if run.status == "partial":
        run.reason = f"the runtime took {done} of {scene.frames} frames ({final.get('end_reason')}; {final.get('error')})"
    n = min(scene.frames, max(outcomes, default=-1) + 1)
    for k in range(n):
        kind, seq, ms = outcomes.get(k, ("lost", None, None))
        run.kinds.append(kind)
        run.frame_ms.append(ms)
        run.published.append(records.get(seq, {}).get("people", []) if seq is not None else [])
    run.truth = _truth(scene, n, run)
    return run


def _read_records(path: Path) -> dict[int, dict]:
    """seq → record, from the JSON-lines sink's file (a torn last line is skipped)."""
    out = {}
    if not path.exists():
        return out
    for line in path.read_text().splitlines():
        try:
            rec = json.loads(line)
        except json.JSONDecodeError:
            continue
        out[int(rec["seq"])] = rec
    return out


def _truth(scene: Scene, n: int, run: SceneRun) -> list[list[dict]]:
    """The true people of frames 0..n-1; a scene the simulator cannot place ends the run there (status partial)."""
    from sim.live import LiveCarpet

    truth: list[list[dict]] = []
    try:
        carpet = LiveCarpet(GRID, GRID, scene.people, scene.seed, rate_hz=RATE_HZ, chunk_s=scene.scene_s)
        for k in range(n):
            truth.append(carpet.truth(k))
    except ValueError as exc:
        run.status, run.reason = "partial", f"the simulator could not place frame {len(truth)}'s scene: {exc}"
    del run.kinds[len(truth):], run.frame_ms[len(truth):], run.published[len(truth):]
    return truth
