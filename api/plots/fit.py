"""Plots of a fit: the data with the fitted curve and its 95% band, the residuals, and the
phase map of the fitted gel (module ``phase_map``)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np


def _pyplot():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def draw_swelling_fit(report: dict[str, Any], data: dict[str, Any], out: str | Path,
                      phase_map: bool = True) -> list[Path]:
    """Size against temperature with the fitted curve and its band (left), the residuals in
    K and in size (right); with ``phase_map`` also ``<out>_phase_map<suffix>``."""
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
    ax.fill_betweenx(band["size"], band["lower"], band["upper"], color="C0", alpha=0.25,
                     label="95% band (parameters)")
    ax.plot(band["temperature"], band["size"], "C0-", label="fit, eq. EqlEqn")
    ax.plot(t, y, "k.", label="data")
    for tr in report.get("transitions", []):
        ax.axvline(tr["temperature"], color="C3", lw=0.8, ls="--")
    lo, hi = t.min() - 2.0, t.max() + 2.0
    ax.set_xlim(lo, hi)
    ax.set_xlabel("temperature (K)")
    ax.set_ylabel(kind.replace("_", " "))
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
    fig.savefig(out, dpi=120)
    plt.close(fig)
    paths = [out]
    if phase_map and report.get("gel"):
        from solver.gel import Gel

        from .phase_map import draw_phase_map

        pm = out.with_name(f"{out.stem}_phase_map{out.suffix}")
        paths.append(draw_phase_map(Gel.from_dict(report["gel"]), pm))
    return paths


def draw_kinetics_fit(report: dict[str, Any], data: dict[str, Any], out: str | Path) -> Path:
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
    ax.set_ylabel(kind.replace("_", " "))
    ax.legend(fontsize=8)
    axr.plot(t, 100.0 * np.asarray(report["residuals_relative"]), "C0o", ms=4)
    axr.axhline(0.0, color="k", lw=0.6)
    axr.set_xlabel("time (s)")
    axr.set_ylabel("residual (%)")
    fig.tight_layout()
    fig.savefig(out, dpi=120)
    plt.close(fig)
    return out
