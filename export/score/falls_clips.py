"""The fall score's clips: simulated scenes → the scene's per-frame body features (cached).

    clips = clip_list(seeds=(3, 4), ordinary_s=30.0)
    feats = clip_features(clips[0], body)      # {"name", "kind", "truth", "seconds", "frames": [[body, …], …]}

Each clip is one scene on a 96×96 carpet at 14 Hz: a fall scenario (sim.motion.falls), a hard
negative (a look-alike, one of the simulator's activities, a pet, a dropped bag beside a standing
person) or ordinary activity. Pressure is the contact model's (sim.contact) plus the objects'
(sim.objects), clean (no sensor model, no calibration: the path a perfect calibration gives); it goes
through the runtime's own SceneTracker and :func:`edge.scene.falls.body_features`, so the detector
sees what it sees on the board: the scene's observations per frame (track, load, area, centre and
pressure moments; edge.scene.falls.observe), merged into bodies when the detector replays them. The model's
activity is not used (the detector then works from pressure alone).
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

RATE_HZ = 14.0
GRID = 96
PITCH_M = 0.01905
CHUNK_S = 10.0
ORDINARY = ("stepping", "bending", "turning", "squat", "twisting", "raising_arms", "lunge", "walking", "standing")
EXERCISE = ("push_up", "sit_up", "sitting")


@dataclass(frozen=True)
class Clip:
    name: str
    kind: str  # fall | lookalike | activity | pet | bag
    what: str  # the scenario / activity
    seed: int
    seconds: float


def clip_list(seeds, ordinary_s: float = 30.0, falls: bool = True, negatives: bool = True) -> list[Clip]:
    from sim.motion.falls import FALLS, LOOKALIKES

    out = []
    for s in seeds:
        if falls:
            out += [Clip(f"{f}-s{s}", "fall", f, s, 0.0) for f in FALLS]
        if negatives:
            out += [Clip(f"{f}-s{s}", "lookalike", f, s, 0.0) for f in LOOKALIKES]
            chunks = max(1, int(round(ordinary_s / CHUNK_S)))  # as the live carpet: a new scene every 10 s
            out += [Clip(f"{a}-s{s}-{i}", "activity", a, s, CHUNK_S) for a in ORDINARY + EXERCISE for i in range(chunks)]
            out += [Clip(f"pet-s{s}", "pet", "pet", s, 2 * ordinary_s), Clip(f"bag-s{s}", "bag", "bag", s, ordinary_s)]
    return out


def _people(clip: Clip, body, rng):
    """[(Track, load fraction (T,))], truth, seconds."""
    from sim.motion import Subject, scene
    from sim.motion.falls import fall_track, on_carpet

    subject = Subject.random(100 + clip.seed, rng)
    size = GRID * PITCH_M
    if clip.kind in ("fall", "lookalike"):
        for attempt in range(4):  # a tall subject's fall may not fit on the carpet: draw another subject
            if attempt:
                subject = Subject.random(100 + clip.seed + 1000 * attempt, rng)
            lie = float(rng.uniform(33.0, 40.0)) if clip.kind == "fall" else float(rng.uniform(20.0, 45.0))
            try:
                ft = on_carpet(fall_track(subject, clip.what, RATE_HZ, rng, body, lie_s=lie), (size, size), rng, body)
                break
            except ValueError:
                if attempt == 3:
                    raise
        return [(ft.track, ft.load_fraction)], ft.truth, ft.truth["seconds"]
    if clip.kind == "pet":
        return [], {"scenario": "pet", "fall": False}, clip.seconds
    acts = [clip.what] if clip.kind == "activity" else ["standing"]
    sc = scene([subject], acts, clip.seconds, RATE_HZ, (size, size), rng, model=body, extend=True)  # as the live carpet
    tr = sc.tracks[0]
    return [(tr, np.ones(len(tr)))], {"scenario": clip.what, "fall": False}, len(tr) / RATE_HZ


class BoardPath:
    """The board's path for one clip: the carpet's sensor model (raw counts: noise, saturation, crosstalk,
    hysteresis, faults) of ``sim://?seed=SEED``, then the runtime's calibration step with the calibration
    the scripted installer session made on that same carpet (cached in ``cal_dir``, one per seed)."""

    def __init__(self, seed: int, cal_dir) -> None:
        from pathlib import Path

        from calibration.file import Calibration
        from calibration.runtime import CalibratedFrames
        from edge.runtime.carpet_calibration import run_sim_session, sim_calibration_path
        from sim.live import live_sensor

        path = sim_calibration_path(Path(cal_dir), seed, GRID)
        if path.exists():
            cal = Calibration.load(path)
        else:  # the session acts on its own sensor of that carpet; the clips get a fresh one
            cal = run_sim_session(live_sensor(seed, GRID, 12, PITCH_M * 1e3), seed, path)
        self.sensor = live_sensor(seed, GRID, 12, PITCH_M * 1e3)  # a fresh carpet of the same seed: clock at 0
        self.step = CalibratedFrames(cal)

    def __call__(self, pressure_kpa: np.ndarray, t_s: float):
        """True pressure → (calibrated pressure kPa or None when refused, masked sensels or None)."""
        out = self.step.process(self.sensor.counts(pressure_kpa, t_s), t_s)
        if out.rejected is not None:
            return None, None
        return out.pressure_kpa, (out.masked if out.masked.any() else None)


def clip_features(clip: Clip, body, path: str = "board", cal_dir="out/falls") -> dict:
    """Run one clip through contact → [sensor → calibration] → SceneTracker → observations (module doc).
    path: "board" (raw counts and calibration, as on the board) or "clean" (the contact model's pressure)."""
    from edge.scene.falls import observe
    from edge.scene.pipeline import SceneTracker
    from sim.contact import ContactModel, regional_tissue, subject_mass_kg
    from sim.objects import DroppedBag, Pet

    rng = np.random.default_rng((clip.seed, sum(map(ord, clip.name))))
    people, truth, seconds = _people(clip, body, rng)
    n = int(round(seconds * RATE_HZ))
    size = GRID * PITCH_M
    objects = []
    if clip.kind == "pet":
        objects.append(Pet.random(rng, size, seconds))
    if clip.kind == "bag":  # dropped beside the person, 0.35–0.8 m from their pelvis
        tr = people[0][0]
        bag = DroppedBag.random(rng, size, drop_s=float(rng.uniform(2, seconds / 2)))
        for _ in range(50):
            ang, dist = rng.uniform(0, 2 * np.pi), rng.uniform(0.35, 0.8)
            c = tr.transl_m[0, :2] + dist * np.array([np.cos(ang), np.sin(ang)])
            if np.all(c > 0.25) and np.all(c < size - 0.25):
                break
        bag.centre_m = tuple(c)
        objects.append(bag)
        truth["bag_kg"] = round(bag.mass_kg, 1)
    carpet = ContactModel(GRID, GRID, pitch_m=PITCH_M)
    tissue = regional_tissue(body)  # as the live carpet and the datasets
    verts = []
    for tr, load in people:
        mass = subject_mass_kg(body, tr.betas)
        v = body.forward(tr.pose_aa[:n], tr.betas, tr.transl_m[:n], vertices=True)["vertices"]
        verts.append((v, mass, load))
    st = SceneTracker(GRID, GRID, PITCH_M)
    board = BoardPath(clip.seed, cal_dir) if path == "board" else None
    frames = []
    t0 = time.perf_counter()
    for k in range(n):
        t = k / RATE_HZ
        p = np.zeros((GRID, GRID), np.float32)
        for v, mass, load in verts:
            if k < len(v) and load[k] > 0:
                p += carpet.pressure_kpa(v[k], body.faces, mass * float(load[k]), static=True,
                                         tissue_kpa_per_mm=tissue).pressure_kpa
        for o in objects:
            p += o.pressure_kpa(t, GRID, GRID, PITCH_M)
        masks = None
        if board is not None:
            p, masks = board(p, t)
        sf = st.update(p, t, masks=masks) if p is not None else None
        obs = observe(sf.people, sf.pressure_kpa, PITCH_M) if sf is not None and sf.valid else []
        frames.append([[o.track_id, round(o.force_n, 2), round(o.area_m2, 6), [round(float(x), 5) for x in o.centre_m],
                        [float(f"{x:.7g}") for x in o.moments]] for o in obs])
    return {"name": clip.name, "kind": clip.kind, "what": clip.what, "seed": clip.seed, "truth": truth,
            "seconds": round(n / RATE_HZ, 3), "path": path, "frames": frames, "sim_s": round(time.perf_counter() - t0, 1)}


def main(argv=None) -> int:
    """python -m export.score.falls_clips OUT.jsonl SEED [SEED …] [--ordinary-s S] [--what A,B]: append clip features."""
    import argparse
    import json
    from pathlib import Path

    from edge.body import BodyModel

    ap = argparse.ArgumentParser(description=main.__doc__)
    ap.add_argument("out")
    ap.add_argument("seeds", type=int, nargs="+")
    ap.add_argument("--ordinary-s", type=float, default=30.0)
    ap.add_argument("--only", choices=("falls", "negatives"))
    ap.add_argument("--what", help="only these scenarios / activities, comma-separated (e.g. slow_collapse,lie_down)")
    ap.add_argument("--path", choices=("board", "clean"), default="board",
                    help="board: sensor model raw counts → calibration (default); clean: the contact model's pressure")
    ap.add_argument("--cal-dir", default="out/falls", help="where the virtual carpets' calibrations are kept")
    a = ap.parse_args(argv)
    clips = clip_list(a.seeds, a.ordinary_s, falls=a.only != "negatives", negatives=a.only != "falls")
    if a.what:
        wanted = set(a.what.split(","))
        unknown = wanted - {c.what for c in clip_list([0], a.ordinary_s)}
        if unknown:
            ap.error(f"--what: unknown {', '.join(sorted(unknown))}; accepted: scenario or activity names of the clip list "
                     "(e.g. slow_collapse,lie_down,sitting,pet,bag)")
        clips = [c for c in clips if c.what in wanted]
    body = BodyModel.load("lite")
    out = Path(a.out)
    done = set()
    if out.exists():
        done = {json.loads(line)["name"] for line in out.read_text().splitlines() if line.strip()}
    for clip in clips:
        if clip.name in done:
            continue
        try:
            got = clip_features(clip, body, a.path, a.cal_dir)
        except ValueError as exc:  # a scene that does not fit on the carpet: say so, go on
            print(f"{clip.name}: skipped ({exc})", flush=True)
            continue
        with out.open("a") as f:
            f.write(json.dumps(got) + "\n")
        print(f"{clip.name}: {got['seconds']} s in {got['sim_s']} s", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
