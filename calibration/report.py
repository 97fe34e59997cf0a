"""The calibration report: a PNG (baseline, noise, gain, faults, coverage, curve) and a
text summary with every step's findings and the validation figures.

matplotlib is imported here only (it is not a runtime dependency).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from calibration.file import FAULT, Calibration
from calibration.result import StepResult


def text_summary(cal: Calibration, results: dict[str, StepResult], validation: StepResult) -> str:
    d = cal.device
    lines = [f"CAvatar carpet calibration — {d['device_id']} ({d['rows']}×{d['cols']}, {d['adc_bits']} bit, "
             f"sign {d['sign']:+d}, firmware {'.'.join(map(str, d.get('firmware', [])))}), created {cal.created}",
             f"curve: P½ {cal.curve.half_scale_kpa:.2f} kPa, exponent {cal.curve.exponent:.2f}, span "
             f"{cal.curve.span_counts:.0f} counts, ceiling {cal.curve.saturation_kpa:.1f} kPa; crosstalk R·g "
             f"{cal.crosstalk_r_norm:g}", ""]
    for step, r in results.items():
        lines.append(r.summary())
    lines += ["", validation.summary(), "", "Validation figures:"]
    for k, v in validation.numbers.items():
        lines.append(f"  {k}: {v}")
    b = results.get("board")
    if b is not None:
        lines.append(f"  gain spread: {b.numbers.get('gain_spread_before', float('nan')):.1%} raw → "
                     f"{b.numbers.get('gain_spread_after', float('nan')):.1%} repeatability after equilibration")
    lines.append(f"  sha256: {cal.sha256 or '(not saved)'}")
    return "\n".join(lines) + "\n"


def write_report(cal: Calibration, results: dict[str, StepResult], validation: StepResult, png: str | Path,
                 txt: str | Path | None = None) -> bool:
    """Write the text summary (``txt``) and the PNG; False when matplotlib (the viz extra) is missing,
    so a board without it still calibrates and keeps the text report."""
    if txt is not None:
        Path(txt).write_text(text_summary(cal, results, validation))
    try:
        import matplotlib
    except ImportError:
        return False

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(2, 3, figsize=(13, 8.2))
    usable = cal.usable
    base = np.where(usable, cal.baseline_counts, np.nan)
    panels = [
        (ax[0, 0], base, "baseline (counts)", "viridis", None),
        (ax[0, 1], np.where(usable, cal.noise_counts, np.nan), "noise σ (counts)", "magma", None),
        (ax[0, 2], np.where(usable, cal.gain, np.nan), "gain (relative)", "coolwarm", (0.5, 2.0)),
    ]
    for a, img, title, cmap, lim in panels:
        lo, hi = lim or np.nanpercentile(img, [1, 99])
        im = a.imshow(img, cmap=cmap, vmin=lo, vmax=hi, interpolation="nearest")
        a.set_title(title)
        fig.colorbar(im, ax=a, fraction=0.046)
    codes = np.zeros(cal.shape)
    names = ["ok", "dead", "weak", "stuck", "noisy", "short", "outside"]
    for k in ("weak", "noisy", "short", "stuck", "outside", "dead"):  # later kinds win where flags overlap
        codes[(cal.fault & FAULT[k]) > 0] = names.index(k)
    names[2] = "weak (usable)"
    cmap = matplotlib.colors.ListedColormap(["#f4f4f4", "#d62728", "#ff7f0e", "#1f1f1f", "#9467bd", "#17becf", "#bbbbbb"])
    im = ax[1, 0].imshow(codes, cmap=cmap, vmin=-0.5, vmax=6.5, interpolation="nearest")
    cb = fig.colorbar(im, ax=ax[1, 0], fraction=0.046, ticks=range(7))
    cb.ax.set_yticklabels(names)
    ax[1, 0].set_title(f"faults ({int((~usable).sum())} sensels masked)")
    w = results.get("walk")
    if w is not None and "coverage" in w.arrays:
        im = ax[1, 1].imshow(np.log1p(w.arrays["coverage"]), cmap="Greens", interpolation="nearest")
        ax[1, 1].set_title(f"walk coverage (log frames active), {w.numbers.get('coverage_fraction', 0):.0%}")
        fig.colorbar(im, ax=ax[1, 1], fraction=0.046)
    else:
        ax[1, 1].set_title("no coverage walk")
    p = np.linspace(0, cal.curve.saturation_kpa * 1.2, 200)
    ax[1, 2].plot(p, cal.curve.span_counts * cal.curve.response(p), label="gain 1")
    for g in (0.7, 1.4):
        ax[1, 2].plot(p, g * cal.curve.span_counts * cal.curve.response(p), "--", lw=0.8, label=f"gain {g}")
    ax[1, 2].axvline(cal.curve.saturation_kpa, color="k", lw=0.6)
    ax[1, 2].set_xlabel("pressure (kPa)")
    ax[1, 2].set_ylabel("counts from baseline")
    v = validation.numbers
    fe = v.get("force_error")
    ax[1, 2].set_title(f"curve; held-out force error {fe:+.1%}" if fe is not None else "curve")
    ax[1, 2].legend(fontsize=8)
    for a in ax.flat[:5]:
        a.set_xlabel(a.get_xlabel() or "column")
        a.set_ylabel(a.get_ylabel() or "row")
    fig.suptitle(f"{cal.device['device_id']}: {v.get('usable_sensels')} / {v.get('sensels')} usable, noise floor "
                 f"{v.get('noise_floor_kpa', float('nan')) * 1000:.0f} Pa")
    fig.tight_layout()
    fig.savefig(png, dpi=90)
    plt.close(fig)
    return True
