"""One figure style for every thermogel plot: sizes, fonts, line widths and the saver.

``save(fig, out, fmt)`` writes PNG (300 dpi), SVG or PDF by ``fmt`` or the file's suffix
(the ``--format`` option of the drawing commands)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

FORMATS = ("png", "svg", "pdf")
RC = {
    "figure.figsize": (6.4, 4.2), "font.size": 10, "axes.labelsize": 10,
    "axes.titlesize": 10, "legend.fontsize": 8.5, "xtick.labelsize": 9, "ytick.labelsize": 9,
    "lines.linewidth": 1.5, "axes.spines.top": False, "axes.spines.right": False,
    "savefig.bbox": "tight", "figure.dpi": 100, "axes.grid": False,
    "legend.frameon": True, "legend.framealpha": 0.85, "legend.edgecolor": "0.85",
    "mathtext.default": "regular", "svg.fonttype": "none", "pdf.fonttype": 42,
}


def pyplot() -> Any:
    """matplotlib.pyplot on the Agg backend with the thermogel style applied."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    plt.rcParams.update(RC)
    return plt


def save(fig: Any, out: str | Path, fmt: str | None = None) -> Path:
    """Write ``fig`` to ``out`` as ``fmt`` (or by the suffix; PNG by default) and close it."""
    p = Path(out)
    kind = (fmt or p.suffix.lstrip(".") or "png").lower()
    if kind not in FORMATS:
        raise ValueError(f"format {kind!r}: one of {', '.join(FORMATS)}")
    if p.suffix.lstrip(".").lower() != kind:
        p = p.with_suffix("." + kind)
    p.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(p, format=kind, dpi=300 if kind == "png" else None)
    import matplotlib.pyplot as plt

    plt.close(fig)
    return p
