"""Figures of a full-solver run: porosity colour map in (t, r) with the front, and profiles
(paper figs. 5-10)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from solver.equilibrium import nearest_stable
from solver.full import FullResult
from solver.gel import Gel


def _title(res: FullResult) -> str:
    d = res.diagnostics
    steps = ", ".join(f"{T:g} K" for _, T in d.get("protocol", []))
    name = d.get("gel", {}).get("name", "")
    return f"{name}: {d.get('t_start', float('nan')):g} K -> {steps} ({d.get('grid', '')}, " \
           f"N = {d.get('n', '')})"


def _final_equilibrium(res: FullResult) -> tuple[float, float] | None:
    """(stretch, porosity) of the equilibrium the run relaxes to, if the run says which gel."""
    d = res.diagnostics
    try:
        gel = Gel.from_dict(d["gel"])
        temp = float(d["protocol"][-1][1])
        eq = nearest_stable(gel, temp, float(res.radius[-1]))
    except (KeyError, TypeError, ValueError, IndexError):
        return None
    return eq.stretch, eq.porosity


def draw_colour_map(res: FullResult, out: Path) -> Path:
    """Porosity phi(r, t) with the radius a(t) (black) and the front R_f(t) (red)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    radii = res.cell_radii()
    tt = np.broadcast_to(res.t[:, None], radii.shape)
    fig, ax = plt.subplots(figsize=(6.5, 4.5))
    mesh = ax.pcolormesh(tt, radii, res.phi, shading="gouraud", cmap="viridis",
                         vmin=0.0, vmax=1.0, rasterized=True)
    ax.plot(res.t, res.radius, "k-", lw=1.2, label="radius a(t)")
    if np.any(np.isfinite(res.front)):
        ax.plot(res.t, res.front, "r-", lw=1.5, label="front $R_f(t)$")
    ax.set_xlabel("time t")
    ax.set_ylabel("radius r")
    ax.set_xlim(res.t[0], res.t[-1])
    ax.set_ylim(0.0, 1.02 * float(np.max(res.radius)))
    fig.colorbar(mesh, ax=ax, label="porosity $\\phi$")
    ax.set_title(_title(res), fontsize=9)
    if res.spinodal:
        ax.text(0.02, 0.02, "spinodal collapse: grid-dependent", transform=ax.transAxes,
                color="w", fontsize=8)
    ax.legend(loc="upper right", fontsize=8)
    fig.tight_layout()
    fig.savefig(out, dpi=150)
    plt.close(fig)
    return out


def draw_profiles(res: FullResult, out: Path, count: int = 9) -> Path:
    """Porosity against r at evenly spaced output times, with the final equilibrium dashed."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    radii = res.cell_radii()
    fig, ax = plt.subplots(figsize=(6.5, 4.5))
    picks = np.unique(np.linspace(0, res.t.size - 1, count).astype(int))
    colours = plt.cm.plasma(np.linspace(0.0, 0.9, picks.size))
    for k, c in zip(picks, colours, strict=True):
        r = np.concatenate([radii[k], [res.radius[k]]])
        p = np.concatenate([res.phi[k], [res.phi[k][-1]]])
        ax.plot(r, p, color=c, lw=1.2, label=f"t = {res.t[k]:.3g}")
    eq = _final_equilibrium(res)
    if eq is not None:
        ax.plot([0.0, eq[0]], [eq[1], eq[1]], "k--", lw=1.0, label="final equilibrium")
    ax.set_xlabel("radius r")
    ax.set_ylabel("porosity $\\phi$")
    ax.set_xlim(0.0, 1.02 * float(np.max(res.radius)))
    ax.set_title(_title(res), fontsize=9)
    ax.legend(fontsize=7, ncol=2)
    fig.tight_layout()
    fig.savefig(out, dpi=150)
    plt.close(fig)
    return out


def draw_run(res: FullResult, out_dir: str | Path, fmt: str = "png") -> list[Path]:
    """Both figures into ``out_dir``; returns the files written."""
    d = Path(out_dir)
    d.mkdir(parents=True, exist_ok=True)
    return [draw_colour_map(res, d / f"porosity_map.{fmt}"),
            draw_profiles(res, d / f"porosity_profiles.{fmt}")]
