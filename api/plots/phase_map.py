"""The phase map of a gel (paper fig. 3): equilibrium curve, spinodal and coexistence regions."""

from __future__ import annotations

from pathlib import Path
from typing import Any, BinaryIO

import numpy as np

from solver.equilibrium import equilibrium_curve, folds
from solver.gel import Gel
from solver.limits import T_MAX, T_MIN
from solver.phase import _normal_grid, spinodal_stiffness, tangent_gap


def region_masks(gel: Gel, temps: np.ndarray, stretches: np.ndarray) -> tuple[np.ndarray, ...]:
    """Boolean (spinodal, coexistence) masks on the (stretch, T) grid (eqs. Spinodal, Coexistence).

    The tangent gap is affine in T, so one scan over normal stretches serves every T.
    """
    spin = np.zeros((stretches.size, temps.size), dtype=bool)
    coex = np.zeros_like(spin)
    for i, lam in enumerate(stretches):
        spin[i] = spinodal_stiffness(gel, temps, lam) < 0
        grid = _normal_grid(lam, 600)
        g0 = tangent_gap(gel, 0.0, grid, lam)
        g1 = tangent_gap(gel, 1.0, grid, lam) - g0
        gaps = g0[None, :] + temps[:, None] * g1[None, :]
        coex[i] = gaps.min(axis=1) < -1e-9
    return spin, coex


def draw_phase_map(gel: Gel, out: str | Path | BinaryIO, t_min: float | None = None,
                   t_max: float | None = None, lambda_max: float | None = None,
                   jump: tuple[float, float, float, float] | None = None,
                   fmt: str = "svg", size: tuple[float, float] = (6, 4.5)) -> Path | BinaryIO:
    """Draw fig. 3 for ``gel`` to ``out`` (PNG or PDF; a file object gets ``fmt``) and
    return it.  ``jump = (T_start, a0, T_end, a_final)`` draws the heating jump at fixed
    stretch and the shrinking to the final equilibrium that follows it."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fl = folds(gel)
    centre = np.mean([f.temperature for f in fl]) if fl else 305.0
    t_min = t_min if t_min is not None else max(T_MIN, centre - 10.0)
    t_max = t_max if t_max is not None else min(T_MAX, centre + 10.0)
    curve = equilibrium_curve(gel, t_min, t_max)
    lam_hi = lambda_max if lambda_max is not None else 1.15 * float(curve.stretch.max())
    temps = np.linspace(t_min, t_max, 300)
    lams = np.linspace(1.0 + 1e-3, lam_hi, 220)
    spin, coex = region_masks(gel, temps, lams)
    if jump is not None:
        t_min = min(t_min, jump[0] - 1.0, jump[2] - 1.0)
        t_max = max(t_max, jump[0] + 1.0, jump[2] + 1.0)
    fig, ax = plt.subplots(figsize=size)
    ax.contourf(temps, lams, coex.astype(float), levels=[0.5, 1.5], colors=["#c6dbef"])
    ax.contourf(temps, lams, spin.astype(float), levels=[0.5, 1.5], colors=["#6baed6"])
    ax.contour(temps, lams, spin.astype(float), levels=[0.5], colors="k", linestyles="--",
               linewidths=0.8)
    ax.contour(temps, lams, coex.astype(float), levels=[0.5], colors="k", linestyles=":",
               linewidths=0.8)
    st = curve.stable
    lam_s = np.where(st, curve.stretch, np.nan)
    lam_u = np.where(~st, curve.stretch, np.nan)
    ax.plot(curve.temperature, lam_s, "C3-", lw=2, label="stable equilibrium")
    ax.plot(curve.temperature, lam_u, "C3-", lw=1, alpha=0.5, label="unstable equilibrium")
    for f in fl:
        ax.axvline(f.temperature, color="grey", lw=0.5)
    if jump is not None:
        _draw_jump(ax, *jump)
    ax.set_xlim(t_min, t_max)
    ax.set_ylim(1.0, lam_hi)
    ax.set_xlabel("temperature T (K)")
    ax.set_ylabel("stretch $\\lambda$")
    ax.set_title(f"{gel.name}: equilibria, spinodal (dark) and coexistence (light) regions")
    ax.legend(loc="upper right", fontsize=8)
    fig.tight_layout()
    if isinstance(out, (str, Path)):
        out = Path(out)
        fig.savefig(out, dpi=150)
    else:
        fig.savefig(out, dpi=150, format=fmt)
    plt.close(fig)
    return out


def _draw_jump(ax: Any, t0: float, a0: float, t1: float, a1: float) -> None:
    """The jump T_start -> T_end at the start stretch (arrow), then the bead's way to the
    final equilibrium at T_end (dotted), with both equilibria marked."""
    ax.annotate("", xy=(t1, a0), xytext=(t0, a0),
                arrowprops={"arrowstyle": "->", "color": "k", "lw": 1.6})
    ax.plot([t1, t1], [a0, a1], "k:", lw=1.4)
    ax.plot([t0], [a0], "ko", ms=5)
    ax.plot([t1], [a1], "k^", ms=6, label="jump and final state")
    ax.text(t0, a0, f"  {t0:g} K", va="bottom", ha="left", fontsize=8)
