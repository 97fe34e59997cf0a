"""What every calibration step returns: numbers, per-sensel arrays and findings in words.

``ok`` False means the step's data must not be used (``retry`` says whether doing the
step again can fix it, e.g. "ask them to step off"). ``numbers`` are JSON-able
figures for the report; ``arrays`` are (H, W) maps handed to later steps and the report.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np


@dataclass
class StepResult:
    step: str
    ok: bool = True
    retry: bool = False
    findings: list[str] = field(default_factory=list)
    numbers: dict[str, Any] = field(default_factory=dict)
    arrays: dict[str, np.ndarray] = field(default_factory=dict)

    def say(self, text: str) -> None:
        self.findings.append(text)

    def refuse(self, text: str, retry: bool = True) -> "StepResult":
        self.ok, self.retry = False, retry
        self.findings.append(text)
        return self

    def summary(self) -> str:
        head = f"[{self.step}] {'ok' if self.ok else 'REFUSED' if not self.retry else 'REDO'}"
        return "\n".join([head] + [f"  - {f}" for f in self.findings])

    # persistence (the resumable session keeps one file per step)
    def save(self, path: str | Path) -> None:
        meta = {"step": self.step, "ok": self.ok, "retry": self.retry, "findings": self.findings,
                "numbers": self.numbers}
        from cavatar_common.atomic import atomic_path  # whole or not at all: a resumed session reads it back

        with atomic_path(path) as tmp:
            np.savez_compressed(tmp, _meta=np.array(json.dumps(meta, default=_jsonable)), **self.arrays)

    @classmethod
    def load(cls, path: str | Path) -> "StepResult":
        with np.load(path, allow_pickle=False) as z:
            meta = json.loads(str(z["_meta"]))
            arrays = {k: z[k] for k in z.files if k != "_meta"}
        return cls(meta["step"], meta["ok"], meta["retry"], meta["findings"], meta["numbers"], arrays)


def _jsonable(o: Any) -> Any:
    if isinstance(o, np.generic):
        return o.item()
    if isinstance(o, np.ndarray):
        return o.tolist()
    raise TypeError(f"not JSON-able: {type(o)}")
