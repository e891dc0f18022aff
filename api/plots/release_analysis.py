"""Plots of release analysis (issue 38): two profiles with their units' spread (``thermogel
compare``), a profile with the empirical models fitted to it (``thermogel fit empirical``)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from .style import pyplot, save


def _profile(ax: Any, side: dict[str, Any], times: list[float], color: str,
             label: str) -> None:
    t = np.asarray(times, float)
    m = np.asarray(side["mean_percent"], float)
    sd = side.get("sd_percent")
    ax.plot(t, m, "o-", color=color, ms=4, label=f"{label} (mean of {side['n_units']})")
    if sd is not None:
        s = np.asarray(sd, float)
        ax.fill_between(t, m - s, m + s, color=color, alpha=0.2, lw=0,
                        label=f"{label}: +- 1 SD of the units")


def draw_comparison(report: dict[str, Any], times: list[float], out: str | Path,
                    fmt: str | None = None) -> Path:
    """Both profiles (mean and +- SD band), the points f2 used marked, f1/f2 in the title."""
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(6.4, 4.2))
    _profile(ax, report["reference"], times, "C0", report["reference"]["label"] or "reference")
    _profile(ax, report["test"], times, "C3", report["test"]["label"] or "test")
    used = np.asarray(report["times_used"], float)
    ax.plot(used, np.asarray(report["reference_mean"])[report["points_used"]], "ks", ms=7,
            mfc="none", label="points f2 uses")
    ax.axhline(85.0, color="0.6", lw=0.8, ls="--")
    ax.set_xlabel(f"time ({report['time_unit']})")
    ax.set_ylabel("released (% of the load)")
    title = f"f1 = {report['f1']:.1f}, f2 = {report['f2']:.1f}"
    b = report.get("bootstrap")
    if b:
        lo, hi = b["interval_bca"]
        title += f"; bootstrap {b['confidence']:.0%} BCa [{lo:.1f}, {hi:.1f}]"
    ax.set_title(title, fontsize=9)
    ax.legend(fontsize=7, loc="lower right")
    return save(fig, out, fmt)


def draw_empirical(report: dict[str, Any], out: str | Path, fmt: str | None = None) -> Path:
    """The profile (mean +- SD) with every fitted model's curve; the best by AIC bold."""
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(6.4, 4.2))
    prof = report["profile"]
    t = np.asarray(prof["time"], float)
    m = np.asarray(prof["mean_percent"], float)
    sd = prof.get("sd_percent")
    ax.errorbar(t, m, yerr=None if sd is None else sd, fmt="ko", ms=4, capsize=2,
                label="data")
    for k, (name, fit) in enumerate(report["models"].items()):
        tt = np.asarray(fit["curve_time"], float)
        best = name == report["best"]
        ax.plot(tt, fit["curve"], color=f"C{k}", lw=2.2 if best else 1.0,
                label=f"{fit['title']} (AIC {fit['aic']:.1f})" + (" best" if best else ""))
    ax.set_xlabel(f"time ({report['time_unit']})")
    ax.set_ylabel("released (% of the load)")
    ax.set_ylim(bottom=0)
    ax.legend(fontsize=7, loc="lower right")
    return save(fig, out, fmt)
