"""Plots of a fit: the data with the fitted curve and its 95% band, the residuals, and the
phase map of the fitted gel (module ``phase_map``)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np


def _pyplot():
    from .style import pyplot

    return pyplot()


def _save(fig: Any, out: Path, fmt: str | None) -> Path:
    from .style import save

    return save(fig, out, fmt or (out.suffix.lstrip(".") or None))


def size_label(kind: str, unit: str | None) -> str:
    """The size axis: 'radius (um)', or '(data units)' when the data's unit is not known
    (the swelling CSV takes any unit); a volume ratio is dimensionless."""
    if kind == "volume_ratio":
        return "volume ratio V / V_ref"
    return f"{kind.replace('_', ' ')} ({unit or 'data units'})"


def _band_rows(band: dict[str, list[float]], lo: float, hi: float) -> dict[str, np.ndarray]:
    """The band where it is finite, with its curve inside the plotted temperatures and its
    edges clipped to them.  Near the dry state (the lowest 5% of the sizes) T(lambda) runs
    off to infinity: rows whose edges leave the axis there are dropped (filling between
    them drew a stray horizontal sliver across the whole axis)."""
    b = {k: np.asarray(v, dtype=float) for k, v in band.items()}
    size = b["size"]
    near_dry = size < size.min() + 0.05 * (size.max() - size.min())
    off_axis = (b["lower"] < lo) | (b["upper"] > hi)
    keep = (np.isfinite(b["lower"]) & np.isfinite(b["upper"]) & np.isfinite(b["temperature"])
            & (b["temperature"] >= lo) & (b["temperature"] <= hi) & ~(near_dry & off_axis))
    out = {k: v[keep] for k, v in b.items()}
    out["lower"] = np.clip(out["lower"], lo, hi)
    out["upper"] = np.clip(out["upper"], lo, hi)
    return out


def draw_swelling_fit(report: dict[str, Any], data: dict[str, Any], out: str | Path,
                      phase_map: bool = True, fmt: str | None = None,
                      size_unit: str | None = None) -> list[Path]:
    """Size against temperature with the fitted equilibrium curve (eq. EqlEqn) and its 95%
    band (left), the residuals in K and in size (right); with ``phase_map`` also
    ``<out>_phase_map<suffix>``.  ``size_unit`` labels the size axis (the data's unit)."""
    from solver.fit import FitResult, curve_band

    plt = _pyplot()
    out = Path(out)
    keys = FitResult.__dataclass_fields__
    res = FitResult(**{k: report[k] for k in keys if k in report and k != "extra"},
                    extra={k: v for k, v in report.items() if k not in keys})
    band = curve_band(res)
    kind = report["size_kind"]
    t, y = np.asarray(data["temperature_K"]), np.asarray(data[kind])
    fig, (ax, axr) = plt.subplots(1, 2, figsize=(11, 4.2))
    lo, hi = t.min() - 2.0, t.max() + 2.0
    b = _band_rows(band, lo, hi)
    ax.fill_betweenx(b["size"], b["lower"], b["upper"], color="C0", alpha=0.25, lw=0,
                     label="95% band (parameters)")
    curve_t, curve_s = np.asarray(band["temperature"]), np.asarray(band["size"])
    inside = np.isfinite(curve_t) & (curve_t >= lo) & (curve_t <= hi)
    ax.plot(curve_t[inside], curve_s[inside], "C0-", label="fitted equilibrium (Flory-Rehner)")
    ax.plot(t, y, "k.", label="data")
    for k, tr in enumerate(report.get("transitions", [])):
        ax.axvline(tr["temperature"], color="C3", lw=0.8, ls="--",
                   label="fitted transitions" if k == 0 else None)
    ax.set_xlim(lo, hi)
    ax.set_xlabel("temperature (K)")
    ax.set_ylabel(size_label(kind, size_unit))
    ax.legend(fontsize=8)
    trs = ", ".join(f"{x['kind']} {x['temperature']:.2f} K" for x in report.get("transitions", []))
    rms = report.get("rms_orthogonal_K", report["rms_residual"])
    ax.set_title(f"swelling fit ({report.get('objective', 'orthogonal')}): rms {rms:.3g} K; "
                 f"{trs}", fontsize=9)
    axr.plot(t, report["residuals_K"], "C0o", ms=4, label="temperature part (K)")
    axr.axhline(0.0, color="k", lw=0.6)
    axr.set_xlabel("temperature (K)")
    axr.set_ylabel("residual (K)")
    ax2 = axr.twinx()
    ax2.plot(t, 100.0 * np.asarray(report["residuals_size"]), "C1s", ms=3,
             label="size part (%)")
    ax2.set_ylabel("size residual (%)")
    axr.legend(loc="upper left", fontsize=8)
    ax2.legend(loc="upper right", fontsize=8)
    axr.set_title("residuals: each point's distance to the curve", fontsize=9)
    fig.tight_layout()
    paths = [_save(fig, out, fmt)]
    out = paths[0]
    if phase_map and report.get("gel"):
        from solver.gel import Gel

        from .phase_map import draw_phase_map

        pm = out.with_name(f"{out.stem}_phase_map{out.suffix}")
        paths.append(draw_phase_map(Gel.from_dict(report["gel"]), pm))
    return paths


def draw_kinetics_fit(report: dict[str, Any], data: dict[str, Any], out: str | Path,
                      fmt: str | None = None, size_unit: str | None = None) -> Path:
    """Size against time with the fitted curve (left) and relative residuals (right)."""
    plt = _pyplot()
    out = Path(out)
    kind = report["size_kind"]
    t, y = np.asarray(data["time_s"]), np.asarray(data[kind])
    order = np.argsort(t)
    fig, (ax, axr) = plt.subplots(1, 2, figsize=(11, 4.2))
    ax.plot(t, y, "k.", label="data")
    ax.plot(t[order], np.asarray(report["fitted_size"])[order], "C0-",
            label=f"{report['model']} model")
    iv = report["intervals"]["tau"]
    ax.set_title(f"tau = {report['parameters']['tau']:.4g} s"
                 + (f" [{iv[0]:.4g}, {iv[1]:.4g}]" if iv else ""), fontsize=9)
    ax.set_xlabel("time (s)")
    ax.set_ylabel(size_label(kind, size_unit))
    ax.legend(fontsize=8)
    axr.plot(t, 100.0 * np.asarray(report["residuals_relative"]), "C0o", ms=4)
    axr.axhline(0.0, color="k", lw=0.6)
    axr.set_xlabel("time (s)")
    axr.set_ylabel("residual (%)")
    fig.tight_layout()
    return _save(fig, out, fmt)
