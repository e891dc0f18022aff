"""Bar plot of global sensitivity indices of the dose time (dosing.studies.sensitivity)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from .style import pyplot, save


def draw_sensitivity(result: dict[str, Any], out: str | Path, fmt: str | None = None) -> Path:
    """Sobol S1 and ST (with their 95% intervals) or Morris mu* (with sigma) per input."""
    plt = pyplot()
    names, idx = result["names"], result["indices"]
    x = np.arange(len(names))
    fig, ax = plt.subplots(figsize=(max(4.0, 1.1 * len(names) + 2.0), 3.6))
    if result["method"] == "sobol":
        w = 0.38
        for k, (key, label, color) in enumerate((("S1", "first order $S_1$", "#4C72B0"),
                                                  ("ST", "total $S_T$", "#DD8452"))):
            ax.bar(x + (k - 0.5) * w, [idx[n][key] for n in names], w,
                   yerr=[idx[n][key + "_conf"] for n in names], capsize=3, label=label,
                   color=color)
        ax.set_ylabel("Sobol index of the dose time")
        ax.set_ylim(min(0.0, ax.get_ylim()[0]), max(1.05, ax.get_ylim()[1]))
        ax.axhline(0.0, color="k", lw=0.6)
    else:
        ax.bar(x - 0.2, [idx[n]["mu_star"] for n in names], 0.4,
               yerr=[idx[n]["mu_star_conf"] for n in names], capsize=3, label=r"$\mu^*$",
               color="#4C72B0")
        ax.bar(x + 0.2, [idx[n]["sigma"] for n in names], 0.4, label=r"$\sigma$",
               color="#DD8452")
        ax.set_ylabel("Morris elementary effect (s)")
    ax.set_xticks(x, [n + (" (log)" if v.get("log") else "") for n, v in
                      zip(names, result["vary"], strict=True)], rotation=20, ha="right")
    ax.legend()
    summary = result.get("output_summary") or {}
    if summary:
        ax.set_title(f"dose time: median {summary['median']:.3g} s "
                     f"(5-95%: {summary['p05']:.3g}-{summary['p95']:.3g} s), "
                     f"{result['evaluations']} front-model answers", fontsize=9)
    return save(fig, out, fmt)
