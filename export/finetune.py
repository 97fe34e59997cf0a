"""Fine-tune a bundle for a new user (the paper's recipe: the pre-trained model, lr 3e-5, a fraction of the user's data).

    report = finetune("edge/models/lean-96", data="/data/new_user", fraction=0.5, out="models/lean-96-anna")

The user's tracks are split in TIME: the first ``fraction`` of every track trains, the rest is
held out (the gate and the reported metrics use it), so no held-out frame is a neighbour of a
training frame in the same window. ``fraction=0`` only evaluates. The result is a new bundle
(int8 gate and all), its manifest naming the bundle it came from.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from export.data import Track


def split_in_time(tracks: list[Track], fraction: float, min_frames: int = 2) -> tuple[list[Track], list[Track]]:
    """(first ``fraction`` of every track, the rest); pieces shorter than ``min_frames`` are dropped."""
    if not 0.0 <= fraction < 1.0:
        raise ValueError(f"fraction must be in [0, 1), got {fraction}")
    head, rest = [], []
    for t in tracks:
        cut = int(round(fraction * len(t)))
        a, b = track_slice(t, 0, cut), track_slice(t, cut, len(t))
        if len(a) >= min_frames:
            head.append(a)
        if len(b) >= min_frames:
            rest.append(b)
    return head, rest


def track_slice(t: Track, start: int, stop: int) -> Track:
    return t.slice(start, stop)


def user_tracks(data: str | Path, split: str = "all", subjects: list[str] | None = None,
                board: bool = False) -> tuple[list[Track], float, Any]:
    """Tracks of ``split`` ("all" for every split: a new user's own recording) of the chosen subjects;
    ``board``: their input on the board's path (export.data.load_tracks)."""
    from export.data import load_tracks
    from sim.dataset import Dataset

    ds = Dataset(data)
    splits = ("train", "val", "test") if split == "all" else (split,)
    tracks = [t for s in splits for t in load_tracks(ds, s, board=board)]
    if subjects:
        ids = {int(s.lstrip("s")) for s in subjects}
        tracks = [t for t in tracks if t.subject in ids]
    if not tracks:
        raise ValueError(f"{data}: no tracks in split {split!r}" + (f" for subjects {subjects}" if subjects else ""))
    return tracks, float(ds.manifest["pitch_m"]), ds


def finetune(bundle: str | Path, data: str | Path, fraction: float, out: str | Path, *, steps: int = 300, lr: float = 3e-5,
             stage: str = "windows", batch: int = 16, chunks: int = 4, split: str = "all", subjects: list[str] | None = None,
             seed: int = 0, threads: int = 1, progress: bool = True, precision: str = "int8",
             held_out_from: float | None = None) -> dict[str, Any]:
    """Fine-tune ``bundle`` on the first ``fraction`` of the user's tracks; write the bundle ``out``; report.

    ``held_out_from``: hold out the frames from this fraction of every track on (default: ``fraction``), so
    a sweep over fractions is judged on one held-out set (frames between the two are unused)."""
    import tempfile

    from export.bundle import bundle_from_net, load_net, update_manifest
    from export.train import TrainConfig, Trainer

    net, manifest = load_net(bundle)
    tracks, pitch, ds = user_tracks(data, split, subjects)
    start = fraction if held_out_from is None else held_out_from
    if start < fraction:
        raise ValueError(f"held_out_from {start} is before the end of the training fraction {fraction}")
    train = split_in_time(tracks, fraction)[0]
    held_out = split_in_time(tracks, start)[1]
    if not held_out:
        raise ValueError(f"fraction {fraction} leaves no held-out frames to check the fine-tuned model on")
    if fraction > 0 and not train:
        raise ValueError(f"fraction {fraction} leaves no track of ≥ 2 frames to fine-tune on")
    source = f"{manifest['name']}@{manifest['files']['encoder.onnx'][:12]}"
    with tempfile.TemporaryDirectory() as tmp:
        if fraction > 0:
            cfg = TrainConfig(data=str(data), out=tmp, stage=stage, steps=steps, batch=batch, chunks=chunks, lr=lr,
                              optimizer="adam", weight_decay=1e-3, seed=seed, threads=threads, val_every=0,
                              checkpoint_every=10**9, progress=progress)
            trainer = Trainer(cfg, net.cfg, tracks=train, val_tracks=[])
            trainer.net.load_state_dict(net.state_dict())
            trainer.run()
            net = trainer.net.to("cpu").eval()
    name = f"{manifest['name']}-ft{int(round(100 * fraction))}"
    training = {"finetuned_from": source, "data": str(data), "split": split, "subjects": subjects or "all",
                "fraction": fraction, "steps": steps if fraction > 0 else 0, "lr": lr, "stage": stage, "seed": seed,
                "held_out_from": start, "frames_trained": int(sum(len(t) for t in train)),
                "frames_held_out": int(sum(len(t) for t in held_out))}
    report = bundle_from_net(net, out, name, pitch_m=pitch, rate_hz=float(ds.manifest.get("rate_hz", 14.0)),
                             calib_tracks=(train or held_out)[:8], gate_tracks=held_out, gate_split="held-out (time split)",
                             training=training, precision=precision, seed=seed)
    if "baseline" in manifest:
        update_manifest(out, baseline=manifest["baseline"])
    report["held_out"] = held_out
    return report
