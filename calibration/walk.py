"""Step 5, coverage walk: dead and half-dead lines, the sign convention, a coverage map.

An open thread reads like an unloaded sensel, so dead lines only show under load.
With ``d = sign · (counts − baseline)`` and ``active = d > max(6σ, 3 % of the span to
the rail)`` (3 % keeps multiplexer smear from a loaded neighbour out):

- dead: along each line, in segments of 16 sensels, a run of adjacent lines active
  < 5 % as often as BOTH lines bounding the run (stuck lines skipped; a carpet edge
  has one neighbour; a run longer than 16 lines is an area not walked, not a fault). A run of 8 or 16 is reported as a multiplexer bank;
- half-dead ("weak"): where both neighbours are active, the line's summed response
  is < 60 % of theirs (saturated neighbours only make the ratio smaller);
- sign: the direction of the large deviations (> 10σ) from the baseline; a board
  whose INFO sign disagrees with the carpet is refused;
- coverage: frames in which each sensel was active (a map, and the fraction of
  usable sensels touched at least once); a region never touched that is neither a
  dead line nor covered is reported, or marked ``outside`` with ``shape_from_walk``.
"""

from __future__ import annotations

import numpy as np
from scipy import ndimage

from calibration.capture import Capture, frame_validity
from calibration.empty import where_text
from calibration.file import FAULT, UNUSABLE
from calibration.result import StepResult

SEGMENT = 16
MAX_RUN = 16  # longest dead run that is a fault (a mux bank); longer = not walked
DEAD_RATIO = 0.05
WEAK_RATIO = 0.6
MIN_COVERAGE = 0.6


def activity_threshold(baseline: np.ndarray, noise: np.ndarray, sign: int, full_scale: int) -> np.ndarray:
    span = (full_scale - baseline) if sign > 0 else baseline
    return np.maximum(6.0 * noise, 0.03 * np.maximum(span, 1.0))


def _dead_runs(act: np.ndarray, skip: np.ndarray, min_evidence: float) -> np.ndarray:
    """act (L, S): activity of L lines in S segments; skip (L,) lines to ignore (stuck).
    Returns (L, S) bool: dead per line segment (the run rule)."""
    n_lines, n_seg = act.shape
    dead = np.zeros_like(act, bool)
    for j in range(n_seg):
        a = act[:, j]
        valid = ~skip
        ref = np.median(a[valid & (a > 0)]) if np.any(valid & (a > 0)) else 0.0
        cand = valid & (a < DEAD_RATIO * ref)
        i = 0
        while i < n_lines:
            if not cand[i]:
                i += 1
                continue
            k = i
            while k + 1 < n_lines and (cand[k + 1] or skip[k + 1]):
                k += 1
            lo = next((m for m in range(i - 1, -1, -1) if not skip[m]), None)
            hi = next((m for m in range(k + 1, n_lines) if not skip[m]), None)
            sides = [a[m] for m in (lo, hi) if m is not None]
            run = [m for m in range(i, k + 1) if not skip[m]]
            if (sides and len(run) <= MAX_RUN and min(sides) >= min_evidence
                    and max(a[run]) < DEAD_RATIO * min(sides)):
                dead[run, j] = True
            i = k + 1
    return dead


def _weak_ratio(d: np.ndarray, active_thr: np.ndarray, unusable: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Per row of d (N, H, W): Σ d[row] / Σ mean(d[neighbours]) where the neighbours are active."""
    n, h, w = d.shape
    num, den, ev = np.zeros(h), np.zeros(h), np.zeros(h)
    act = (d > active_thr) & ~unusable
    for r in range(h):
        if r == 0 or r == h - 1:
            continue  # an edge line sees only the rim of feet: no fair comparison
        nb = [r - 1, r + 1]
        m = np.logical_and.reduce([act[:, q] for q in nb]) & ~unusable[r]
        if not m.any():
            continue
        num[r] = d[:, r][m].sum()
        den[r] = np.mean([d[:, q][m].sum() for q in nb])
        ev[r] = m.sum()
    ratio = np.where(den > 0, num / np.maximum(den, 1e-9), np.nan)
    return ratio, ev


def coverage_walk(cap: Capture, baseline: np.ndarray, noise: np.ndarray, fault: np.ndarray,
                  shape_from_walk: bool = False) -> StepResult:
    res = StepResult("walk")
    ok, reasons = frame_validity(cap.frames, cap.full_scale)
    raw = cap.frames[ok].astype(np.float32)
    if raw.shape[0] < 3 * cap.rate_hz:
        return res.refuse(f"the walk holds only {raw.shape[0] / cap.rate_hz:.1f} s of good frames; walk for 60–90 s")
    unusable = (fault & UNUSABLE) > 0
    delta = raw - baseline[None]
    if _check_sign(res, cap, delta, noise, unusable):
        return res
    d = cap.sign * delta
    thr = activity_threshold(baseline, noise, cap.sign, cap.full_scale)
    count = ((d > thr[None]) & ~unusable[None]).sum(axis=0).astype(np.int32)
    new_fault = np.zeros(cap.shape, np.uint8)
    line_faults: list[dict] = []
    _dead_lines(res, count, (fault & FAULT["stuck"]) > 0, new_fault, line_faults)
    gone = unusable | (new_fault > 0)
    _weak_lines(res, d, thr, gone, new_fault, line_faults)
    coverage = _coverage(res, cap, count, ~(gone | (new_fault & UNUSABLE > 0)), new_fault, shape_from_walk)
    res.numbers.update(coverage_fraction=round(coverage, 4), line_faults=line_faults,
                       dead_sensels=int((new_fault & FAULT["dead"] > 0).sum()),
                       weak_sensels=int((new_fault & FAULT["weak"] > 0).sum()),
                       crosstalk_r_norm=None)
    res.arrays.update(coverage=count, fault=new_fault)
    res.say(f"coverage: {coverage:.0%} of usable sensels stepped on at least once")
    res.say("crosstalk (line loading) is not measurable from a walk; the readout's nominal value is used")
    if coverage < MIN_COVERAGE:
        return res.refuse(f"only {coverage:.0%} of the carpet was stepped on (need {MIN_COVERAGE:.0%}); "
                          "keep walking over the empty areas of the map")
    return res


def _check_sign(res: StepResult, cap: Capture, delta: np.ndarray, noise: np.ndarray, unusable: np.ndarray) -> bool:
    """Which way pressure moves the readings, against the board's sign; True when the step was refused."""
    big = np.abs(delta) > np.maximum(10.0 * noise, 0.03 * cap.full_scale)[None]
    big &= ~unusable[None]
    pos, neg = int((big & (delta > 0)).sum()), int((big & (delta < 0)).sum())
    res.numbers.update(frames_used=int(delta.shape[0]), sign_votes={"up": pos, "down": neg})
    if pos + neg < 50:
        res.refuse("nothing moved during the walk: was anyone walking on the carpet?")
        return True
    measured = 1 if pos > neg else -1
    res.numbers["measured_sign"] = measured
    if measured != cap.sign and max(pos, neg) > 0.8 * (pos + neg):
        res.refuse(f"the board reports sign {cap.sign:+d}, but pressure moves the readings "
                   f"{'up' if measured > 0 else 'down'} (sign {measured:+d}): the front end or the "
                   "board's configuration is inverted. Fix the board's sign setting (or pass "
                   f"--sign {measured:+d}) and calibrate again.", retry=False)
        return True
    res.say(f"sign convention confirmed: pressure moves readings {'up' if cap.sign > 0 else 'down'} ({cap.sign:+d})")
    return False


def _dead_lines(res: StepResult, count: np.ndarray, stuck: np.ndarray, new_fault: np.ndarray,
                line_faults: list[dict]) -> None:
    """Rows and columns (or runs of them) that never responded under the walk: dead, or a mux bank."""
    dead_by: dict[str, np.ndarray] = {}
    for axis in ("row", "col"):
        c = count if axis == "row" else count.T
        st = (stuck if axis == "row" else stuck.T).mean(axis=1) >= 0.5
        n_lines, length = c.shape
        n_seg = max(1, length // SEGMENT)
        edges = np.linspace(0, length, n_seg + 1).astype(int)
        act = np.stack([c[:, edges[j]:edges[j + 1]].sum(axis=1) for j in range(n_seg)], axis=1).astype(float)
        dead_seg = _dead_runs(act, st, min_evidence=30.0)
        dead = np.zeros_like(c, bool)
        for j in range(n_seg):
            dead[:, edges[j]:edges[j + 1]] |= dead_seg[:, j:j + 1]
        dead_by[axis] = dead if axis == "row" else dead.T
    # a block silent as rows AND as columns is an area (not walked, or no carpet there), not line faults
    both = dead_by["row"] & dead_by["col"]
    lab, _ = ndimage.label(both)
    for i, sl in enumerate(ndimage.find_objects(lab), start=1):
        if min(sl[0].stop - sl[0].start, sl[1].stop - sl[1].start) >= 3:
            for axis in dead_by:
                dead_by[axis][lab == i] = False
    for axis in ("row", "col"):
        dead = dead_by[axis] if axis == "row" else dead_by[axis].T
        new_fault[dead_by[axis]] |= FAULT["dead"]
        _report_dead(res, axis, dead, line_faults)


def _report_dead(res: StepResult, axis: str, dead: np.ndarray, line_faults: list[dict]) -> None:
    """One axis's dead lines (lines × positions) as line faults: whole lines, runs of ≥ 8 (a mux bank), part-way."""
    frac = dead.mean(axis=1)
    whole = [int(i) for i in np.flatnonzero(frac >= 0.75)]
    runs: list[list[int]] = []
    for i in whole:
        if runs and i == runs[-1][-1] + 1:
            runs[-1].append(i)
        else:
            runs.append([i])
    for run in runs:
        if len(run) >= 8:
            line_faults.append({"kind": "mux_bank", "axis": axis, "start": run[0], "size": len(run), "found_by": "walk"})
            res.say(f"{axis}s {run[0]}–{run[-1]} are dead together ({len(run)} lines): a failed multiplexer "
                    "bank or connector; masked. Check the tile's ribbon cable.")
        else:
            for i in run:
                line_faults.append({"kind": "dead", "axis": axis, "index": i, "found_by": "walk"})
                res.say(f"{axis} {i} is dead (an open thread: no response under the walk): masked")
    for i in np.flatnonzero((frac > 0) & (frac < 0.75)):
        where_dead = np.flatnonzero(dead[i])
        a, b = int(where_dead[0]), int(where_dead[-1])
        line_faults.append({"kind": "dead", "axis": axis, "index": int(i), "start": a, "stop": b + 1, "found_by": "walk"})
        res.say(f"{axis} {i} is dead from {'column' if axis == 'row' else 'row'} {a} to {b} (broken part-way): masked there")


def _weak_lines(res: StepResult, d: np.ndarray, thr: np.ndarray, gone: np.ndarray, new_fault: np.ndarray,
                line_faults: list[dict]) -> None:
    """Half-dead lines: responding much less than their neighbours under the same walk."""
    for axis in ("row", "col"):
        dd = d if axis == "row" else np.transpose(d, (0, 2, 1))
        th = thr if axis == "row" else thr.T
        un = gone if axis == "row" else gone.T
        ratio, ev = _weak_ratio(dd, th[None], un)
        for i in np.flatnonzero((ratio < WEAK_RATIO) & (ev >= 30)):
            if un[i].mean() > 0.5:
                continue
            sl = (i, slice(None)) if axis == "row" else (slice(None), i)
            new_fault[sl] |= FAULT["weak"]
            line_faults.append({"kind": "weak", "axis": axis, "index": int(i), "response_ratio": round(float(ratio[i]), 3),
                                "found_by": "walk"})
            res.say(f"{axis} {i} is half-dead: it responds {ratio[i]:.0%} as strongly as its neighbours; "
                    "its gain comes from the board step (masked if too weak to correct)")


def _coverage(res: StepResult, cap: Capture, count: np.ndarray, usable_now: np.ndarray, new_fault: np.ndarray,
              shape_from_walk: bool) -> float:
    """The share of usable sensels stepped on; the largest untouched areas said (or, on the border with
    ``shape_from_walk``, marked outside the carpet)."""
    h, w = cap.shape
    touched = (count > 0) & usable_now
    coverage = float(touched.sum() / max(usable_now.sum(), 1))
    untouched = usable_now & (count == 0)
    lab, nlab = ndimage.label(untouched)
    holes = []
    for i, sl in enumerate(ndimage.find_objects(lab), start=1):
        size = int((lab[sl] == i).sum())
        if size >= max(16, 0.01 * h * w):
            holes.append((size, sl, i))
    holes.sort(key=lambda x: -x[0])
    for size, sl, i in holes[:4]:
        border = sl[0].start == 0 or sl[1].start == 0 or sl[0].stop == h or sl[1].stop == w
        if shape_from_walk and border:
            new_fault[lab == i] |= FAULT["outside"]
            res.say(f"{size} sensels at {where_text(sl[0], sl[1], cap.pitch_m, cap.shape)} never responded: "
                    "marked outside the carpet (shape from the walk)")
        else:
            res.say(f"{size} sensels at {where_text(sl[0], sl[1], cap.pitch_m, cap.shape)} were never stepped on: "
                    "walk there (or, if the carpet has no sensels there, pass --mask / --shape-from-walk)")
    return coverage
