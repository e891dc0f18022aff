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


def region_bounds(gel: Gel, stretches: np.ndarray, n: int = 600
                  ) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """The regions' boundaries as curves T(lambda), computed, not read off a grid.

    Both tests are affine in T at fixed lambda: the spinodal stiffness s0 + T s1 < 0
    (eq. Spinodal) holds for T beyond -s0 / s1, and the tangent gap g0(n) + T g1(n) of each
    normal stretch n (eq. Coexistence) is negative beyond -g0 / g1.  So at each lambda the
    region is {T > above} U {T < below} with ``above`` the smallest crossing of the
    decreasing lines and ``below`` the largest of the increasing ones (NaN: no such part).
    Returns {'spinodal': (above, below), 'coexistence': (above, below)}.
    """
    lam = np.asarray(stretches, dtype=float)
    s0 = spinodal_stiffness(gel, 0.0, lam)
    s1 = spinodal_stiffness(gel, 1.0, lam) - s0
    with np.errstate(divide="ignore", invalid="ignore"):
        t_sp = -s0 / s1
    spin = (np.where(s1 < 0, t_sp, np.nan), np.where(s1 > 0, t_sp, np.nan))
    above, below = np.full(lam.size, np.nan), np.full(lam.size, np.nan)
    for i, x in enumerate(lam):
        grid = _normal_grid(x, n)
        # n -> lambda is the spinodal's limit (below): there g0 and g1 are round-off
        grid = grid[np.abs(grid - x) > 1e-3 * x]
        g0 = tangent_gap(gel, 0.0, grid, x)
        g1 = tangent_gap(gel, 1.0, grid, x) - g0
        with np.errstate(divide="ignore", invalid="ignore"):
            tn = -g0 / g1
        dec, inc = (g1 < 0) & np.isfinite(tn), (g1 > 0) & np.isfinite(tn)
        if dec.any():
            above[i] = tn[dec].min()
        if inc.any():
            below[i] = tn[inc].max()
    # the spinodal lies inside the coexistence region (the gap's curvature at n = lambda)
    above = np.fmin(above, spin[0])
    below = np.fmax(below, spin[1])
    return {"spinodal": spin, "coexistence": (above, below)}


def _runs_only(x: np.ndarray, shortest: int = 3) -> np.ndarray:
    """``x`` with runs of fewer than ``shortest`` finite samples set to NaN: where s1 (or
    g1) passes through zero with s0 the ratio is 0/0 at a sample or two, not a boundary."""
    out = x.copy()
    ok = np.isfinite(x)
    i = 0
    while i < x.size:
        if ok[i]:
            j = i
            while j < x.size and ok[j]:
                j += 1
            if j - i < shortest:
                out[i:j] = np.nan
            i = j
        else:
            i += 1
    return out


def _fill_region(ax: Any, lams: np.ndarray, bounds: tuple[np.ndarray, np.ndarray],
                 t_lo: float, t_hi: float, color: str, ls: str) -> None:
    """Fill {T > above} U {T < below} between the axis limits; draw its boundary curves."""
    above, below = (_runs_only(b) for b in bounds)
    ok = np.isfinite(above) & (above < t_hi)
    ax.fill_betweenx(lams, np.clip(np.where(ok, above, t_hi), t_lo, t_hi), t_hi, where=ok,
                     color=color, lw=0, interpolate=True)
    ax.plot(above, lams, "k", ls=ls, lw=0.8)  # the axes clip it
    ok = np.isfinite(below) & (below > t_lo)
    ax.fill_betweenx(lams, t_lo, np.clip(np.where(ok, below, t_lo), t_lo, t_hi), where=ok,
                     color=color, lw=0, interpolate=True)
    ax.plot(below, lams, "k", ls=ls, lw=0.8)


def draw_phase_map(gel: Gel, out: str | Path | BinaryIO, t_min: float | None = None,
                   t_max: float | None = None, lambda_max: float | None = None,
                   jump: tuple[float, float, float, float] | None = None,
                   fmt: str = "svg", size: tuple[float, float] = (6, 4.5)) -> Path | BinaryIO:
    """Draw fig. 3 for ``gel`` to ``out`` (PNG or PDF; a file object gets ``fmt``) and
    return it.  ``jump = (T_start, a0, T_end, a_final)`` draws the heating jump at fixed
    stretch and the shrinking to the final equilibrium that follows it."""
    from .style import pyplot

    plt = pyplot()
    fl = folds(gel)
    centre = np.mean([f.temperature for f in fl]) if fl else 305.0
    t_min = t_min if t_min is not None else max(T_MIN, centre - 10.0)
    t_max = t_max if t_max is not None else min(T_MAX, centre + 10.0)
    curve = equilibrium_curve(gel, t_min, t_max)
    lam_hi = lambda_max if lambda_max is not None else 1.15 * float(curve.stretch.max())
    lams = np.linspace(1.0 + 1e-3, lam_hi, 400)
    bounds = region_bounds(gel, lams)
    if jump is not None:
        t_min = min(t_min, jump[0] - 1.0, jump[2] - 1.0)
        t_max = max(t_max, jump[0] + 1.0, jump[2] + 1.0)
    fig, ax = plt.subplots(figsize=size)
    _fill_region(ax, lams, bounds["coexistence"], t_min, t_max, "#c6dbef", ":")
    _fill_region(ax, lams, bounds["spinodal"], t_min, t_max, "#6baed6", "--")
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
        from .style import save

        return save(fig, out, Path(out).suffix.lstrip(".") or fmt)
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
