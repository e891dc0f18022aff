"""A dose's validation at a glance, drawn from the answer's plain data alone.

A direct validation (issue 12, the default): the full solver's dose time at the bead's own
interfacial length with its numerical bound (n against n/2 cells), the times at the ends of
the mesh length's plausible range, the delayed-transition bound of the model form, and the
answer.  A ladder validation (issue 8): the time at each rung, the time after the front
nucleated, the extrapolated limit ell -> 0 with its bound, and the answer
(docs/interfacial.md sec. 9-10)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np


def draw_validation(answer: dict[str, Any], out: Path, fmt: str | None = None) -> Path:
    """Write the figure of ``answer`` (``DoseAnswer.to_dict()`` with a regularized
    validation, direct or ladder) to ``out`` (PNG)."""
    rep = answer.get("validation") or {}
    direct = rep.get("method") == "direct" and bool(rep.get("interfacial_length"))
    if not direct and rep.get("limit") is None:
        raise ValueError("the answer has no regularized validation to draw (validate it, with "
                         "interfacial_length > 0)")
    from .style import pyplot, save

    plt = pyplot()
    if direct:
        fig = _direct_figure(plt, answer, rep)
    else:
        fig = _ladder_figure(plt, answer, rep)
    fig.tight_layout()
    return save(fig, out, fmt or (Path(out).suffix.lstrip(".") or None))


def _direct_figure(plt: Any, answer: dict[str, Any], rep: dict[str, Any]) -> Any:
    """A dot chart of the dose times (units of tau, and s on a second axis when the bead
    size is known): the truth at the bead's ell with its numerical bound, the times at the
    ends of the ell range, the delayed-transition time of the model form and the answer,
    one row each, so every estimate is on one linear time axis (not a single point on an
    empty log-ell axis)."""
    ell, truth = float(rep["interfacial_length"]), float(rep["time"])
    unc = rep.get("uncertainty") or {}
    rows: list[tuple[str, float, float, str, str]] = []  # label, time, +-, marker, colour
    err = float(rep.get("error") or 0.0) * truth
    rows.append((f"truth: ell = {ell:.2g} (bead's own)\n+- numerical bound (n vs n/2)", truth,
                 err, "o", "C0"))
    span = [float(x) for x in unc.get("interfacial_lengths") or []]
    times = list(unc.get("interfacial_length_times") or [])
    for x, t in zip(span, times, strict=False):
        if t is not None:
            rows.append((f"ell = {x:.2g} (end of the mesh-length range)", float(t), 0.0, "s",
                         "C0"))
    delayed = unc.get("delayed_transition_time")
    if delayed is not None:
        spread = float(unc.get("delayed_transition_spread") or 0.0) * float(delayed)
        rows.append(("model form: delayed transition (ell = 0)", float(delayed), spread, "D",
                     "C7"))
    rows.append((f"answer ({answer['model']})", float(answer["time"]),
                 float(answer.get("error_estimate") or 0.0) * float(answer["time"]), "*",
                 "C3"))
    fig, ax = plt.subplots(figsize=(6.4, 0.55 * len(rows) + 1.9))
    ys = np.arange(len(rows))[::-1]
    for y, (_, t, e, marker, colour) in zip(ys, rows, strict=True):
        ax.errorbar([t], [y], xerr=[[e], [e]] if e else None, fmt=marker, color=colour,
                    capsize=4, ms=8 if marker == "*" else 6)
    ax.axvline(truth, color="C0", lw=0.6, ls=":")
    ax.set_yticks(ys, [r[0] for r in rows], fontsize=8)
    ax.set_ylim(-0.6, len(rows) - 0.4)
    ax.set_xlabel("time to the dose (units of tau)")
    tau = answer.get("timescale_seconds")
    if tau:
        sec = ax.secondary_xaxis("top", functions=(lambda t: t * tau, lambda s: s / tau))
        sec.set_xlabel("time to the dose (s)")
    ax.set_title(f"{answer['dose_fraction']:.0%} dose, direct validation: error estimate "
                 f"{answer['error_estimate']:.1%}", fontsize=10)
    ax.grid(True, axis="x", alpha=0.3)
    return fig


def _ladder_figure(plt: Any, answer: dict[str, Any], rep: dict[str, Any]) -> Any:
    """Dose time against ell on the ladder's rungs, the limit ell -> 0 and the answer."""
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
    return fig
