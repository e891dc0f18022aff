"""A design map with the batch's CV as an axis (``thermogel sweep --size-cv``; issue 26):
the batch's delay against its mean bead over CV x dose, for one gel, T_end and mean size
(the spread a dose tolerates)."""

from __future__ import annotations

from pathlib import Path
from typing import Any, BinaryIO

import numpy as np


def cv_grid(table: dict[str, Any], gel_index: int = 0) -> tuple[np.ndarray, ...]:
    """(CVs, doses, delay in %: doses x CVs) at the grid's first T_end and radius."""
    g = table["grid"]
    shape = tuple(g["shape"])
    delay = np.full(shape, np.nan)
    for row in table["rows"]:
        if row.get("batch_delay") is not None:
            delay[np.unravel_index(row["index"], shape)] = 100.0 * row["batch_delay"]
    return (np.asarray(g["size_cvs"], dtype=float), np.asarray(g["doses"], dtype=float),
            delay[gel_index, 0, 0])


def draw_cv_map(table: dict[str, Any], target: str | Path | BinaryIO,
                gel_index: int = 0) -> str | Path | BinaryIO:
    """Contours (or lines, with a single CV or dose) of the batch's delay over CV x dose."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    cvs, doses, d = cv_grid(table, gel_index)
    g = table["grid"]
    fig, ax = plt.subplots(figsize=(6, 4.2))
    if len(cvs) >= 2 and len(doses) >= 2 and np.isfinite(d).sum() >= 4:
        cs = ax.contourf(cvs, doses, d, levels=[0, 5, 10, 25, 50, 75, 100, 150],
                         cmap="viridis", extend="max")
        ax.contour(cvs, doses, d, levels=[10, 25, 50], colors="w", linewidths=0.8)
        fig.colorbar(cs, ax=ax, label="batch's delay vs its mean bead (%)")
        ax.set_ylabel("dose (fraction of the stored fluid)")
    else:
        for j, f in enumerate(doses):
            ax.plot(cvs, d[j], "o-", label=f"dose {f:g}")
        ax.set_ylabel("batch's delay vs its mean bead (%)")
        ax.legend(fontsize=8)
    ax.set_xlabel("size CV (number-weighted lognormal)")
    name = g["gels"][gel_index].get("name", "custom")
    ax.set_title(f"{name} {g['t_start']:g} -> {g['t_ends'][0]:g} K, mean "
                 f"{g['dry_radii_um'][0]:g} um dry (white: +10, +25, +50 %)", fontsize=9)
    fig.tight_layout()
    fig.savefig(target, dpi=110)
    plt.close(fig)
    return target
