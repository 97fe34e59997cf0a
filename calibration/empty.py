"""Step 3, empty capture: baseline, noise, stuck/noisy lines, and nobody on the carpet.

Per sensel, in "pressure direction" ``d = sign · counts`` (pressure raises d):

- noise σ = 1.4826 · MAD of frame-to-frame differences / √2, floored at 0.5 count
  (differences ignore slow changes and a person who stands still);
- a first baseline b₀ = 10th percentile of d (robust to someone on a sensel for up to
  90 % of the capture); frames with d − b₀ > 4σ are "loaded" there; the baseline is
  the median of the unloaded frames (unbiased, unlike a low percentile);
- stuck: a sensel that reads a rail code in ≥ 90 % of frames or never changes; a line
  with ≥ 50 % such sensels is a stuck line; an isolated rail sensel is a shorted
  crossing (its row and column stay usable);
- noisy: a line whose median σ is > 3× the carpet's, a sensel > 5× (and > 3 counts);
- someone on the carpet: blobs of baseline raised above the local carpet level
  (> 8σ and > 5 % of the room to the rail, ≥ 20 cm², excluding stuck lines/sensels) →
  refuse with where they are (metres and sensels) so they can step off;
- refused as well: shorter than 5 s of good frames, or median noise above
  5 counts at 10 bit (scaled by bit depth).
"""

from __future__ import annotations

import numpy as np
from scipy import ndimage

from calibration.capture import Capture, frame_validity, sensel_xy_m
from calibration.file import FAULT
from calibration.result import StepResult

MIN_DURATION_S = 5.0
NOISE_FLOOR_COUNTS = 0.5
MAX_NOISE_LSB10 = 5.0
MIN_BLOB_M2 = 20e-4  # a load smaller than 20 cm² is not a person (a foot is ≈ 180 cm²)


def robust_noise(d: np.ndarray) -> np.ndarray:
    """(N, H, W) → (H, W): 1.4826 · MAD of frame differences / √2, floored."""
    diff = np.diff(d, axis=0)
    med = np.median(diff, axis=0)
    mad = np.median(np.abs(diff - med), axis=0)
    return np.maximum(1.4826 * mad / np.sqrt(2.0), NOISE_FLOOR_COUNTS)


def where_text(rows: slice, cols: slice, pitch_m: float, shape: tuple[int, int]) -> str:
    r0, r1, c0, c1 = rows.start, rows.stop - 1, cols.start, cols.stop - 1
    x, y = sensel_xy_m((r0 + r1) / 2, (c0 + c1) / 2, pitch_m)
    h, w = shape
    ns = "near the row-0 edge" if (r0 + r1) / 2 < h / 3 else "near the far edge" if (r0 + r1) / 2 > 2 * h / 3 else "mid-carpet"
    ew = "column-0 side" if (c0 + c1) / 2 < w / 3 else "far side" if (c0 + c1) / 2 > 2 * w / 3 else "centre"
    return (f"x = {x:.2f} m, y = {y:.2f} m ({ns}, {ew}; sensels rows {r0}–{r1}, columns {c0}–{c1})")


def empty_capture(cap: Capture, min_duration_s: float = MIN_DURATION_S) -> StepResult:
    res = StepResult("empty")
    fs, sign = cap.full_scale, cap.sign
    ok, reasons = frame_validity(cap.frames, fs)
    if reasons:
        res.say("frames dropped before use: " + ", ".join(f"{v} {k.replace('_', ' ')}" for k, v in reasons.items()))
    raw = cap.frames[ok].astype(np.float32)
    n = raw.shape[0]
    res.numbers.update(frames_used=n, frames_dropped=int((~ok).sum()))
    if n < min_duration_s * cap.rate_hz:
        return res.refuse(f"the empty capture holds {n / cap.rate_hz:.1f} s of good frames; at least "
                          f"{min_duration_s:g} s are needed (10 s recommended). Capture again.")
    d = sign * raw
    noise = robust_noise(d)
    b0 = np.percentile(d, 10, axis=0)
    loaded = (d - b0) > 4.0 * noise
    base_d = np.nanmedian(np.where(loaded, np.nan, d), axis=0)
    base_d = np.where(np.isnan(base_d), b0, base_d)
    baseline = (sign * base_d).astype(np.float32)

    fault = np.zeros(cap.shape, np.uint8)
    line_faults: list[dict] = []
    stuckish, lone, rail_blob = _stuck(res, raw, fs, fault, line_faults)
    healthy = ~stuckish | rail_blob
    typical = _noisy(res, noise, healthy, fault, line_faults)
    lsb10 = 2.0 ** (int(cap.device["adc_bits"]) - 10)
    res.numbers.update(noise_median_counts=round(typical, 3), noise_median_lsb10=round(typical / lsb10, 3),
                       baseline_median_counts=round(float(np.median(baseline[healthy])) if healthy.any() else 0.0, 2),
                       stuck_sensels=int((fault & FAULT["stuck"] > 0).sum()), noisy_sensels=int((fault & FAULT["noisy"] > 0).sum()),
                       loaded_fraction=round(float(loaded[:, healthy].mean()) if healthy.any() else 0.0, 4))
    res.arrays.update(baseline_counts=baseline, noise_counts=noise.astype(np.float32), fault=fault)
    res.numbers["line_faults"] = line_faults
    if typical / lsb10 > MAX_NOISE_LSB10:
        return res.refuse(f"the carpet is too noisy: median σ {typical:.1f} counts ({typical / lsb10:.1f} at 10 bit, "
                          f"limit {MAX_NOISE_LSB10:g}). Look for a mains/motor source nearby, a loose ground or "
                          "someone moving on the carpet, then capture again.")
    if _someone_on_it(res, cap, d, base_d, baseline, noise, fault, lone, rail_blob, line_faults):
        return res
    res.say(f"baseline median {res.numbers['baseline_median_counts']:.1f} counts, noise σ {typical:.2f} counts "
            f"({n} frames, {n / cap.rate_hz:.1f} s)")
    return res


def _stuck(res: StepResult, raw: np.ndarray, fs: int, fault: np.ndarray,
           line_faults: list[dict]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Stuck sensels and lines (a rail code nearly always, or no change at all) → (stuck-ish sensels,
    lone ones marked short for now, patches at the rail that are a load, not a fault)."""
    rail_hi, rail_lo = raw >= fs, raw <= 0
    at_rail = (rail_hi.mean(axis=0) >= 0.9) | (rail_lo.mean(axis=0) >= 0.9)
    frozen = (raw.max(axis=0) == raw.min(axis=0))
    stuckish = at_rail | frozen
    stuck_rows = np.flatnonzero(stuckish.mean(axis=1) >= 0.5)
    stuck_cols = np.flatnonzero(stuckish.mean(axis=0) >= 0.5)
    line_mask = np.zeros(fault.shape, bool)
    line_mask[stuck_rows, :] = True
    line_mask[:, stuck_cols] = True
    fault[line_mask & stuckish] |= FAULT["stuck"]
    for axis, idx in (("row", stuck_rows), ("col", stuck_cols)):
        for i in idx:
            line_faults.append({"kind": "stuck", "axis": axis, "index": int(i), "found_by": "empty"})
            res.say(f"{axis} {i} is stuck (reads a rail code or never changes): masked")
    lone = stuckish & ~line_mask
    lab, _ = ndimage.label(lone, structure=np.ones((3, 3)))
    sizes = np.bincount(lab.ravel())
    rail_blob = lone & (sizes[lab] >= 3)  # a patch at the rail is a load (someone standing), not a fault
    lone &= ~rail_blob
    fault[lone] |= FAULT["short"]  # provisional: confirmed by _someone_on_it unless next to someone standing
    return stuckish, lone, rail_blob


def _noisy(res: StepResult, noise: np.ndarray, healthy: np.ndarray, fault: np.ndarray, line_faults: list[dict]) -> float:
    """Noisy lines and single sensels masked; → the typical noise (counts) of the healthy sensels."""
    typical = float(np.median(noise[healthy])) if healthy.any() else float(np.median(noise))
    rows, cols = noise.shape
    row_noise = np.array([np.median(noise[r][healthy[r]]) if healthy[r].any() else 0 for r in range(rows)])
    col_noise = np.array([np.median(noise[:, c][healthy[:, c]]) if healthy[:, c].any() else 0 for c in range(cols)])
    for axis, arr in (("row", row_noise), ("col", col_noise)):
        for i in np.flatnonzero(arr > 3.0 * typical):
            sl = (i, slice(None)) if axis == "row" else (slice(None), i)
            fault[sl] |= FAULT["noisy"]
            line_faults.append({"kind": "noisy", "axis": axis, "index": int(i), "noise_counts": float(arr[i]),
                                "found_by": "empty"})
            res.say(f"{axis} {i} is noisy (σ {arr[i]:.1f} counts vs {typical:.1f} typical): masked")
    lone_noisy = healthy & (noise > max(5.0 * typical, 3.0)) & ((fault & FAULT["noisy"]) == 0)
    fault[lone_noisy] |= FAULT["noisy"]
    if lone_noisy.any():
        res.say(f"{int(lone_noisy.sum())} single noisy sensels masked")
    return typical


def _someone_on_it(res: StepResult, cap: Capture, d: np.ndarray, base_d: np.ndarray, baseline: np.ndarray,
                   noise: np.ndarray, fault: np.ndarray, lone: np.ndarray, rail_blob: np.ndarray,
                   line_faults: list[dict]) -> bool:
    """Someone on the carpet: raised blobs against the local carpet level. Confirms the lone shorts that
    are not next to a load; True when the step was refused (someone stood there the whole capture)."""
    fs, sign, n = cap.full_scale, cap.sign, d.shape[0]
    usable = (fault == 0)
    level = _local_level(base_d, usable, cap.pitch_m)
    room = np.abs((fs if sign > 0 else 0) - baseline)
    raised = ((base_d - level > np.maximum(8.0 * noise, 0.05 * room)) & usable) | rail_blob
    labels, nblob = ndimage.label(raised, structure=np.ones((3, 3)))
    min_sensels = max(3, int(np.ceil(MIN_BLOB_M2 / cap.pitch_m**2)))
    blobs = []
    for i, sl in enumerate(ndimage.find_objects(labels), start=1):
        size = int((labels[sl] == i).sum())
        if size >= min_sensels:
            blobs.append((size, sl))
    strong = ((d - base_d) > 8.0 * noise) & usable
    near = ndimage.binary_dilation(raised, iterations=2)
    fault[lone & near] &= ~np.uint8(FAULT["short"])
    for r, c in zip(*np.nonzero(lone & ~near)):
        line_faults.append({"kind": "short", "row": int(r), "col": int(c), "found_by": "empty"})
        res.say(f"sensel ({r}, {c}) sits at a rail: a shorted crossing (or stuck sensel), masked; "
                f"row {r} and column {c} are kept")
    part = float((strong.reshape(n, -1).sum(axis=1) >= 4).mean())
    if part > 0.02 and not blobs:
        res.say(f"someone was on the carpet in {part:.0%} of the frames; the baseline uses only the frames "
                "where each sensel was free")
    res.numbers["occupied_frame_fraction"] = round(float(part), 3)
    if not blobs:
        return False
    blobs.sort(key=lambda b: -b[0])
    res.numbers["people_blobs"] = [{"rows": [s[0].start, s[0].stop - 1], "cols": [s[1].start, s[1].stop - 1],
                                    "sensels": n_} for n_, s in blobs]
    groups = _group(blobs, cap.pitch_m)
    where = "; ".join(where_text(rs, cs, cap.pitch_m, cap.shape) for rs, cs in groups[:3])
    who = "someone (or something) is" if len(groups) == 1 else f"{len(groups)} people or objects are"
    res.refuse(f"{who} on the carpet during the whole capture at {where}. "
               "Ask them to step off (or remove the object), then capture again.")
    return True


def _local_level(base_d: np.ndarray, usable: np.ndarray, pitch_m: float) -> np.ndarray:
    """The carpet's unloaded level around each sensel: a median over ~0.6 m, ignoring unusable sensels."""
    size = max(5, min(int(round(0.6 / pitch_m)), min(base_d.shape) // 2) | 1)
    filled = np.where(usable, base_d, np.median(base_d[usable]) if usable.any() else 0.0)
    return ndimage.median_filter(filled, size=size, mode="nearest")


def _group(blobs: list, pitch_m: float, radius_m: float = 0.6) -> list[tuple[slice, slice]]:
    """Merge contact blobs closer than ``radius_m`` (two feet are one person): bounding slices."""
    boxes = [[s[0].start, s[0].stop, s[1].start, s[1].stop] for _, s in blobs]
    merged = True
    while merged:
        merged = False
        for i in range(len(boxes)):
            for j in range(i + 1, len(boxes)):
                a, b = boxes[i], boxes[j]
                ca = np.array([(a[0] + a[1]) / 2, (a[2] + a[3]) / 2])
                cb = np.array([(b[0] + b[1]) / 2, (b[2] + b[3]) / 2])
                if np.linalg.norm(ca - cb) * pitch_m < radius_m:
                    boxes[i] = [min(a[0], b[0]), max(a[1], b[1]), min(a[2], b[2]), max(a[3], b[3])]
                    del boxes[j]
                    merged = True
                    break
            if merged:
                break
    return [(slice(b[0], b[1]), slice(b[2], b[3])) for b in boxes]
