"""Step 6, board equilibration: per-sensel gain from a near-planar load.

A person standing on a rigid 60 × 60 cm board loads the carpet with a plane of
pressure (≈ 2 kPa; tilted as they shift their weight). Per frame, with the current
curve and ``d = sign · (counts − baseline)``:

1. ``p = curve⁻¹(d / (gain · span))``; the board's footprint is the largest connected
   region above 0.3 kPa (≥ 50 % of the board's area), eroded by one sensel (edges hold
   partial loads);
2. a plane ``a + b·x + c·y`` is fitted to ``p`` over the footprint (least squares, once
   more without the > 50 % outliers);
3. each sensel's gain sample is ``d / (span · r(plane))``: its response relative to a
   typical sensel at the plane's pressure.

Gains are the geometric mean of the samples (two passes: the second fits the plane to
gain-corrected pressures), normalised to median 1, clipped to [0.5, 2]; sensels the
board never covered get a row × column model. The spread reported: the σ of log gain
("before": how uneven the raw carpet is) and the residual spread of held-out (odd)
frames corrected with gains from the even frames ("after").
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import ndimage

from calibration.capture import Capture, frame_validity
from calibration.file import UNUSABLE, Curve
from calibration.result import StepResult

BOARD_SIDE_M = 0.60
MAX_FRAMES = 360
GAIN_CLIP = (0.5, 2.0)


@dataclass
class BoardFrame:
    """One usable board frame: footprint sensel indices and their d, the full footprint for force."""

    idx: np.ndarray  # (K,) flat indices of the eroded footprint
    full_idx: np.ndarray  # (M,) flat indices of the whole footprint (dilated by one)
    box_masked: int  # unusable sensels inside the footprint's bounding box
    box_area: int


def default_curve(baseline: np.ndarray, sign: int, full_scale: int, usable: np.ndarray) -> Curve:
    """The note's typical curve with the span that puts a typical sensel at the rail at 14 kPa."""
    c = Curve(half_scale_kpa=8.0, exponent=1.2, saturation_kpa=14.0)
    room = (full_scale - baseline) if sign > 0 else baseline
    c.span_counts = float(np.median(room[usable]) / c.response(np.array(14.0)))
    return c


def board_frames(d: np.ndarray, usable: np.ndarray, p: np.ndarray, pitch_m: float) -> list[BoardFrame | None]:
    """Find the board's footprint in each frame of p (N, H, W) kPa."""
    area_px = (BOARD_SIDE_M / pitch_m) ** 2
    out: list[BoardFrame | None] = []
    for t in range(p.shape[0]):
        loaded = (p[t] > 0.3) & usable
        on = ndimage.binary_closing(loaded, structure=np.ones((3, 3)), iterations=2)  # bridges dead lines inside
        lab, n = ndimage.label(on)
        if n == 0:
            out.append(None)
            continue
        sizes = np.bincount(lab.ravel())
        sizes[0] = 0
        k = int(np.argmax(sizes))
        comp = lab == k
        if sizes[k] < 0.5 * area_px or sizes[k] > 2.0 * area_px:
            out.append(None)
            continue
        inner = ndimage.binary_erosion(comp, structure=np.ones((3, 3)), iterations=1) & loaded
        full = ndimage.binary_dilation(comp, iterations=1) & usable
        sl = ndimage.find_objects(comp.astype(int))[0]
        out.append(BoardFrame(np.flatnonzero(inner), np.flatnonzero(full), int((~usable[sl]).sum()),
                              int(comp[sl].size)))
    return out


def _plane_coef(xy: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Least-squares plane v ≈ A + B·(x − x̄) + C·(y − ȳ) about the centroid (once more without
    the > 50 % outliers). Returns (A, B, C, x̄, ȳ)."""
    c = xy.mean(axis=0)
    a = np.column_stack([np.ones(len(v)), xy - c])
    coef, *_ = np.linalg.lstsq(a, v, rcond=None)
    fit = a @ coef
    keep = np.abs(v / np.maximum(fit, 1e-6) - 1.0) < 0.5
    if keep.sum() > 10 and not keep.all():
        coef, *_ = np.linalg.lstsq(a[keep], v[keep], rcond=None)
    return np.array([coef[0], coef[1], coef[2], c[0], c[1]])


def placements(frames: list[BoardFrame | None], xy: np.ndarray, jump_m: float = 0.05) -> np.ndarray:
    """(N,) placement number per frame (−1 where no board): a new one when the footprint moves."""
    out = np.full(len(frames), -1)
    k, last = -1, None
    for t, bf in enumerate(frames):
        if bf is None:
            continue
        c = xy[bf.full_idx].mean(axis=0)
        if last is None or np.linalg.norm(c - last) > jump_m:
            k += 1
        out[t], last = k, c
    return out


def gain_samples(d_flat: np.ndarray, frames: list[BoardFrame | None], gain_flat: np.ndarray, curve: Curve,
                 xy: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Log gain samples of every footprint sensel of every usable frame:
    (sensel flat index, frame number, log sample), concatenated.

    The plane's tilt is relative to the placement's mean tilt (the person leans around
    the board's centre): a free tilt per frame would absorb any large-scale gain gradient."""
    place = placements(frames, xy)
    coefs: dict[int, np.ndarray] = {}
    for t, bf in enumerate(frames):
        if bf is None or len(bf.idx) < 20:
            continue
        p = curve.inverse(np.maximum(d_flat[t, bf.idx], 0) / (gain_flat[bf.idx] * curve.span_counts))
        coefs[t] = _plane_coef(xy[bf.idx], p)
    mean_tilt = {}
    for k in set(place[list(coefs)]):
        rel = np.array([coefs[t][1:3] / max(coefs[t][0], 1e-6) for t in coefs if place[t] == k])
        mean_tilt[k] = rel.mean(axis=0)
    idx, frm, val = [], [], []
    for t, co in coefs.items():
        bf = frames[t]
        a_, b_, c_, x0, y0 = co
        bt, ct = np.array([b_, c_]) / max(a_, 1e-6) - mean_tilt[place[t]]
        plane = np.maximum(a_ * (1.0 + bt * (xy[bf.idx, 0] - x0) + ct * (xy[bf.idx, 1] - y0)), 0.05)
        dv = d_flat[t, bf.idx]
        sample = dv / (curve.span_counts * curve.response(plane))
        good = sample > 0.05
        idx.append(bf.idx[good])
        frm.append(np.full(int(good.sum()), t))
        val.append(np.log(sample[good]))
    if not idx:
        return np.zeros(0, int), np.zeros(0, int), np.zeros(0)
    return np.concatenate(idx), np.concatenate(frm), np.concatenate(val)


def solve_gains(idx: np.ndarray, frm: np.ndarray, val: np.ndarray, n_sensels: int, n_frames: int,
                iterations: int = 40, level0: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """log sample = log gain[sensel] + log level[frame]: alternating means.

    The level absorbs each placement's mean gain (a plane fitted to uncorrected
    pressure is normalised to the local gains), so overlapping placements tie the
    whole carpet to one scale. Returns (log gain with NaN where unseen, sample count)."""
    count = np.bincount(idx, minlength=n_sensels).astype(float)
    fcount = np.bincount(frm, minlength=n_frames).astype(float)
    lg = np.zeros(n_sensels)
    lv = np.zeros(n_frames) if level0 is None else level0.copy()
    for _ in range(iterations):
        lg = np.bincount(idx, val - lv[frm], minlength=n_sensels) / np.maximum(count, 1)
        lv = np.bincount(frm, val - lg[idx], minlength=n_frames) / np.maximum(fcount, 1)
    solve_gains.last_level = lv
    lg = np.where(count > 0, lg, np.nan)
    return lg, count


def row_col_fill(log_g: np.ndarray, known: np.ndarray, iterations: int = 10) -> np.ndarray:
    """Fit log g ≈ a_r + b_c on known sensels (alternating means); evaluate everywhere."""
    a = np.zeros(log_g.shape[0])
    b = np.zeros(log_g.shape[1])
    for _ in range(iterations):
        with np.errstate(invalid="ignore"):
            res = np.where(known, log_g - b[None, :], 0.0)
            a = res.sum(axis=1) / np.maximum(known.sum(axis=1), 1)
            res = np.where(known, log_g - a[:, None], 0.0)
            b = res.sum(axis=0) / np.maximum(known.sum(axis=0), 1)
    return a[:, None] + b[None, :]


def board_equilibration(cap: Capture, baseline: np.ndarray, noise: np.ndarray, fault: np.ndarray,
                        curve: Curve | None = None, gain0: np.ndarray | None = None) -> StepResult:
    res = StepResult("board")
    ok, _ = frame_validity(cap.frames, cap.full_scale)
    raw = cap.frames[ok].astype(np.float32)
    h, w = cap.shape
    usable = (fault & UNUSABLE) == 0
    curve = curve or default_curve(baseline, cap.sign, cap.full_scale, usable)
    d = cap.sign * (raw - baseline[None])
    d[:, ~usable] = 0.0
    d[d < 3.0 * noise[None]] = 0.0
    g = np.ones((h, w)) if gain0 is None else gain0.astype(float).copy()
    stride = max(1, int(np.ceil(d.shape[0] / MAX_FRAMES)))  # neighbouring frames at 14 Hz are near copies
    d = d[::stride]
    p0 = curve.inverse(np.maximum(d, 0) / (g[None] * curve.span_counts))
    frames = board_frames(d, usable, p0, cap.pitch_m)
    n_used = sum(f is not None for f in frames)
    res.numbers["frames_used"] = n_used
    if n_used < 10:
        return res.refuse(f"the board was seen in only {n_used} frames: put the board flat on the carpet, stand "
                          "on it still, then move it to the next spot")
    rr, cc = np.mgrid[0:h, 0:w]
    xy = np.column_stack([(cc.ravel() + 0.5) * cap.pitch_m, (rr.ravel() + 0.5) * cap.pitch_m])
    d_flat = d.reshape(d.shape[0], -1)

    g_flat = g.ravel()
    nf = d.shape[0]
    level = None
    for _ in range(3):
        idx, frm, val = gain_samples(d_flat, frames, g_flat, curve, xy)
        lg, c = solve_gains(idx, frm, val, h * w, nf, level0=level)
        level = solve_gains.last_level
        lg -= np.nanmedian(lg[c >= 3])
        g_flat = np.where(c >= 3, np.exp(np.nan_to_num(lg)), 1.0)
    covered = (c >= 3).reshape(h, w) & usable
    log_g = np.log(g_flat).reshape(h, w)
    fill = row_col_fill(log_g, covered)
    log_g = np.where(covered, log_g, fill)
    raw_gain = np.exp(log_g)
    gain = np.clip(raw_gain, *GAIN_CLIP)

    # spread before (the measured gains) and after (held-out odd frames, gains from even frames)
    ev = frm % 2 == 0
    lg_e, c_e = solve_gains(idx[ev], frm[ev], val[ev], h * w, nf, level0=level)
    lg_o, c_o = solve_gains(idx[~ev], frm[~ev], val[~ev], h * w, nf, level0=level)
    both = (c_e >= 2) & (c_o >= 2)
    resid = (lg_o - lg_e)[both]
    resid = resid - np.median(resid) if resid.size else resid
    spread_before = float(_robust_std(log_g[covered]))
    spread_after = float(_robust_std(resid) / np.sqrt(2.0)) if resid.size else float("nan")
    res.numbers.update(gain_spread_before=round(spread_before, 4), gain_spread_after=round(spread_after, 4),
                       covered_fraction=round(float(covered.sum() / max(usable.sum(), 1)), 4),
                       clipped_sensels=int(((raw_gain < GAIN_CLIP[0]) | (raw_gain > GAIN_CLIP[1]))[usable].sum()),
                       board_spots_frames=n_used)
    res.arrays.update(gain=gain.astype(np.float32), raw_gain=raw_gain.astype(np.float32),
                      board_covered=covered)
    res.say(f"gain spread {spread_before:.1%} across the carpet; after equilibration {spread_after:.1%} "
            f"on held-out frames ({n_used} board frames, {covered.sum()} sensels covered)")
    if covered.sum() < 0.5 * usable.sum():
        res.say("the board covered less than half of the carpet; uncovered sensels use a row × column model")
    return res


def _robust_std(x: np.ndarray) -> float:
    x = x[np.isfinite(x)]
    if x.size == 0:
        return float("nan")
    return 1.4826 * float(np.median(np.abs(x - np.median(x))))
