"""Heat maps of a design map (``dosing.studies.sweep``): actuation time with iso-time contours and
its validated error over T_end x bead size, one column per dose; points without a
front-model answer are hatched grey."""

from __future__ import annotations

from pathlib import Path
from typing import Any, BinaryIO

import numpy as np

MAX_PANELS = 8  # dose columns drawn (each ~0.3 s of matplotlib): a figure in seconds


def _grids(table: dict[str, Any], gel_index: int) -> tuple[np.ndarray, ...]:
    """(seconds, validated error, prior error) arrays of shape (doses, radii, t_ends) for
    one gel; NaN where there is none (no answer; not validated; no prior)."""
    g = table["grid"]
    n_g, n_t, n_r, n_d = g["shape"]
    secs = np.full((n_g, n_t, n_r, n_d), np.nan)
    err = np.full_like(secs, np.nan)
    prior = np.full_like(secs, np.nan)
    for row in table["rows"]:
        idx = np.unravel_index(row["index"], (n_g, n_t, n_r, n_d))
        key = "seconds" if row["seconds"] is not None else "time"
        if row[key] is not None:
            secs[idx] = row[key]
        if row.get("front_time_error") is not None:
            err[idx] = abs(row["front_time_error"])
        if row.get("error_estimate") is not None:
            prior[idx] = abs(row["error_estimate"])
    return tuple(a[gel_index].transpose(2, 1, 0) for a in (secs, err, prior))


def _iso_time(ax: Any, t_ends: list[float], radii: list[float], secs: np.ndarray) -> None:
    """Iso-time contours (labelled, log-spaced levels) over T_end x bead size."""
    ok = np.isfinite(secs) & (secs > 0)
    if len(t_ends) < 2 or len(radii) < 2 or ok.sum() < 4:
        return
    lo, hi = np.log10(secs[ok].min()), np.log10(secs[ok].max())
    if hi - lo < 1e-6:
        return
    levels = _nice_levels(lo, hi)
    cs = ax.contour(t_ends, radii, np.ma.masked_invalid(np.where(ok, secs, np.nan)),
                    levels=levels, colors="w", linewidths=0.8)
    ax.clabel(cs, fmt=lambda v: f"{v:g} s", fontsize=7)


def _nice_levels(lo: float, hi: float) -> list[float]:
    """1-2-5 levels per decade strictly inside [10^lo, 10^hi] (at most about 8)."""
    out = [m * 10.0**e for e in range(int(np.floor(lo)), int(np.ceil(hi)) + 1)
           for m in (1.0, 2.0, 5.0)]
    out = [v for v in out if 10.0**lo < v < 10.0**hi]
    while len(out) > 8:
        out = out[::2]
    return out


def _edges(values: list[float], log: bool) -> np.ndarray:
    v = np.asarray(values, dtype=float)
    if v.size == 1:
        return np.array([v[0] * 0.9, v[0] * 1.1]) if log else np.array([v[0] - 0.5, v[0] + 0.5])
    x = np.log(v) if log else v
    mid = (x[1:] + x[:-1]) / 2
    e = np.concatenate([[2 * x[0] - mid[0]], mid, [2 * x[-1] - mid[-1]]])
    return np.exp(e) if log else e


def panel_doses(n: int, most: int = MAX_PANELS) -> list[int]:
    """The dose columns drawn: all of them up to ``most``, else ``most`` evenly spaced ones
    (the first and the last among them), so a figure takes seconds whatever the grid."""
    if n <= most:
        return list(range(n))
    return sorted({int(round(k)) for k in np.linspace(0, n - 1, most)})


def draw_sweep(table: dict[str, Any], out: str | Path | BinaryIO, gel_index: int = 0,
               fmt: str = "svg") -> str | Path | BinaryIO:
    """Draw ``table`` (``SweepResult.to_dict()``) for one gel to ``out`` (PNG, PDF or SVG):
    top row the actuation time (s, or tau without bead sizes) with iso-time contours,
    bottom row the validated relative error of the front model where a validation is done
    (log colour); at most ``MAX_PANELS`` doses, evenly spaced, are drawn; the front model's
    prior, one number per dose, is written on the panel and labelled as a prior, not painted
    as if it were measured.  A file object gets ``fmt``."""
    from matplotlib.colors import LogNorm

    from .style import pyplot

    plt = pyplot()
    g = table["grid"]
    secs, err, prior = _grids(table, gel_index)
    picks = panel_doses(len(g["doses"]))
    secs, err, prior = secs[picks], err[picks], prior[picks]
    doses = [g["doses"][k] for k in picks]
    x = _edges(g["t_ends"], log=False)
    y = _edges(g["dry_radii_um"], log=True)
    n = len(doses)
    fig, axes = plt.subplots(2, n, figsize=(2.4 * n + 1.6, 5.4), squeeze=False,
                             sharex=True, sharey=True, layout="constrained")
    unit = "s" if any(r["seconds"] is not None for r in table["rows"]) else "tau"
    validated = bool(np.isfinite(err).any())
    rows = [(secs, f"actuation time ({unit})", "viridis"),
            (err, "validated relative error |front - truth| / truth", "magma_r")]
    for r, (data, label, cmap) in enumerate(rows):
        finite = data[np.isfinite(data) & (data > 0)]
        norm = LogNorm(finite.min(), finite.max()) if finite.size else None
        mesh = None
        for j in range(n):
            ax = axes[r, j]
            ax.set_facecolor("#dddddd")
            ax.fill_between(x[[0, -1]], y[0], y[-1], hatch="///", facecolor="none",
                            edgecolor="#bbbbbb", linewidth=0)
            if finite.size:
                mesh = ax.pcolormesh(x, y, np.ma.masked_invalid(data[j]), cmap=cmap,
                                     norm=norm)
            if r == 0:
                _iso_time(ax, g["t_ends"], g["dry_radii_um"], data[j])
                ax.set_title(f"dose {doses[j]:.0%}")
            else:
                p = prior[j][np.isfinite(prior[j])]
                if p.size:  # the front model's prior: one number per dose, stated as such
                    text = (f"prior (not validated):\n{p.min():.0%}" if p.min() == p.max()
                            else f"prior (not validated):\n{p.min():.0%}-{p.max():.0%}")
                    ax.text(0.5, 0.5 if not validated else 0.08, text, ha="center",
                            va="center", fontsize=8, transform=ax.transAxes,
                            bbox={"facecolor": "white", "alpha": 0.85, "lw": 0})
                ax.set_xlabel("T_end (K)")
            ax.set_yscale("log")
            if j == 0:
                ax.set_ylabel("dry radius (um)")
        if mesh is not None and norm is not None:
            fig.colorbar(mesh, ax=axes[r, :].tolist(), label=label, shrink=0.9)
    gel = g["gels"][gel_index].get("name", "custom")
    shown = ("" if len(picks) == len(g["doses"]) else
             f"\n{len(picks)} of {len(g['doses'])} doses drawn (evenly spaced; the table has "
             "them all)")
    fig.suptitle(f"{gel}, T_start = {g['t_start']:g} K: front-model design map with iso-time "
                 "contours (grey: no answer)" + ("" if validated else "\nno point validated "
                 "yet: the error shown is the front model's prior") + shown, fontsize=10)
    if isinstance(out, (str, Path)):
        from .style import save

        return save(fig, out, Path(out).suffix.lstrip(".") or fmt)
    fig.savefig(out, dpi=130, format=fmt)
    plt.close(fig)
    return out
