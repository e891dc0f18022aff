"""Work-precision diagram (issue 7): wall time against error, log-log, one line per method and
one panel per case, from the rows of benchmarks/work_precision.py."""

from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path
from typing import Any

METRICS = {"err_a": "max relative error of a(t)", "err_t80": "relative error of the 80% time"}


def _points(rows: Sequence[dict[str, Any]], metric: str) -> list[tuple[float, float]]:
    """(error, wall) pairs of the rows with a positive, finite error and wall time, in the
    rows' order (the sweep order)."""
    pts = []
    for r in rows:
        err, wall = r.get(metric), r.get("wall_s")
        if err is not None and wall is not None and err > 0 and wall > 0 and math.isfinite(err):
            pts.append((float(err), float(wall)))
    return pts


def draw_work_precision(rows: Sequence[dict[str, Any]], out: Path,
                        metric: str = "err_a", title: str = "") -> Path:
    """Write the diagram of ``metric`` ('err_a' or 'err_t80') for every case in ``rows``."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.ticker import NullFormatter

    cases = list(dict.fromkeys(r["case"] for r in rows))
    methods = list(dict.fromkeys(r["method"] for r in rows))
    cols = min(3, max(1, len(cases)))
    nrows = math.ceil(len(cases) / cols)
    fig, axes = plt.subplots(nrows, cols, figsize=(4.6 * cols, 3.8 * nrows), squeeze=False)
    styles = {m: (f"C{i % 10}", "os^vD<>ph*"[i % 10]) for i, m in enumerate(methods)}
    for ax, case in zip(axes.flat, cases, strict=False):
        for method in methods:
            pts = _points([r for r in rows if r["case"] == case and r["method"] == method],
                          metric)
            if not pts:
                continue
            colour, marker = styles[method]
            hollow = method.startswith("explicit")
            ax.plot(*zip(*pts, strict=True), marker=marker, color=colour,
                    ls="none" if len(pts) == 1 else "-", label=method,
                    mfc="none" if hollow else colour)
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.xaxis.set_minor_formatter(NullFormatter())
        ax.set_title(case, fontsize=10)
        ax.set_xlabel(METRICS[metric], fontsize=8)
        ax.set_ylabel("wall time (s)", fontsize=8)
        ax.grid(True, which="both", alpha=0.3)
    for ax in list(axes.flat)[len(cases):]:
        ax.axis("off")
    handles = {}
    for ax in axes.flat:
        for h, lab in zip(*ax.get_legend_handles_labels(), strict=True):
            handles.setdefault(lab, h)
    fig.legend(handles.values(), handles.keys(), loc="lower center", ncol=3, fontsize=8,
               frameon=False)
    fig.suptitle(title or "work-precision (explicit: hollow, extrapolated wall time)",
                 fontsize=10)
    fig.tight_layout(rect=(0, 0.06 + 0.02 * math.ceil(len(handles) / 3), 1, 0.96))
    out = Path(out)
    fig.savefig(out, dpi=120)
    plt.close(fig)
    return out
