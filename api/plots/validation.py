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


def draw_validation(answer: dict[str, Any], out: Path) -> Path:
    """Write the figure of ``answer`` (``DoseAnswer.to_dict()`` with a regularized
    validation, direct or ladder) to ``out`` (PNG)."""
    rep = answer.get("validation") or {}
    direct = rep.get("method") == "direct" and bool(rep.get("interfacial_length"))
    if not direct and rep.get("limit") is None:
        raise ValueError("the answer has no regularized validation to draw (validate it, with "
                         "interfacial_length > 0)")
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    if direct:
        fig = _direct_figure(plt, answer, rep)
    else:
        fig = _ladder_figure(plt, answer, rep)
    fig.tight_layout()
    out = Path(out)
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, dpi=120)
    plt.close(fig)
    return out


def _direct_figure(plt: Any, answer: dict[str, Any], rep: dict[str, Any]) -> Any:
    """Dose time against ell (log axis): the truth with its numerical bound, the ell range's
    ends (shaded), the delayed-transition time and the answer."""
    from matplotlib.ticker import NullFormatter

    ell, truth = float(rep["interfacial_length"]), float(rep["time"])
    unc = rep.get("uncertainty") or {}
    fig, ax = plt.subplots(figsize=(6.0, 5.4))
    span = [float(x) for x in unc.get("interfacial_lengths") or []]
    times = [t for t in unc.get("interfacial_length_times") or [] if t is not None]
    if len(span) == 2:
        ax.axvspan(min(span), max(span), color="C0", alpha=0.08,
                   label="plausible range of ell (mesh length)")
    if len(times) == len(span) and times:
        ax.plot(span, times, "s", color="C0", mfc="none", label="full solver at the range's ends")
    err = float(rep.get("error") or 0.0) * truth
    ax.errorbar([ell], [truth], yerr=[[err], [err]], fmt="o", color="C0", capsize=4,
                label=f"truth at the bead's ell = {ell:.3g}: {truth:.4g} (numerical bound)")
    ax.axhline(answer["time"], color="C3", lw=1.2,
               label=f"answer ({answer['model']}): {answer['time']:.4g}")
    delayed = unc.get("delayed_transition_time")
    if delayed is not None:  # far above the rest (1.5-9x): a legend line, not a data line
        ratio = float(unc.get("delayed_transition_ratio") or float(delayed) / truth)
        ax.plot([], [], " ", label=f"model form: the delayed transition gives {float(delayed):.4g}"
                                   f" ({ratio:.2f}x, off this scale)")
    ax.set_xscale("log")
    ax.xaxis.set_minor_formatter(NullFormatter())
    lo, hi = min([ell, *span]), max([ell, *span])
    ax.set_xlim(lo / 2.0, hi * 2.0)
    ax.set_xlabel("interfacial length ell (dry radii)")
    ax.set_ylabel("time to the dose (units of tau)")
    ax.set_title(f"{answer['dose_fraction']:.0%} dose, direct validation: error estimate "
                 f"{answer['error_estimate']:.1%}", fontsize=10)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7, loc="upper center", bbox_to_anchor=(0.5, -0.16), frameon=False)
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
