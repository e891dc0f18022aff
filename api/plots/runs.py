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


def _scales(dry_radius_um: float | None, tau_s: float | None) -> tuple[float, str, float, str]:
    """(length factor, length label, time factor, time label): um and s where the bead size
    (and tau) are known, else dry radii and tau."""
    length = (dry_radius_um, "radius r (um)") if dry_radius_um else (1.0, "radius r / dry radius")
    time = (tau_s, "time (s)") if tau_s else (1.0, "time t / tau")
    return length[0], length[1], time[0], time[1]


def draw_colour_map(res: FullResult, out: Path, dry_radius_um: float | None = None,
                    tau_s: float | None = None) -> Path:
    """Porosity phi(r, t) with the radius a(t) (black) and the front R_f(t) (red); in um
    and s when the bead's dry radius and tau (eq. timescale) are given."""
    from .style import pyplot, save

    plt = pyplot()
    lf, llab, tf, tlab = _scales(dry_radius_um, tau_s)
    radii = res.cell_radii() * lf
    t = res.t * tf
    tt = np.broadcast_to(t[:, None], radii.shape)
    fig, ax = plt.subplots(figsize=(6.5, 4.5))
    mesh = ax.pcolormesh(tt, radii, res.phi, shading="gouraud", cmap="viridis",
                         vmin=0.0, vmax=1.0, rasterized=True)
    ax.plot(t, res.radius * lf, "k-", lw=1.2, label="radius a(t)")
    if np.any(np.isfinite(res.front)):
        ax.plot(t, res.front * lf, "r-", lw=1.5, label="front $R_f(t)$")
    ax.set_xlabel(tlab)
    ax.set_ylabel(llab)
    ax.set_xlim(t[0], t[-1])
    ax.set_ylim(0.0, 1.02 * float(np.max(res.radius)) * lf)
    fig.colorbar(mesh, ax=ax, label="porosity $\\phi$")
    ax.set_title(_title(res), fontsize=9)
    if res.spinodal:
        ax.text(0.02, 0.02, "spinodal collapse: grid-dependent", transform=ax.transAxes,
                color="w", fontsize=8)
    ax.legend(loc="upper right", fontsize=8)
    fig.tight_layout()
    return save(fig, out)


def draw_profiles(res: FullResult, out: Path, count: int = 9,
                  dry_radius_um: float | None = None, tau_s: float | None = None) -> Path:
    """Porosity against r at evenly spaced output times, with the final equilibrium dashed
    (r in um and t in s when the bead's dry radius and tau are given)."""
    from .style import pyplot, save

    plt = pyplot()
    lf, llab, tf, tlab = _scales(dry_radius_um, tau_s)
    radii = res.cell_radii() * lf
    fig, ax = plt.subplots(figsize=(6.5, 4.5))
    picks = np.unique(np.linspace(0, res.t.size - 1, count).astype(int))
    colours = plt.cm.plasma(np.linspace(0.0, 0.9, picks.size))
    unit = " s" if tau_s else ""
    for k, c in zip(picks, colours, strict=True):
        r = np.concatenate([radii[k], [res.radius[k] * lf]])
        p = np.concatenate([res.phi[k], [res.phi[k][-1]]])
        ax.plot(r, p, color=c, lw=1.2, label=f"t = {res.t[k] * tf:.3g}{unit}")
    eq = _final_equilibrium(res)
    if eq is not None:
        ax.plot([0.0, eq[0] * lf], [eq[1], eq[1]], "k--", lw=1.0, label="final equilibrium")
    ax.set_xlabel(llab)
    ax.set_ylabel("porosity $\\phi$")
    ax.set_xlim(0.0, 1.02 * float(np.max(res.radius)) * lf)
    ax.set_title(_title(res), fontsize=9)
    ax.legend(fontsize=7, ncol=2)
    fig.tight_layout()
    return save(fig, out)


def draw_run(res: FullResult, out_dir: str | Path, fmt: str = "png",
             dry_radius_um: float | None = None, tau_s: float | None = None) -> list[Path]:
    """Both figures into ``out_dir``; returns the files written (physical axes, um and s,
    when the bead's dry radius and tau are given)."""
    d = Path(out_dir)
    d.mkdir(parents=True, exist_ok=True)
    return [draw_colour_map(res, d / f"porosity_map.{fmt}", dry_radius_um, tau_s),
            draw_profiles(res, d / f"porosity_profiles.{fmt}", dry_radius_um=dry_radius_um,
                          tau_s=tau_s)]
