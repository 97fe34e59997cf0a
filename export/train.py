"""Train the CAvatar model on a simulated dataset (CPU by default, CUDA when present).

    python -m export.train --data /work/data/sim96 --out runs/lean --preset lean --steps 5000
    cavatar train --data /work/data/sim96 --out runs/lean --resume

Stages (``stage``, export/stages.py says why): ``frames`` trains the encoder with a one-frame
head on B frames drawn independently from all tracks; ``head`` freezes the encoder, caches
every frame's features and trains the temporal head on B independent windows; ``windows``
(end to end) takes ``chunks`` chunks of B+T-1 consecutive frames of one person each, every
frame of a chunk encoded ONCE and unfolded into B overlapping windows of T. ``init`` starts a
stage from another run's weights. ``data`` may name several datasets of one grid (the first
one's val split validates). The run folder holds ``config.json``, ``checkpoint.pt`` (model, discriminator, optimisers, step,
every RNG state; written every ``checkpoint_every`` steps, at the end and on SIGINT) and
``log.jsonl`` (one line of losses per ``log_every`` steps, one per validation).
"""

from __future__ import annotations

import json
import math
import random
import signal
import sys
import time
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import torch

from cavatar_common.atomic import atomic_path
from cavatar_common.config import strict_from_dict
from export.model import CAvatarNet, JointDiscriminator, ModelConfig

CHECKPOINT = "checkpoint.pt"


@dataclass
class TrainConfig:
    """Everything a run needs besides the model configuration."""

    data: str | list[str] = ""      # a dataset folder, or several (same grid and pitch)
    out: str = "runs/lean"
    stage: str = "windows"          # "frames", "head" or "windows" (export/stages.py)
    init: str = ""                  # checkpoint whose model (and frame head) weights start this run
    cache_copies: int = 2           # stage "head": corruption copies of every frame in the feature cache (copy c turned c·90°)
    input: str = "clean"            # "clean": true pressure through export.data.corrupt; "board": the board's path
    turns: bool = True              # turn the carpet by random quarter turns (frames, head stages; export/stages.py)
    exclude_activities: list[str] = field(default_factory=list)  # leave-one-activity-out: these never train
    steps: int = 5000
    batch: int = 32                 # B windows per chunk
    chunks: int = 1                 # chunks (of different tracks) per step
    lr: float = 1e-4
    lr_schedule: str = "constant"   # "constant" or "cosine" (to lr/100 at `steps`; a function of the step, so resume-safe)
    weight_decay: float = 1e-3
    optimizer: str = "adam"         # "adam" (the paper's: L2 added to the gradient) or "adamw" (decoupled decay)
    seed: int = 0
    checkpoint_every: int = 200
    val_every: int = 500
    val_frame_stride: int = 4       # validation MPJPE on every 4th frame of every val track
    log_every: int = 10
    device: str = "auto"            # "auto": CUDA when present, else CPU
    threads: int = 0                # torch intra-op threads (0: torch's default)
    progress: bool = True
    model: dict[str, Any] = field(default_factory=dict)  # ModelConfig.to_dict()

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> "TrainConfig":
        return strict_from_dict(cls, d, "training")

    def data_paths(self) -> list[str]:
        paths = [self.data] if isinstance(self.data, str) else list(self.data)
        if not paths or not all(paths):
            raise ValueError("no dataset given (data)")
        return paths


class Trainer:
    """Holds the data, model, optimisers and RNGs of one run; ``run()`` trains to ``cfg.steps``."""

    def __init__(self, cfg: TrainConfig, model_cfg: ModelConfig | None = None, tracks=None, val_tracks=None):
        from export.body.torch_body import TorchBodyModel
        from export.data import load_tracks
        from export.model.heads import FrameHead
        from export.stages import STAGES
        from sim.dataset import Dataset

        if cfg.stage not in STAGES:
            raise ValueError(f"stage must be one of {STAGES}, got {cfg.stage!r}")
        if cfg.input not in ("clean", "board"):
            raise ValueError(f"input must be 'clean' or 'board', got {cfg.input!r}")
        if cfg.lr_schedule not in ("constant", "cosine"):
            raise ValueError(f"lr_schedule must be 'constant' or 'cosine', got {cfg.lr_schedule!r}")
        self.cfg = cfg
        self.out = Path(cfg.out)
        self.out.mkdir(parents=True, exist_ok=True)
        if cfg.threads:
            torch.set_num_threads(cfg.threads)
        self.device = torch.device("cuda" if cfg.device == "auto" and torch.cuda.is_available() else
                                   ("cpu" if cfg.device == "auto" else cfg.device))
        datasets = [Dataset(d) for d in cfg.data_paths()]
        ds = datasets[0]
        self.dataset_manifest = ds.manifest
        self.pitch_m = float(ds.manifest["pitch_m"])
        grid = (int(ds.manifest["rows"]), int(ds.manifest["cols"]))
        for other in datasets[1:]:
            if (int(other.manifest["rows"]), int(other.manifest["cols"])) != grid or float(other.manifest["pitch_m"]) != self.pitch_m:
                raise ValueError(f"{other.path}: grid/pitch differ from {ds.path}'s; train on one carpet geometry at a time")
        self.model_cfg = model_cfg or (ModelConfig.from_dict(cfg.model) if cfg.model else ModelConfig.preset("lean"))
        if self.model_cfg.grid != grid:
            self.model_cfg = ModelConfig.from_dict({**self.model_cfg.to_dict(), "grid": list(grid)})
        cfg.model = self.model_cfg.to_dict()
        board = cfg.input == "board"
        self.tracks = tracks if tracks is not None else [t for d in datasets for t in load_tracks(d, "train", board=board)]
        self.val_tracks = val_tracks if val_tracks is not None else load_tracks(ds, "val", board=board)
        if cfg.exclude_activities:
            from export.data import without_activities

            self.tracks = without_activities(self.tracks, cfg.exclude_activities)
        self.tracks = [t for t in self.tracks if len(t) >= 2]
        if not self.tracks:
            raise ValueError(f"{cfg.data}: no training tracks")
        self.weights = np.array([len(t) for t in self.tracks], float)
        self.weights /= self.weights.sum()

        torch.manual_seed(cfg.seed)
        random.seed(cfg.seed)
        self.rng = np.random.default_rng(cfg.seed)
        self.net = CAvatarNet(self.model_cfg).to(self.device)
        self.disc = JointDiscriminator().to(self.device) if self.model_cfg.discriminator else None
        self.frame_head = FrameHead(self.model_cfg).to(self.device) if cfg.stage == "frames" else None
        self.cache = None  # stage "head": built from the (frozen) encoder on the first step
        if cfg.init:
            self.init_from(cfg.init)
        self.body = TorchBodyModel.load(self.model_cfg.body_model).to(self.device)
        if cfg.optimizer not in ("adam", "adamw"):
            raise ValueError(f"optimizer must be 'adam' or 'adamw', got {cfg.optimizer!r}")
        opt_cls = torch.optim.Adam if cfg.optimizer == "adam" else torch.optim.AdamW
        if cfg.stage == "head":
            self.net.encoder.requires_grad_(False)
        self.opt = opt_cls(self.trainable(), lr=cfg.lr, weight_decay=cfg.weight_decay)
        self.opt_d = opt_cls(self.disc.parameters(), lr=cfg.lr, weight_decay=cfg.weight_decay) if self.disc else None
        self.step = 0
        self.best_val: float | None = None
        self._stop = False
        (self.out / "config.json").write_text(json.dumps(asdict(cfg), indent=1))

    def lr_at(self, step: int) -> float:
        if self.cfg.lr_schedule == "constant":
            return self.cfg.lr
        t = min(step / max(self.cfg.steps, 1), 1.0)
        return self.cfg.lr * (0.01 + 0.99 * 0.5 * (1 + math.cos(math.pi * t)))

    def trainable(self) -> list[torch.nn.Parameter]:
        """What this stage optimises: the frame head and encoder (frames), the head (head), all (windows)."""
        if self.cfg.stage == "frames":
            return [*self.net.encoder.parameters(), *self.frame_head.parameters()]
        if self.cfg.stage == "head":
            return list(self.net.head.parameters())
        return list(self.net.parameters())

    def init_from(self, path: str | Path) -> None:
        """Model weights (not optimiser, step or RNG) from another run's checkpoint of the same architecture."""
        ck = torch.load(path, map_location=self.device, weights_only=False)
        if ck["model_config"] != self.model_cfg.to_dict():
            raise ValueError(f"{path}: its model configuration differs from this run's; --init needs the same architecture")
        self.net.load_state_dict(ck["model"])
        if self.frame_head is not None and ck.get("frame_head"):
            self.frame_head.load_state_dict(ck["frame_head"])

    # ---- batches ---------------------------------------------------------------------------
    def sample(self) -> tuple[dict[str, torch.Tensor], dict[str, torch.Tensor]]:
        """One batch of this stage → (outputs, targets)."""
        from export.model.heads import OUTPUTS
        from export.stages import FeatureCache, sample_frames

        if self.cfg.stage == "windows":
            chunk = self.sample_chunk()
            return self.net.forward_chunk(chunk["x"]), chunk
        if self.cfg.stage == "frames":
            batch = sample_frames(self.tracks, self.weights, self.cfg.batch, self.pitch_m, self.rng, self.device, self.cfg.turns)
            return dict(zip(OUTPUTS, self.frame_head(self.net.encoder(batch["x"])))), batch
        if self.cache is None:
            t0 = time.monotonic()
            self.cache = FeatureCache(self.net.encoder, self.tracks, self.pitch_m, self.cfg.cache_copies, self.cfg.seed,
                                      device=self.device, progress=self._cache_progress if self.cfg.progress else None,
                                      turns=self.cfg.turns)
            if self.cfg.progress:
                print(f"\nfeature cache: {self.cfg.cache_copies} × {sum(len(t) for t in self.tracks)} frames in "
                      f"{time.monotonic() - t0:.0f} s", file=sys.stderr)
        batch = self.cache.sample(self.tracks, self.weights, self.cfg.batch, self.model_cfg.window, self.rng, self.device)
        return dict(zip(OUTPUTS, self.net.head(batch["windows"]))), batch

    @staticmethod
    def _cache_progress(done: int, total: int) -> None:
        print(f"\rfeature cache {done}/{total} frames", end="", file=sys.stderr, flush=True)

    def sample_chunk(self) -> dict[str, torch.Tensor]:
        """One chunk: B+T-1 frames of one track → inputs (N,1,H,W) and targets of the B windows."""
        from edge.infer.normalise import center_of_pressure_m
        from export.data import chunk_indices, training_input

        t, b = self.model_cfg.window, self.cfg.batch
        tr = self.tracks[int(self.rng.choice(len(self.tracks), p=self.weights))]
        n = b + t - 1
        start = int(self.rng.integers(-(t - 1), max(len(tr) - n, -(t - 1)) + 1))
        idx = chunk_indices(len(tr), start, n)
        p = training_input(tr.pressure_kpa[idx].astype(np.float32), self.rng, tr.board)  # (N,H,W) kPa
        x = torch.log1p(p)[:, None]                                              # NORMALISATION (log1p, 1 kPa)
        tgt = idx[t - 1:]                                                        # the windows' target frames
        cop = center_of_pressure_m(p[t - 1:].numpy(), self.pitch_m)
        transl_rel = tr.transl_m[tgt] - np.concatenate([cop, np.zeros((len(tgt), 1))], -1)
        as_t = lambda a, dt=torch.float32: torch.as_tensor(np.ascontiguousarray(a), dtype=dt, device=self.device)  # noqa: E731
        return {"x": x.to(self.device), "pose_aa": as_t(tr.pose_aa[tgt]), "betas": as_t(tr.betas[tgt]),
                "transl_rel_m": as_t(transl_rel), "activity": as_t(tr.activity[tgt], torch.long),
                "joints_m": as_t(tr.joints_m[tgt] - tr.joints_m[tgt][:, :1])}

    # ---- one step ---------------------------------------------------------------------------
    def train_step(self) -> dict[str, float]:
        from export.losses import discriminator_loss, generator_losses

        self.net.train()
        if self.cfg.stage == "head":
            self.net.encoder.eval()
        if self.frame_head is not None:
            self.frame_head.train()
        totals: dict[str, float] = {}
        self.opt.zero_grad(set_to_none=True)
        fakes, reals = [], []
        repeats = self.cfg.chunks if self.cfg.stage == "windows" else 1
        for _ in range(repeats):
            out, target = self.sample()
            loss, parts, fake = generator_losses(out, target, self.body, self.model_cfg, self.disc)
            (loss / repeats).backward()
            fakes.append(fake)
            reals.append(target["joints_m"])
            for k, v in {"loss": float(loss.detach()), **parts}.items():
                totals[k] = totals.get(k, 0.0) + v / repeats
        torch.nn.utils.clip_grad_norm_(self.trainable(), 5.0)
        for group in self.opt.param_groups:
            group["lr"] = self.lr_at(self.step)
        self.opt.step()
        if self.disc is not None:
            self.opt_d.zero_grad(set_to_none=True)
            d_loss = discriminator_loss(self.disc, torch.cat(reals), torch.cat(fakes))
            d_loss.backward()
            self.opt_d.step()
            totals["discriminator"] = float(d_loss.detach())
        self.step += 1
        return totals

    # ---- validation ---------------------------------------------------------------------------
    def validate(self) -> dict[str, float]:
        from edge.body import BodyModel
        from export.evaluate import torch_callables, track_metrics

        if not self.val_tracks:
            return {}
        net = self.net.to("cpu")
        try:
            encode, head = torch_callables(net, self.frame_head.to("cpu") if self.frame_head is not None else None)
            return track_metrics(self.val_tracks, encode, head, self.model_cfg.window, self.pitch_m,
                                 BodyModel.load(self.model_cfg.body_model), frame_stride=self.cfg.val_frame_stride)
        finally:
            self.net.to(self.device)
            if self.frame_head is not None:
                self.frame_head.to(self.device)

    # ---- checkpoints ---------------------------------------------------------------------------
    def state(self) -> dict[str, Any]:
        return {"step": self.step, "model": self.net.state_dict(), "model_config": self.model_cfg.to_dict(),
                "frame_head": self.frame_head.state_dict() if self.frame_head is not None else None,
                "disc": self.disc.state_dict() if self.disc else None, "opt": self.opt.state_dict(),
                "opt_d": self.opt_d.state_dict() if self.opt_d else None, "best_val": self.best_val,
                "rng": {"numpy": self.rng.bit_generator.state, "torch": torch.get_rng_state(),
                        "cuda": torch.cuda.get_rng_state_all() if torch.cuda.is_available() else None,
                        "python": random.getstate()},
                "train_config": asdict(self.cfg)}

    def save(self, name: str = CHECKPOINT) -> Path:
        path = self.out / name
        with atomic_path(path) as part:  # fsynced: training resumes from it after a crash
            torch.save(self.state(), part)
        return path

    def load(self, path: str | Path) -> None:
        ck = torch.load(path, map_location=self.device, weights_only=False)
        if ck["model_config"] != self.model_cfg.to_dict():
            raise ValueError(f"{path}: its model configuration differs from this run's")
        self.net.load_state_dict(ck["model"])
        if self.frame_head is not None:
            self.frame_head.load_state_dict(ck["frame_head"])
        self.opt.load_state_dict(ck["opt"])
        if self.disc is not None and ck["disc"] is not None:
            self.disc.load_state_dict(ck["disc"])
            self.opt_d.load_state_dict(ck["opt_d"])
        self.step, self.best_val = int(ck["step"]), ck.get("best_val")
        self.rng.bit_generator.state = ck["rng"]["numpy"]
        torch.set_rng_state(ck["rng"]["torch"])
        if ck["rng"].get("cuda") is not None and torch.cuda.is_available():
            torch.cuda.set_rng_state_all(ck["rng"]["cuda"])
        random.setstate(ck["rng"]["python"])

    # ---- the loop ---------------------------------------------------------------------------
    def run(self) -> dict[str, Any]:
        cfg = self.cfg
        previous = signal.getsignal(signal.SIGINT)

        def on_sigint(signum, frame):  # finish the step, checkpoint, stop
            self._stop = True

        if threading_main():
            signal.signal(signal.SIGINT, on_sigint)
        log = open(self.out / "log.jsonl", "a")
        t0, start_step = time.monotonic(), self.step
        last: dict[str, float] = {}
        try:
            while self.step < cfg.steps and not self._stop:
                last = self.train_step()
                if self.step % cfg.log_every == 0 or self.step == cfg.steps:
                    log.write(json.dumps({"step": self.step, "time_s": round(time.monotonic() - t0, 2),
                                          **{k: round(v, 6) for k, v in last.items()}}) + "\n")
                    log.flush()
                if cfg.val_every and (self.step % cfg.val_every == 0 or self.step == cfg.steps):
                    val = self.validate()
                    if val:
                        log.write(json.dumps({"step": self.step, "val": val}) + "\n")
                        log.flush()
                        if self.best_val is None or val["mpjpe_cm"] < self.best_val:
                            self.best_val = val["mpjpe_cm"]
                            self.save("best.pt")
                if self.step % cfg.checkpoint_every == 0:
                    self.save()
                if cfg.progress:
                    done = self.step - start_step
                    el = time.monotonic() - t0
                    eta = el / max(done, 1) * (cfg.steps - self.step)
                    bar = "#" * int(30 * self.step / cfg.steps)
                    print(f"\r[{bar:<30}] step {self.step}/{cfg.steps} loss {last.get('loss', 0):.4f} "
                          f"mpjpe(train) {last.get('mpjpe_train_cm', 0):.1f} cm  {el / max(done, 1):.2f} s/step "
                          f"ETA {_hms(eta)}", end="", file=sys.stderr, flush=True)
        finally:
            self.save()
            log.close()
            if threading_main():
                signal.signal(signal.SIGINT, previous)
            if cfg.progress:
                print(file=sys.stderr)
        return {"step": self.step, "interrupted": self._stop, "last": last, "best_val_mpjpe_cm": self.best_val}


def threading_main() -> bool:
    import threading

    return threading.current_thread() is threading.main_thread()


def _hms(s: float) -> str:
    s = int(s)
    return f"{s // 3600}:{s % 3600 // 60:02d}:{s % 60:02d}"


def train(cfg: TrainConfig, model_cfg: ModelConfig | None = None, resume: bool = False, **kwargs: Any) -> Trainer:
    """Build a trainer, resume from ``<out>/checkpoint.pt`` if asked (and present), run it."""
    trainer = Trainer(cfg, model_cfg, **kwargs)
    ck = Path(cfg.out) / CHECKPOINT
    if resume and ck.exists():
        trainer.load(ck)
    trainer.run()
    return trainer


def load_model(path: str | Path) -> CAvatarNet:
    """A trained CAvatarNet (eval mode, CPU) from a checkpoint file."""
    ck = torch.load(path, map_location="cpu", weights_only=False)
    net = CAvatarNet(ModelConfig.from_dict(ck["model_config"]))
    net.load_state_dict(ck["model"])
    return net.eval()


if __name__ == "__main__":  # pragma: no cover
    from edge.cli import main

    sys.exit(main(["train", *sys.argv[1:]]))
