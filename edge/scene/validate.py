"""Frame validation: a bad frame gets a reason (counted by the caller), never an exception.

Reasons, checked in this order:

- ``not_an_array``        the input is not a numeric array;
- ``shape_mismatch``      pressure is not (rows, cols);
- ``mask_shape_mismatch`` the masks are not a (rows, cols) array;
- ``bad_time``            the timestamp is not finite;
- ``time_not_increasing`` the timestamp is not after the last valid frame's (duplicate or reordered);
- ``non_finite``          more NaN/Inf sensels (outside the masks) than ``max_nonfinite_fraction``;
- ``constant``            every usable sensel reads the same non-zero value (a stuck readout;
                          an all-zero frame is accepted as empty because calibration may clip at 0);
- ``out_of_range``        a usable sensel outside [min_pressure_kpa, max_pressure_kpa];
- ``implausible_force``   total force outside [min_total_force_n, max_total_force_n].
"""

from __future__ import annotations

import math

import numpy as np

from edge.scene.config import SceneConfig

REASONS = ("not_an_array", "shape_mismatch", "mask_shape_mismatch", "bad_time", "time_not_increasing", "non_finite",
           "constant", "out_of_range", "implausible_force")


def check_frame(
    pressure_kpa: object,
    masks: object,
    t_s: object,
    shape: tuple[int, int],
    pitch_m: float,
    last_t_s: float | None,
    config: SceneConfig,
) -> tuple[str | None, np.ndarray | None, np.ndarray | None]:
    """Check one frame.

    pressure_kpa: (H, W) numeric; masks: (H, W) bool of unusable sensels or None.
    Returns (reason or None, pressure as float32 (H, W), unusable (H, W) bool including
    tolerated non-finite sensels, or None when every sensel is usable).
    """
    if not isinstance(pressure_kpa, np.ndarray) or pressure_kpa.dtype.kind not in "fiu":
        return "not_an_array", None, None
    if pressure_kpa.shape != shape:
        return "shape_mismatch", None, None
    if masks is not None and (not isinstance(masks, np.ndarray) or masks.shape != shape):
        return "mask_shape_mismatch", None, None
    try:
        t = float(t_s)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        return "bad_time", None, None
    if not math.isfinite(t):
        return "bad_time", None, None
    if last_t_s is not None and t <= last_t_s:
        return "time_not_increasing", None, None
    p = pressure_kpa.astype(np.float32, copy=False)
    bad = masks.astype(bool, copy=False) if masks is not None and masks.any() else None
    finite = np.isfinite(p)
    if not finite.all():
        nonfinite = ~finite if bad is None else ~finite & ~bad
        if nonfinite.sum() > config.max_nonfinite_fraction * p.size:
            return "non_finite", None, None
        bad = ~finite if bad is None else bad | ~finite
        p = np.where(finite, p, np.float32(0.0))
    usable = p if bad is None else p[~bad]
    if usable.size == 0:
        return "constant", None, None
    lo, hi = float(usable.min()), float(usable.max())
    if lo == hi and hi != 0.0:
        return "constant", None, None
    if lo < config.min_pressure_kpa or hi > config.max_pressure_kpa:
        return "out_of_range", None, None
    total_n = float(usable.sum(dtype=np.float64)) * pitch_m * pitch_m * 1e3
    if not config.min_total_force_n <= total_n <= config.max_total_force_n:
        return "implausible_force", None, None
    return None, p, bad
