"""A resumable calibration session: runs the steps in order, saving after each one.

The work folder holds ``state.json`` (options, which steps are done), one result file
per step (``<step>.npz``: numbers, findings, maps) and the captures
(``captures/<step>.npz``). Running again resumes after the last finished step;
``redo="board"`` redoes that step alone (a fresh capture from the provider) and keeps
the others. Assembly, validation and the report are always recomputed at the end.

Captures come from a *provider* (``capture(step, attempt, last_result) -> Capture``
and ``say(text)``): recordings, a live board with prompts, or the virtual carpet's
scripted actor (:mod:`calibration.providers`).
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from calibration.board import board_equilibration
from calibration.capture import Capture
from calibration.empty import empty_capture
from calibration.file import Calibration
from calibration.result import StepResult
from calibration.selftest import self_test
from calibration.stance import known_weight_stance
from calibration.validate import assemble, validation
from calibration.walk import coverage_walk

STEPS = ("self_test", "empty", "walk", "board", "stance", "holdout")
MAX_ATTEMPTS = 3


class SessionError(Exception):
    """A step could not be completed (its findings say why)."""


@dataclass
class Options:
    mass_kg: float | None = None
    board_mass_kg: float = 3.0
    crosstalk_r_norm: float = 0.0
    shape_from_walk: bool = False
    mask_path: str | None = None
    temperature_c: float | None = None


@dataclass
class Session:
    workdir: Path
    options: Options = field(default_factory=Options)

    def __post_init__(self) -> None:
        self.workdir = Path(self.workdir)
        (self.workdir / "captures").mkdir(parents=True, exist_ok=True)
        state = self.workdir / "state.json"
        self.done: list[str] = []
        if state.exists():
            saved = json.loads(state.read_text())
            self.done = saved.get("done", [])
            for k, v in saved.get("options", {}).items():
                if getattr(self.options, k, None) in (None, 0.0, False) and v is not None:
                    setattr(self.options, k, v)

    # ------------------------------------------------------------------ storage
    def _save_state(self) -> None:
        from cavatar_common.atomic import write_atomic

        state = {"done": self.done, "options": self.options.__dict__}
        write_atomic(self.workdir / "state.json", json.dumps(state, indent=1))

    def result(self, step: str) -> StepResult | None:
        path = self.workdir / f"{step}.npz"
        return StepResult.load(path) if path.exists() and step in self.done else None

    def capture(self, step: str) -> Capture | None:
        path = self.workdir / "captures" / f"{step}.npz"
        return Capture.load(path) if path.exists() else None

    # ------------------------------------------------------------------ steps
    def compute(self, step: str, cap: Capture) -> StepResult:
        """Run one step's pure function on ``cap`` with the earlier steps' results."""
        if step == "self_test":
            return self_test(cap)
        if step == "empty":
            return empty_capture(cap)
        e = self._need("empty")
        base, noise = e.arrays["baseline_counts"], e.arrays["noise_counts"]
        fault = e.arrays["fault"].copy()
        if step == "walk":
            return coverage_walk(cap, base, noise, fault, shape_from_walk=self.options.shape_from_walk)
        w = self.result("walk")
        if w is not None:
            fault |= w.arrays["fault"]
        mask = self._mask()
        if mask is not None:
            from calibration.file import FAULT
            fault[~mask] |= FAULT["outside"]
        if step == "board":
            return board_equilibration(cap, base, noise, fault)
        b = self.result("board")
        gain = b.arrays["gain"] if b is not None else np.ones(cap.shape, np.float32)
        if step == "stance":
            if not self.options.mass_kg:
                raise SessionError("the stance step needs the person's mass (--mass KG)")
            return known_weight_stance(cap, base, noise, fault, gain, float(self.options.mass_kg),
                                       board_cap=self.capture("board"), board_mass_kg=self.options.board_mass_kg)
        if step == "holdout":  # nothing to compute until assembly: keep the capture
            res = StepResult("holdout")
            res.say(f"held-out stance captured ({cap.frames.shape[0]} frames)")
            return res
        raise ValueError(f"unknown step {step!r}; steps are {', '.join(STEPS)}")

    def _need(self, step: str) -> StepResult:
        r = self.result(step)
        if r is None:
            raise SessionError(f"the {step} step has not been done yet")
        return r

    def _mask(self) -> np.ndarray | None:
        if not self.options.mask_path:
            return None
        return np.load(self.options.mask_path).astype(bool)

    def run(self, provider, steps: tuple[str, ...] = STEPS, redo: str | None = None) -> dict[str, StepResult]:
        """Do every step of ``steps`` not done yet (and ``redo``), asking ``provider`` for captures."""
        if redo is not None and redo not in STEPS:
            raise ValueError(f"unknown step {redo!r}; steps are {', '.join(STEPS)}")
        results: dict[str, StepResult] = {}
        todo = [s for s in steps if s not in self.done or s == redo]
        if redo is not None:
            todo = [redo]
        for step in steps:
            if step not in todo:
                r = self.result(step)
                if r is not None:
                    results[step] = r
                continue
            last: StepResult | None = None
            for attempt in range(MAX_ATTEMPTS):
                cap = provider.capture(step, attempt, last)
                if cap is None:
                    break
                res = self.compute(step, cap)
                provider.say(res.summary())
                last = res
                if res.ok or not res.retry:
                    break
            if last is None:
                continue
            if not last.ok:
                raise SessionError(f"step {step} failed: " + " ".join(last.findings[-1:]))
            cap.save(self.workdir / "captures" / f"{step}.npz")
            last.save(self.workdir / f"{step}.npz")
            if step not in self.done:
                self.done.append(step)
            self._save_state()
            results[step] = last
        return results

    # ------------------------------------------------------------------ the end
    def finish(self, out_path: str | Path | None = None) -> tuple[Calibration, StepResult]:
        """Assemble, validate and (with ``out_path``) save the calibration file."""
        e = self._need("empty")
        cap = self.capture("empty")
        stance = self.result("stance")
        cal = assemble(cap.device, cap.pitch_m, e, self.result("walk"), self.result("board"), stance,
                       mask=self._mask(), crosstalk_r_norm=self.options.crosstalk_r_norm,
                       temperature_c=self.options.temperature_c)
        phi = float(stance.numbers.get("saturated_fill_ratio", 1.0)) if stance is not None else 1.0
        v = validation(cal, self.capture("holdout"), self.options.mass_kg, phi)
        cal.validation = dict(v.numbers, ok=v.ok, findings=v.findings)
        cal.steps["saturated_fill_ratio"] = phi
        if out_path is not None:
            cal.save(out_path)
        return cal, v

    def all_results(self) -> dict[str, Any]:
        return {s: r for s in STEPS if (r := self.result(s)) is not None}
