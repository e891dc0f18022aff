"""Heat maps of a design map (``dosing.sweep``): actuation time and its error over T_end x
bead size, one column per dose; points without a front-model answer are hatched grey."""

from __future__ import annotations

from pathlib import Path
from typing import Any, BinaryIO

import numpy as np


def _grids(table: dict[str, Any], gel_index: int) -> tuple[np.ndarray, ...]:
    """(seconds, error) arrays of shape (doses, radii, t_ends) for one gel; NaN where no
    answer (failed, or needs the full solver and not validated)."""
    g = table["grid"]
    n_g, n_t, n_r, n_d = g["shape"]
    secs = np.full((n_g, n_t, n_r, n_d), np.nan)
    err = np.full_like(secs, np.nan)
    for row in table["rows"]:
        idx = np.unravel_index(row["index"], (n_g, n_t, n_r, n_d))
        key = "seconds" if row["seconds"] is not None else "time"
        if row[key] is not None:
            secs[idx] = row[key]
        e = row["front_time_error"] if row.get("front_time_error") is not None \
            else row["error_estimate"]
        if e is not None:
            err[idx] = abs(e)
    return (secs[gel_index].transpose(2, 1, 0), err[gel_index].transpose(2, 1, 0))


def _edges(values: list[float], log: bool) -> np.ndarray:
    v = np.asarray(values, dtype=float)
    if v.size == 1:
        return np.array([v[0] * 0.9, v[0] * 1.1]) if log else np.array([v[0] - 0.5, v[0] + 0.5])
    x = np.log(v) if log else v
    mid = (x[1:] + x[:-1]) / 2
    e = np.concatenate([[2 * x[0] - mid[0]], mid, [2 * x[-1] - mid[-1]]])
    return np.exp(e) if log else e


def draw_sweep(table: dict[str, Any], out: str | Path | BinaryIO, gel_index: int = 0,
               fmt: str = "svg") -> str | Path | BinaryIO:
    """Draw ``table`` (``SweepResult.to_dict()``) for one gel to ``out`` (PNG, PDF or SVG):
    top row the actuation time (s, or tau without bead sizes), bottom row its relative error
    (the validation's where one is done, else the front model's estimate), log colour.
    A file object gets ``fmt``."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.colors import LogNorm

    g = table["grid"]
    secs, err = _grids(table, gel_index)
    doses = g["doses"]
    x = _edges(g["t_ends"], log=False)
    y = _edges(g["dry_radii_um"], log=True)
    n = len(doses)
    fig, axes = plt.subplots(2, n, figsize=(2.4 * n + 1.6, 5.4), squeeze=False,
                             sharex=True, sharey=True, layout="constrained")
    rows = [(secs, "actuation time (s)", "viridis"), (err, "relative error", "magma_r")]
    for r, (data, label, cmap) in enumerate(rows):
        finite = data[np.isfinite(data) & (data > 0)]
        norm = LogNorm(finite.min(), finite.max()) if finite.size else None
        mesh = None
        for j in range(n):
            ax = axes[r, j]
            ax.set_facecolor("#dddddd")
            ax.fill_between(x[[0, -1]], y[0], y[-1], hatch="///", facecolor="none",
                            edgecolor="#bbbbbb", linewidth=0)
            mesh = ax.pcolormesh(x, y, np.ma.masked_invalid(data[j]), cmap=cmap, norm=norm)
            ax.set_yscale("log")
            if r == 0:
                ax.set_title(f"dose {doses[j]:.0%}", fontsize=10)
            if r == 1:
                ax.set_xlabel("T_end (K)")
            if j == 0:
                ax.set_ylabel("dry radius (um)")
        if mesh is not None and norm is not None:
            fig.colorbar(mesh, ax=axes[r, :].tolist(), label=label, shrink=0.9)
    gel = g["gels"][gel_index].get("name", "custom")
    fig.suptitle(f"{gel}, T_start = {g['t_start']:g} K: front-model design map "
                 "(grey: no front-model answer)", fontsize=11)
    if isinstance(out, (str, Path)):
        out = Path(out)
        fig.savefig(out, dpi=130)
    else:
        fig.savefig(out, dpi=130, format=fmt)
    plt.close(fig)
    return out
