"""A dose's validation at a glance: the full solver's time at each interfacial length, the
time after the front nucleated, the extrapolated limit ell -> 0 with its bound, and the
answer (docs/interfacial.md sec. 9).  Drawn from the answer's plain data alone."""

from __future__ import annotations

from pathlib import Path
from typing import Any


def draw_validation(answer: dict[str, Any], out: Path) -> Path:
    """Write the figure of ``answer`` (``DoseAnswer.to_dict()`` with a regularized
    validation) to ``out`` (PNG)."""
    rep = answer.get("validation") or {}
    if rep.get("limit") is None:
        raise ValueError("the answer has no regularized validation to draw (validate it, with "
                         "interfacial_length > 0)")
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    runs = [e for e in rep["runs"] if e.get("time") is not None]
    ells = [e["interfacial_length"] for e in runs]
    lim = rep["limit"]
    fig, ax = plt.subplots(figsize=(5.6, 4.0))
    ax.plot(ells, [e["time"] for e in runs], "o-", color="C0", label="full solver: dose time")
    after = [(e["interfacial_length"], e["time"] - e["nucleation_time"]) for e in runs
             if e.get("nucleation_time") is not None]
    if len(after) == len(runs):
        ax.plot(*zip(*after, strict=True), "s--", color="C1", mfc="none",
                label="time after the front nucleates")
    x0 = 0.0
    ax.errorbar([x0], [lim["time"]], yerr=[[lim["error"]], [lim["error"]]], fmt="D",
                color="k", capsize=4, label=f"limit ell -> 0: {lim['time']:.4g}")
    ax.axhline(answer["time"], color="C3", lw=1.2,
               label=f"answer ({answer['model']}): {answer['time']:.4g}")
    ax.set_xlim(-0.05 * max(ells), 1.08 * max(ells))
    ax.set_xlabel("interfacial length ell (dry radii)")
    ax.set_ylabel("time to the dose (units of tau)")
    ax.set_title(f"{answer['dose_fraction']:.0%} dose: error estimate "
                 f"{answer['error_estimate']:.1%}", fontsize=10)
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    out = Path(out)
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, dpi=120)
    plt.close(fig)
    return out
