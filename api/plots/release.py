"""Figures of a drug run: cumulative release through a protocol, and concentration profiles."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from solver.solute import ReleaseResult


def _heating_spans(rel: ReleaseResult) -> list[tuple[float, float]]:
    """(start, end) of the stretches at the hottest temperature (the heatings)."""
    temp = np.asarray(rel.temperature)
    hot = temp >= temp.max() - 1e-9
    spans, start = [], None
    for k in range(temp.size):
        if hot[k] and start is None:
            start = rel.t[max(k - 1, 0)]
        if not hot[k] and start is not None:
            spans.append((start, rel.t[k - 1]))
            start = None
    if start is not None:
        spans.append((start, rel.t[-1]))
    return spans if temp.min() < temp.max() else []


def draw_release(rel: ReleaseResult, out: str | Path, tau_seconds: float | None = None,
                 doses: list[float] | None = None) -> Path:
    """Cumulative drug released (and its squeezed-out part) with the expelled fluid, through
    the protocol (heatings shaded; ``doses`` as cumulative target lines), beside the pore
    concentration profiles c/c0 against r."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (ax, bx) = plt.subplots(1, 2, figsize=(11, 4.2))
    scale = tau_seconds or 1.0
    t = rel.t * scale
    for a, b in _heating_spans(rel):
        ax.axvspan(a * scale, b * scale, color="tab:red", alpha=0.12, lw=0)
    ax.plot(t, rel.released_fraction, "k", label="drug released")
    ax.plot(t, rel.squeezed_fraction if np.size(rel.squeezed_fraction) == np.size(t)
            else rel.advected_fraction, "k--", lw=1,
            label="... squeezed out (the same heating with D0 = 0)")
    ax.plot(t, rel.expelled_fraction, "tab:blue", lw=1, label="fluid expelled (of stored)")
    if doses:
        for c in np.cumsum(doses):
            ax.axhline(c, color="grey", lw=0.6, ls=":")
    ax.set_xlabel("time (s)" if tau_seconds else "time t / tau")
    ax.set_ylabel("fraction of the load / stored fluid")
    ax.set_ylim(min(0.0, float(rel.expelled_fraction.min())) - 0.02, 1.02)
    ax.legend(fontsize=8, loc="lower right")
    ax.set_title("cumulative release (heatings shaded)")
    picks = np.unique(np.linspace(0, rel.profile_t.size - 1, 6).astype(int))
    cmap = plt.get_cmap("viridis")
    for j, k in enumerate(picks):
        lab = f"t = {rel.profile_t[k] * scale:.3g}" + (" s" if tau_seconds else "")
        bx.plot(rel.profile_radii[k], rel.profiles[k], color=cmap(j / max(len(picks) - 1, 1)),
                label=lab)
    bx.set_xlabel("r (dry radii)")
    bx.set_ylabel("pore concentration c / c0")
    bx.set_ylim(-0.02, max(1.05, float(np.nanmax(rel.profiles)) * 1.05))
    bx.legend(fontsize=8)
    bx.set_title("concentration profiles")
    fig.tight_layout()
    path = Path(out)
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return path


def draw_schedule_release(answer: dict[str, Any], rel: ReleaseResult, out: str | Path) -> Path:
    """:func:`draw_release` for a drug schedule's protocol run, with its doses."""
    return draw_release(rel, out, answer.get("timescale_seconds"), answer.get("doses"))
