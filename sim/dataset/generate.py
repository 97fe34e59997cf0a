"""Generate a dataset: motion → posed meshes → contact physics → sensor → shards.

    generate("data/train96", subjects=12, seconds_per_activity=10, people=(1, 3), grid=96, seed=0)

Subjects are split 80/10/10 by subject (at least one in val and test when there are
three or more), so test subjects are never seen in training. Each *sequence* is one
scene of people of one split, and one shard: every subject does every activity once
alone, in an order of their own (three activities per sequence); multi-person scenes are rounds of one activity per
person (people doing several activities in turn would need more floor than a 1.83 m
carpet has; lying activities are left out of 3-person rounds for the same reason). A
round whose people cannot be placed after a few tries is skipped and counted in the
manifest (``skipped_scenes``). Each sequence gets its own carpet session (a random carpet per ``carpets_per_split``
group, a new session per sequence: temperature, drift), so the model sees many carpets.
Everything derives from ``seed``: the same call writes the same files. Sequences are
independent and run on ``workers`` processes.
"""

from __future__ import annotations

import os
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from sim.dataset.format import FAULT_BITS, FRAME_FLAGS, DatasetWriter, Subject

PAPER_ACTIVITIES = ("stepping", "bending", "turning", "squat", "twisting", "raising_arms", "lunge", "sitting", "push_up", "sit_up")


@dataclass(frozen=True)
class Plan:
    """One sequence to render: which subjects, which activities, which carpet, which seeds."""

    index: int
    split: str
    subjects: tuple[int, ...]
    activities: tuple[tuple[str, ...], ...]  # per person
    seconds_per_activity: float
    carpet_seed: int
    session: int
    seed: int


def split_subjects(n: int, rng: np.random.Generator) -> list[str]:
    """80/10/10 by subject, at least one val and one test subject when n ≥ 3."""
    n_test = max(1, round(0.1 * n)) if n >= 3 else 0
    n_val = max(1, round(0.1 * n)) if n >= 3 else 0
    splits = ["test"] * n_test + ["val"] * n_val + ["train"] * (n - n_test - n_val)
    return [splits[i] for i in rng.permutation(n)]


LYING = ("push_up", "sit_up")
ACTIVITIES_PER_SEQUENCE = 3


def _sequences_alone(activities: tuple[str, ...], rng: np.random.Generator) -> list[tuple[str, ...]]:
    """Every activity once, shuffled, ACTIVITIES_PER_SEQUENCE at a time, at most one lying
    activity per sequence (lying forward then backward needs more than a 1.83 m carpet)."""
    lying = [str(a) for a in rng.permutation([a for a in activities if a in LYING])]
    other = [str(a) for a in rng.permutation([a for a in activities if a not in LYING])]
    n_seq = max(len(lying), -(-len(activities) // ACTIVITIES_PER_SEQUENCE))
    seqs: list[list[str]] = [[] for _ in range(n_seq)]
    for i, a in enumerate(lying):
        seqs[i].append(a)
    for i, a in enumerate(other):
        seqs[min(range(n_seq), key=lambda k: (len(seqs[k]), k))].append(a)
    return [tuple(rng.permutation(q).tolist()) for q in seqs if q]


def plan_sequences(subject_splits: list[str], people: tuple[int, int], activities: tuple[str, ...],
                   seconds_per_activity: float, rng: np.random.Generator, carpets_per_split: int = 3) -> list[Plan]:
    """Every subject does every activity once alone; multi-person rounds are added on top."""
    plans: list[Plan] = []
    lo, hi = people

    def add(split: str, group: tuple[int, ...], acts: tuple[tuple[str, ...], ...]) -> None:
        plans.append(Plan(len(plans), split, group, acts, seconds_per_activity,
                          carpet_seed=int(rng.integers(carpets_per_split)) + 1000 * ("train", "val", "test").index(split),
                          session=len(plans), seed=int(rng.integers(2**31))))

    for split in ("train", "val", "test"):
        members = [i for i, s in enumerate(subject_splits) if s == split]
        if lo <= 1:  # alone: every activity, in an order of their own, a few per sequence (a lying
            for m in members:  # person's reach over many activities may not fit the carpet at once)
                for seq in _sequences_alone(activities, rng):
                    add(split, (m,), (seq,))
        for k in range(max(2, lo), hi + 1):
            if len(members) < k:
                continue
            pool = [a for a in activities if k < 3 or a not in LYING] or list(activities)
            for _ in range(max(1, len(members) // k) * max(1, len(activities) // 2)):
                group = tuple(int(x) for x in rng.choice(members, size=k, replace=False))
                add(split, group, tuple((str(rng.choice(pool)),) for _ in group))
    return plans


class Renderer:
    """Per-process models (body, contact, tissue), reused across sequences."""

    def __init__(self, grid: int, pitch_m: float, rate_hz: float, adc_bits: int, body: str = "lite") -> None:
        from edge.body import BodyModel
        from sim.contact import ContactModel, regional_tissue

        self.grid, self.pitch_m, self.rate_hz, self.adc_bits = grid, pitch_m, rate_hz, adc_bits
        self.body = BodyModel.load(body)
        self.contact = ContactModel(grid, grid, pitch_m=pitch_m)
        self.tissue = regional_tissue(self.body)

    def render(self, plan: Plan, subject_list: list[Any]) -> dict[str, np.ndarray]:
        from sim.contact.track import track_contacts, track_dynamics
        from sim.motion import scene
        from sim.sensor import CarpetSensor, FrameStream, StreamConfig

        subjects = [subject_list[i] for i in plan.subjects]
        size = self.grid * self.pitch_m
        sc = place_scene(scene, subjects, [list(a) for a in plan.activities], plan.seconds_per_activity, self.rate_hz, size,
                         plan.seed, self.body, extend=True)
        n, p_max = sc.num_frames, 3
        pressure = np.zeros((n, self.grid, self.grid), np.float32)
        out = {
            "present": np.zeros((n, p_max), bool), "subject": np.full((n, p_max), -1, np.int16),
            "activity": np.full((n, p_max), -1, np.int8), "pose_aa": np.zeros((n, p_max, 72), np.float32),
            "betas": np.zeros((n, p_max, 10), np.float32), "transl_m": np.zeros((n, p_max, 3), np.float32),
            "joints_m": np.zeros((n, p_max, 24, 3), np.float32),
        }
        for slot, (track, subj_index) in enumerate(zip(sc.tracks, plan.subjects)):
            fw, dyn = track_dynamics(self.body, track)
            joints = fw["joints"]
            for t, res in enumerate(track_contacts(self.contact, self.body, self.tissue, track, fw, dyn)):
                pressure[t] += res.pressure_kpa
            out["present"][:, slot] = True
            out["subject"][:, slot] = subj_index
            out["activity"][:, slot] = track.activity
            out["pose_aa"][:, slot] = track.pose_aa
            out["betas"][:, slot] = track.betas
            out["transl_m"][:, slot] = track.transl_m
            out["joints_m"][:, slot] = joints
        sensor = CarpetSensor.random(plan.carpet_seed, grid=self.grid, adc_bits=self.adc_bits, pitch_mm=self.pitch_m * 1e3)
        sensor.start_session(plan.session)
        stream = FrameStream(sensor, StreamConfig(drop_rate=0.003, duplicate_rate=0.003, tear_rate=0.002, jitter_s=0.002),
                             seed=plan.seed)
        counts, t_s, flags, truth = [], [], [], []
        for c, ts, fl in stream.frames(pressure):
            counts.append(c)
            t_s.append(ts)
            truth.append(fl.seq)  # dropped frames are never yielded: ground truth follows the true frame
            flags.append(FRAME_FLAGS["after_drop"] * (fl.dropped_before > 0) | FRAME_FLAGS["torn"] * bool(fl.torn)
                         | FRAME_FLAGS["duplicate"] * fl.duplicate | FRAME_FLAGS["corrupt"] * bool(fl.corrupt))
        truth = np.asarray(truth)
        out = {k: v[truth] for k, v in out.items()}
        pressure = pressure[truth]
        counts = np.stack(counts)
        t_s = np.asarray(t_s)
        flags = np.asarray(flags, np.uint8)
        n = len(counts)
        fault = np.zeros((self.grid, self.grid), np.uint8)
        for kind, mask in sensor.fault_masks.items():
            if kind in FAULT_BITS:
                fault[mask] |= FAULT_BITS[kind]
        return {"counts": counts, "pressure_kpa": pressure.astype(np.float16), "t_s": t_s,
                "sequence": np.zeros(n, np.int32), "frame_flags": flags, "fault_mask": fault, **out}


def place_scene(scene_fn, subjects, activities, seconds_per_activity, rate_hz, size_m, seed, body, attempts: int = 4,
                extend: bool = False):
    """A scene of these people, retrying with new orders and places when they do not fit
    (extend: activities take the time they need, ``sim.motion.scene``).

    Several large people doing lying activities may not fit a 1.83 m carpet at all; after
    ``attempts`` the error says so (the caller chooses smaller groups).
    """
    last = None
    for attempt in range(attempts):
        rng = np.random.default_rng((seed, attempt))
        try:
            return scene_fn(subjects, activities, seconds_per_activity, rate_hz, (size_m, size_m), rng, model=body,
                            tries=40 if len(subjects) == 1 else 10, extend=extend)
        except ValueError as exc:
            last = exc
    raise ValueError(f"{len(subjects)} people doing {activities} did not fit the carpet in {attempts} attempts: {last}")


_RENDERERS: dict[tuple, Renderer] = {}  # per process, by settings: models are loaded once


def _worker(args: tuple) -> tuple[int, dict[str, np.ndarray] | None]:
    """Render one plan; None when its people could not be placed on the carpet."""
    plan, subjects, settings = args
    key = tuple(sorted(settings.items()))
    if key not in _RENDERERS:
        _RENDERERS[key] = Renderer(**settings)
    try:
        return plan.index, _RENDERERS[key].render(plan, subjects)
    except ValueError:  # the people could not be placed on the carpet: recorded as skipped
        return plan.index, None


def _calibrate(args: tuple):
    from sim.dataset.calibrate import carpet_calibration

    carpet, grid, adc_bits, pitch_mm, method = args
    return carpet_calibration(carpet, grid=grid, adc_bits=adc_bits, pitch_mm=pitch_mm, method=method)


def generate(out_dir: str | Path, *, subjects: int = 12, seconds_per_activity: float = 10.0, people: tuple[int, int] = (1, 1),
             grid: int = 96, pitch_mm: float = 19.05, rate_hz: float = 14.0, adc_bits: int = 12, seed: int = 0,
             activities: tuple[str, ...] = PAPER_ACTIVITIES, workers: int = 1, body: str = "lite",
             progress: bool = True, overwrite: bool = False, calibration: str | None = None) -> Path:
    """calibration: None, "installer" or "truth" — also write each carpet's calibration
    (``calibration-<carpet>.npz``, see sim.dataset.calibrate), listed in the manifest and named
    by each shard's ``carpet``, so that the board's path (counts → calibration → kPa) can be read
    (export.data.load_tracks(board=True))."""
    from sim.motion import ACTIVITIES
    from sim.motion import Subject as MotionSubject

    _check_arguments(people, activities, calibration, seconds_per_activity, rate_hz)
    rng = np.random.default_rng(seed)
    motion_subjects = [MotionSubject.random(i, seed * 1000 + i) for i in range(subjects)]
    splits = split_subjects(subjects, rng)
    plans = plan_sequences(splits, people, tuple(activities), seconds_per_activity, rng)
    settings = {"grid": grid, "pitch_m": pitch_mm / 1000, "rate_hz": rate_hz, "adc_bits": adc_bits, "body": body}
    subject_records = [Subject(f"s{i:02d}", splits[i], [float(b) for b in s.betas]) for i, s in enumerate(motion_subjects)]
    writer = DatasetWriter(out_dir, rows=grid, cols=grid, pitch_m=pitch_mm / 1000, rate_hz=rate_hz, activities=list(ACTIVITIES),
                           subjects=subject_records, source="sim", overwrite=overwrite,
                           settings={"seed": seed, "subjects": subjects, "seconds_per_activity": seconds_per_activity,
                                     "people": list(people), "activities": list(activities), "adc_bits": adc_bits, "body": body,
                                     "calibration": calibration})
    os.environ["OMP_NUM_THREADS"] = os.environ["OPENBLAS_NUM_THREADS"] = "1"  # BLAS threads fight on 2 cores (workers inherit)
    jobs = [(p, motion_subjects, settings) for p in plans]
    shards = _InPlanOrder(writer, plans, progress)
    carpets = sorted({p.carpet_seed for p in plans}) if calibration else []
    cal_jobs = [(c, grid, adc_bits, pitch_mm, calibration) for c in carpets]
    if workers <= 1:
        calibrations = [_calibrate(job) for job in cal_jobs]
        for job in jobs:
            shards.put(*_worker(job))
    else:
        with ProcessPoolExecutor(max_workers=workers) as pool:
            calibrations = list(pool.map(_calibrate, cal_jobs))
            for index, arrays in pool.map(_worker, jobs):
                shards.put(index, arrays)
    if calibration:
        _list_calibrations(writer, Path(out_dir), carpets, calibrations, calibration)
    writer.close()
    if progress:
        print(file=sys.stderr)
    return Path(out_dir)


def _check_arguments(people: tuple[int, int], activities: tuple[str, ...], calibration: str | None,
                     seconds_per_activity: float, rate_hz: float) -> None:
    from sim.dataset.calibrate import METHODS
    from sim.motion import ACTIVITIES

    if not 1 <= people[0] <= people[1] <= 3:
        raise ValueError(f"people must be a range within 1..3, got {people}")
    if not round(seconds_per_activity * rate_hz) >= 2:  # (every sequence would be skipped: 0 frames written)
        raise ValueError(f"seconds per activity must give at least 2 frames at {rate_hz:g} Hz, got {seconds_per_activity:g} s")
    if calibration is not None and calibration not in METHODS:
        raise ValueError(f"calibration must be one of {METHODS}, got {calibration!r}")
    unknown = [a for a in activities if a not in ACTIVITIES]
    if unknown:
        raise ValueError(f"unknown activities {unknown}; known: {list(ACTIVITIES)}")


class _InPlanOrder:
    """Writes the shards in plan order, whatever order the workers finish in, and reports progress."""

    def __init__(self, writer: DatasetWriter, plans: list, progress: bool) -> None:
        self.writer, self.plans, self.progress = writer, plans, progress
        self.t0, self.done, self.frames, self.next_index = time.monotonic(), 0, 0, 0
        self.results: dict[int, dict[str, np.ndarray] | None] = {}

    def put(self, index: int, arrays: dict[str, np.ndarray] | None) -> None:
        self._report(arrays)
        self.results[index] = arrays
        while self.next_index in self.results:
            arrays = self.results.pop(self.next_index)
            plan = self.plans[self.next_index]
            if arrays is None:
                self.writer.manifest.setdefault("skipped_scenes", []).append(
                    {"subjects": list(plan.subjects), "activities": [list(a) for a in plan.activities]})
            else:
                self.writer.write_shard(arrays, {"split": plan.split, "subjects": list(plan.subjects), "seed": plan.seed,
                                                 "people": len(plan.subjects), "carpet": plan.carpet_seed})
            self.next_index += 1

    def _report(self, arrays: dict[str, np.ndarray] | None) -> None:
        self.done += 1
        self.frames += 0 if arrays is None else len(arrays["counts"])
        if self.progress:
            el = time.monotonic() - self.t0
            eta = el / self.done * (len(self.plans) - self.done)
            bar = "#" * int(30 * self.done / len(self.plans))
            print(f"\r[{bar:<30}] {self.done}/{len(self.plans)} sequences, {self.frames} frames, "
                  f"{self.frames / el:.0f} frames/s, ETA {eta:.0f} s", end="", file=sys.stderr, flush=True)


def _list_calibrations(writer: DatasetWriter, out_dir: Path, carpets: list, calibrations: list, method: str) -> None:
    """Save each carpet's calibration beside the shards and list it (file, method, hash) in the manifest."""
    writer.manifest["calibrations"] = {}
    for c, cal in zip(carpets, calibrations):
        name = f"calibration-{c}.npz"
        digest = cal.save(out_dir / name)
        writer.manifest["calibrations"][str(c)] = {"file": name, "method": method, "sha256": digest,
                                                   "validation_ok": cal.validation.get("ok")}
