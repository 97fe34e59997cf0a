"""People segmentation and tracking quality of the scene step on the board's path, against the
simulator's per-person truth. Writes bench/results/scene_quality.json.

    OMP_NUM_THREADS=1 python -m bench.scene_quality [--quick] [--cache DIR]

Scenes: every activity alone (6 s each, two seeds), 2 and 3 people doing upright activities side by
side (8 s each), placed by the simulator (``sim.dataset.generate.place_scene``), and 30 s of
``sim://?people=N&seed=S``'s own stream (``sim.live.LiveCarpet``: a new scene every 10 s, the
people reappearing elsewhere at once, which no real person does). Each frame: every
person's TRUE pressure (``sim.contact``) → summed → the virtual carpet's sensor (raw counts) →
``calibration.runtime.CalibratedFrames`` with the calibration a perfect procedure would make →
``edge.scene.SceneTracker`` with the default configuration. The placed scenes' per-person
pressure is cached (``--cache``, default /tmp/scene_quality_cache) so reruns only time the scene.

Per frame, reported tracks are matched to true people on the pressure they share (Hungarian on
the true person's pressure inside the track's mask; a pair needs ≥ 20 % of the person's pressure):
- count right: reported tracks == true people on the carpet (more than 20 N of their own pressure);
  every scene starts with everyone on the carpet, so its first birth_frames − 1 = 2 frames miss them
  by design (a track is reported from its third observation): count_right_after_birth leaves them out;
- extra: unmatched tracks; missed: unmatched people; identity switch: a person matched to
  another track id than at their last match; MOTA = 1 − (missed + extra + switches) / person-frames;
- mask IoU over loaded sensels (true total > 0.2 kPa, the model's input floor): the track's mask
  against the sensels where the matched person's true pressure is the largest (the truth's
  assignment). With one person the model was trained on the whole frame, so the truth is every
  loaded sensel;
- trained mask IoU over the whole grid: the track's mask against the mask the model was trained
  with (``export.data.footprint_masks``: the person's loaded sensels, nearest-joint assignment
  between several, grown by 2 sensels), i.e. how closely the runtime's per-person input matches
  the training input; with the share of the trained mask the track's covers, and of the track's
  mask inside the trained one (which of the two is larger).
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from pathlib import Path

for var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(var, "1")

import numpy as np  # noqa: E402
from scipy.optimize import linear_sum_assignment  # noqa: E402

from bench.machine import describe  # noqa: E402

RATE_HZ = 14.0
FLOOR_KPA = 0.2
PITCH_M = 0.01905
PRESENT_N = 20.0
BIRTH_FRAMES = 3  # SceneConfig().birth_frames: everyone is on the carpet at a scene's first frame
ALONE = ("stepping", "bending", "turning", "squat", "twisting", "raising_arms", "lunge", "sitting", "push_up", "sit_up",
         "walking")
GROUPS = {2: [("lunge", "sitting"), ("walking", "stepping"), ("squat", "turning"), ("bending", "twisting")],
          3: [("stepping", "squat", "raising_arms"), ("walking", "twisting", "bending"), ("turning", "squat", "stepping")]}


# (people, seed) of sim://'s own stream, a new scene every 10 s (with 3 people, seeds 1 and 2 stop at a
# scene the simulator cannot place: sim.live.place_chunk raises)
STREAMS = [(2, 1), (2, 2)]
STREAM_S = 30.0


def scene_list(quick: bool) -> list[tuple[str, tuple[str, ...], float, int]]:
    """(name, activities per person (or ("live",) * people for a sim:// stream), seconds, seed)."""
    alone = [(f"alone-{a}-{seed}", (a,), 6.0, seed) for seed in (11, 12) for a in ALONE]
    multi = [(f"{k}p-{'-'.join(acts)}", acts, 8.0, 21 + i) for k, rows in GROUPS.items() for i, acts in enumerate(rows)]
    streams = [(f"sim-{k}p-seed{seed}", ("live",) * k, STREAM_S, seed) for k, seed in STREAMS]
    if quick:
        alone = [s for s in alone if s[1][0] in ("lunge", "push_up", "sit_up", "sitting") and s[3] == 11]
        multi = multi[:1] + multi[4:5]  # one of 2 people, one of 3
        streams = []
    return alone + multi + streams


def render_live(people: int, seconds: float, seed: int, cache: Path) -> dict[str, np.ndarray]:
    """sim://?people=N&seed=S's own scenes (sim.live.LiveCarpet: the same people, a new scene every 10 s), per person."""
    path = cache / f"live-{people}p-{seconds:g}s-{seed}.npz"
    if path.exists():
        with np.load(path) as z:
            if "joints_m" in z.files:  # a cache from before the joints were kept is made again
                return {k: z[k] for k in z.files}
    from sim.live import LiveCarpet

    lc = LiveCarpet(96, 96, people, seed)
    n = int(round(seconds * RATE_HZ))
    own = np.zeros((n, people, 96, 96), np.float16)
    transl = np.zeros((n, people, 3), np.float32)
    joints = np.zeros((n, people, 24, 3), np.float32)
    names = np.empty((n, people), dtype=object)
    for t in range(n):
        for j, (person, mass) in enumerate(zip(lc.truth(t), lc.mass_kg)):
            v = lc.body.forward(person["pose_aa"][None], person["betas"][None], person["transl_m"][None], vertices=True)
            res = lc.contact.pressure_kpa(v["vertices"][0], lc.body.faces, mass, static=True, tissue_kpa_per_mm=lc.tissue)
            own[t, j], transl[t, j], names[t, j] = res.pressure_kpa, person["transl_m"], person["activity"]
            joints[t, j] = v["joints"][0]
    lc.close()
    out = {"own_kpa": own, "transl_m": transl, "joints_m": joints, "activity": names.astype(str)}
    cache.mkdir(parents=True, exist_ok=True)
    np.savez_compressed(path, **out)
    return out


def render(activities: tuple[str, ...], seconds: float, seed: int, cache: Path) -> dict[str, np.ndarray]:
    """Per-person true pressure (F, P, H, W) float16, pelvis (F, P, 3), activity names (F, P)."""
    path = cache / f"{'-'.join(activities)}-{seconds:g}s-{seed}.npz"
    if path.exists():
        with np.load(path) as z:
            if "joints_m" in z.files:  # a cache from before the joints were kept is made again
                return {k: z[k] for k in z.files}
    from edge.body import BodyModel
    from sim.contact import ContactModel, subject_mass_kg, tissue_stiffness
    from sim.dataset.generate import place_scene
    from sim.motion import Subject, scene

    body = BodyModel.load("lite")
    contact = ContactModel(96, 96, pitch_m=0.01905)
    tissue = tissue_stiffness(body)
    subjects = [Subject.random(i, seed * 1000 + i) for i in range(len(activities))]
    masses = [subject_mass_kg(body, s.betas) for s in subjects]
    sc = place_scene(scene, subjects, [[a] for a in activities], seconds, RATE_HZ, 96 * 0.01905, (seed, 0), body, attempts=3)
    n = sc.num_frames
    own = np.zeros((n, len(subjects), 96, 96), np.float16)
    transl = np.zeros((n, len(subjects), 3), np.float32)
    joints = np.zeros((n, len(subjects), 24, 3), np.float32)
    names = np.empty((n, len(subjects)), dtype=object)
    for t in range(n):
        for j, (tr, mass) in enumerate(zip(sc.tracks, masses)):
            v = body.forward(tr.pose_aa[t][None], tr.betas[None], tr.transl_m[t][None], vertices=True)
            res = contact.pressure_kpa(v["vertices"][0], body.faces, mass, static=True, tissue_kpa_per_mm=tissue)
            own[t, j] = res.pressure_kpa
            transl[t, j] = tr.transl_m[t]
            joints[t, j] = v["joints"][0]
            names[t, j] = tr.activity_names[t]
    out = {"own_kpa": own, "transl_m": transl, "joints_m": joints, "activity": names.astype(str)}
    cache.mkdir(parents=True, exist_ok=True)
    np.savez_compressed(path, **out)
    return out


def run_scene(data: dict[str, np.ndarray], sensor_seed: int, config=None) -> dict:
    """The board's path over one scene → per-frame rows and the scene step's times."""
    from calibration.from_truth import calibration_from_truth
    from calibration.runtime import CalibratedFrames
    from edge.scene import SceneTracker
    from sim.live import live_sensor

    sensor = live_sensor(sensor_seed, 96)
    calibrated = CalibratedFrames(calibration_from_truth(sensor, device_id=f"sim-{sensor_seed}"))
    st = SceneTracker(96, 96, 0.01905, config)
    own = data["own_kpa"].astype(np.float32)
    rows, times = [], []
    last_match: dict[int, int] = {}
    for t in range(len(own)):
        t_s = t / RATE_HZ
        total = own[t].sum(axis=0)
        cal = calibrated.process(sensor.counts(total, t_s), t_s)
        if cal.rejected is not None:
            continue
        t0 = time.perf_counter()
        sf = st.update(cal.pressure_kpa, t_s, masks=cal.masked if cal.masked.any() else None)
        times.append((time.perf_counter() - t0) * 1e3)
        rows.append({**score_frame(own[t], sf.people, data["activity"][t], last_match, data["joints_m"][t]), "frame": t})
    return {"rows": rows, "times_ms": times}


def score_frame(own: np.ndarray, people: list, activity: np.ndarray, last_match: dict[int, int],
                joints_m: np.ndarray) -> dict:
    """own (P, H, W) true kPa per person; people: the scene's PersonObservations; joints_m (P, 24, 3)."""
    from export.data import footprint_masks

    total = own.sum(axis=0)
    loaded = total > FLOOR_KPA
    force = own.reshape(len(own), -1).sum(axis=1)
    present = [p for p in range(len(own)) if force[p] * 0.01905**2 * 1e3 > PRESENT_N]
    owner = own.argmax(axis=0)
    share = np.array([[own[p][q.mask].sum() / max(force[p], 1e-9) for p in present] for q in people]).reshape(len(people), len(present))
    matched = {}
    if people and present:
        r, c = linear_sum_assignment(-share)
        matched = {present[j]: i for i, j in zip(r, c) if share[i, j] >= 0.2}
    switches, ious, trained = 0, [], []
    is_present = np.zeros(len(own), bool)
    is_present[present] = True
    footprints = footprint_masks(total, joints_m, is_present, PITCH_M, FLOOR_KPA)  # what the model was trained on
    for p, i in matched.items():
        tid = people[i].track_id
        switches += p in last_match and last_match[p] != tid
        last_match[p] = tid
        truth = loaded if len(present) == 1 else loaded & (owner == p)
        got = loaded & people[i].mask
        ious.append(float((truth & got).sum() / max((truth | got).sum(), 1)))
        both = float((footprints[p] & people[i].mask).sum())
        trained.append((both / max(float((footprints[p] | people[i].mask).sum()), 1.0),
                        both / max(float(footprints[p].sum()), 1.0), both / max(float(people[i].mask.sum()), 1.0)))
    return {"true": len(present), "reported": len(people), "missed": len(present) - len(matched),
            "extra": len(people) - len(matched), "switches": int(switches), "ious": ious, "trained_ious": trained,
            "activity": str(activity[present[0]]) if len(present) == 1 else "several"}


def summarise(rows: list[dict]) -> dict:
    n = len(rows)
    pf = sum(r["true"] for r in rows)
    ious = [x for r in rows for x in r["ious"]]
    trained = [tuple(x) for r in rows for x in r["trained_ious"]]
    missed, extra, sw = (sum(r[k] for r in rows) for k in ("missed", "extra", "switches"))
    settled = [r for r in rows if r["frame"] >= BIRTH_FRAMES - 1]
    return {"frames": n, "person_frames": pf, "count_right": round(sum(r["true"] == r["reported"] for r in rows) / max(n, 1), 4),
            "frames_with_extra": round(sum(r["reported"] > r["true"] for r in rows) / max(n, 1), 4),
            "missed": missed, "extra": extra, "id_switches": sw, "mota": round(1 - (missed + extra + sw) / max(pf, 1), 4),
            "count_right_after_birth": round(sum(r["true"] == r["reported"] for r in settled) / max(len(settled), 1), 4),
            "mask_iou_mean": round(float(np.mean(ious)), 4) if ious else None,
            "mask_iou_p10": round(float(np.percentile(ious, 10)), 4) if ious else None,
            **_trained(trained)}


def _trained(trained: list[tuple[float, float, float]]) -> dict:
    """Means of (IoU, share of the trained mask inside the track's, share of the track's inside the trained) and the IoU's p10."""
    if not trained:
        return {"trained_mask_iou_mean": None, "trained_mask_iou_p10": None, "trained_mask_covered_mean": None,
                "track_mask_inside_trained_mean": None}
    t = np.array(trained)
    return {"trained_mask_iou_mean": round(float(t[:, 0].mean()), 4), "trained_mask_iou_p10": round(float(np.percentile(t[:, 0], 10)), 4),
            "trained_mask_covered_mean": round(float(t[:, 1].mean()), 4),
            "track_mask_inside_trained_mean": round(float(t[:, 2].mean()), 4)}


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="the four hardest single-person activities and two group scenes")
    ap.add_argument("--cache", type=Path, default=Path("/tmp/scene_quality_cache"), help="placed scenes' per-person pressure")
    ap.add_argument("--out", type=Path, default=Path(__file__).parent / "results" / "scene_quality.json")
    ap.add_argument("--before", type=Path, help="a result of this bench on the code before a change, kept beside as 'before'")
    ap.add_argument("--before-code", default="d34ed20 (edge/scene before the body-aware grouping)",
                    help="what code --before was measured on")
    args = ap.parse_args(argv)
    scenes, all_rows, all_times = [], [], []
    for name, acts, seconds, seed in scene_list(args.quick):
        try:
            live = acts[0] == "live"
            data = render_live(len(acts), seconds, seed, args.cache) if live else render(acts, seconds, seed, args.cache)
        except ValueError as exc:
            print(f"{name}: skipped ({exc})")
            continue
        res = run_scene(data, sensor_seed=seed)
        for r in res["rows"]:
            r["scene"] = name
        all_rows += res["rows"]
        all_times += res["times_ms"]
        s = {"scene": name, "people": len(acts), **summarise(res["rows"]),
             "scene_step_median_ms": round(float(np.median(res["times_ms"])), 3)}
        scenes.append(s)
        print(json.dumps(s))
    by_people = {f"{k}_people": summarise([r for r in all_rows if r["true"] == k]) for k in (1, 2, 3)}
    alone = [r for r in all_rows if r["true"] == 1]
    by_activity = {a: summarise([r for r in alone if r["activity"] == a]) for a in sorted({r["activity"] for r in alone})}
    command = " ".join(["OMP_NUM_THREADS=1 python -m bench.scene_quality", *(sys.argv[1:] if argv is None else argv)])
    out = {"benchmark": "scene_quality", "command": command,
           "machine": describe(), "method": __doc__.split("\n\n", 2)[2].strip(),
           "by_people": by_people, "alone_by_activity": by_activity, "scenes": scenes,
           "scene_step_ms": {"median": round(float(np.median(all_times)), 3), "p99": round(float(np.percentile(all_times, 99)), 3)}}
    if args.before:
        old = json.loads(args.before.read_text())
        out["before"] = {k: old[k] for k in ("command", "by_people", "alone_by_activity", "scene_step_ms")}
        out["before"]["code"] = args.before_code
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(out, indent=1) + "\n")
    print(json.dumps(by_people, indent=1))
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
