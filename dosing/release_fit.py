"""Fit a drug's free diffusivity D0 to a measured cumulative release curve, with f2.

Built: isothermal release (``t_end == t_start``), the case a pharmaceutics lab measures first.
The bead sits at its equilibrium stretch a0 at T (eq. EqlEqn), porosity phi0 = 1 - a0^-3; the
drug diffuses through the pore fluid with D_eff = D0 H(phi0) (the hindrance law of
``solver.solute.hindrance``: free-volume with the sieve r_s / xi from Stokes-Einstein, Ogston,
or none) out of a sphere of radius a0 R_dry into a perfect sink: Crank's series
(``solver.solute.crank.crank_sphere``, Crank eq. 6.20).  Not built: release under a heating
jump or protocol (the bead shrinks while the drug diffuses), which needs the full solver
with the solute per trial D0; such a request is refused (ParameterError naming ``t_end``).

Residuals are absolute differences in released fraction, the noise estimated from them;
D0 is fitted in log form (95% interval exp(q +- t sd)), as in ``solver.fit.result``.

f2 (FDA, Guidance for Industry: Dissolution Testing of Immediate Release Solid Oral Dosage
Forms, 1997; Moore & Flanner 1996): f2 = 50 log10(100 / sqrt(1 + mean((R_t - T_t)^2))) with
R, T in percent released at the same times.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np
from scipy.optimize import least_squares

from solver.equilibrium import equilibrium
from solver.errors import ParameterError, require_finite_positive
from solver.fit.result import covariance_from_jacobian, t_quantile
from solver.gel import check_temperature
from solver.solute.crank import crank_sphere

from .drug import DrugModel
from .fit_csv import read_table
from .request import resolve_gel
from .units import PhysicalConstants


def f2(reference: Any, test: Any, *, fda_85_rule: bool = False) -> float:
    """The FDA similarity factor of two profiles in percent released at the same times.

    ``fda_85_rule``: keep only the first point at which the reference exceeds 85% (the
    guidance's "only one measurement after 85% dissolution"); t = 0 points are dropped."""
    r = np.asarray(reference, dtype=float)
    t = np.asarray(test, dtype=float)
    if r.shape != t.shape or r.ndim != 1 or r.size == 0:
        raise ParameterError("f2", f"{r.shape} and {t.shape}", "two profiles of equal length")
    keep = ~((r == 0.0) & (t == 0.0))
    if fda_85_rule:
        over = np.nonzero(r > 85.0)[0]
        if over.size:
            keep &= np.arange(r.size) <= over[0]
    d = r[keep] - t[keep]
    if d.size == 0:
        raise ParameterError("f2", "no points", "at least one time with release > 0")
    return float(50.0 * math.log10(100.0 / math.sqrt(1.0 + float(np.mean(d * d)))))


def read_release_csv(source: str | Path, loaded_ug: float | None = None,
                     info: dict[str, Any] | None = None) -> tuple[np.ndarray, np.ndarray]:
    """(time in s, released fraction) from a lab's CSV (``dosing.fit_csv``: time_s/min/h;
    ``released`` as a fraction, ``released (%)``, or a mass ``released_ug`` with
    ``loaded_ug``)."""
    tab = read_table(source, "time", ("released",))
    if info is not None:
        info.update(tab.to_dict())
    t, y = tab.columns["time"], tab.columns["released"]
    if "ug" in tab.units["released"]:
        if loaded_ug is None:
            raise ParameterError("loaded_ug", None, "a finite number > 0 (ug per bead or per "
                                 "sample) to turn a released mass into a fraction")
        y = y / require_finite_positive("loaded_ug", loaded_ug)
    if np.any(~np.isfinite(t)) or np.any(~np.isfinite(y)):
        raise ParameterError("released", "NaN", "finite times and releases")
    if np.any(t < 0):
        raise ParameterError("time", float(t.min()), "times >= 0 (0 = the start)")
    if np.any(y < -0.05) or np.any(y > 1.05):
        raise ParameterError("released", f"{y.min():.3g}-{y.max():.3g}",
                             "fractions of the load in 0-1 (or percent with 'released (%)')")
    return t, y


def fit_release(time_s: Any, released: Any, gel: Any, t_start: float, t_end: float | None,
                dry_radius_um: float, *, hindrance: str = "none",
                mesh_size_nm: float | None = None, fiber_radius_nm: float | None = None,
                constants: PhysicalConstants | None = None,
                d0_start_cm2_s: float = 1e-6) -> dict[str, Any]:
    """Fit D0 (cm^2/s) to a cumulative isothermal release curve (module doc); the report has
    ``parameters``/``intervals``/``stderr`` with ``drug_diffusivity_cm2_s``, the effective
    D, ``f2`` of the fit against the data, the fitted curve and a 95% band."""
    t = np.asarray(time_s, dtype=float)
    y = np.asarray(released, dtype=float)
    g = resolve_gel(gel)
    t0 = check_temperature(t_start, "t_start")
    if t_end is not None and abs(check_temperature(t_end, "t_end") - t0) > 1e-9:
        raise ParameterError("t_end", t_end, f"equal to t_start = {t0:g} K (isothermal "
                             "release)", "fits under a heating jump or protocol are not "
                             "built: the bead shrinks while the drug diffuses")
    r_um = require_finite_positive("dry_radius_um", dry_radius_um)
    c = constants or PhysicalConstants()
    a0 = equilibrium(g, t0, "swollen").stretch
    phi0 = 1.0 - a0**-3
    radius_um = a0 * r_um
    n = t.size
    if n < 3:
        raise ParameterError("data", f"{n} points", "at least 3 points")

    def d_eff(d0: float) -> float:
        drug = DrugModel(diffusivity_cm2_s=d0, hindrance=hindrance, mesh_size_nm=mesh_size_nm,
                         fiber_radius_nm=fiber_radius_nm)
        return d0 * float(drug.hindrance_law(a0, t0, c).factor(phi0))

    def model(q: float, tt: np.ndarray = t) -> np.ndarray:
        return crank_sphere(tt, d_eff(math.exp(q)) * 1e8, radius_um)  # um^2/s

    def fun(x: np.ndarray) -> np.ndarray:
        return model(float(x[0])) - y

    # start: the half-release time, Crank's t_1/2 = 0.0305 a^2 / D
    best = None
    for d0 in (d0_start_cm2_s, 1e-7, 1e-5, 1e-8):
        res = least_squares(fun, [math.log(d0)], bounds=([math.log(1e-12)], [math.log(1e-3)]),
                            x_scale="jac", xtol=1e-12, ftol=1e-12, max_nfev=200)
        if best is None or res.cost < best.cost:
            best = res
    assert best is not None
    cov, chi2 = covariance_from_jacobian(best.jac, best.fun, 1)
    q = float(best.x[0])
    sd = math.sqrt(max(cov[0, 0], 0.0))
    tq = t_quantile(n - 1)
    d0 = math.exp(q)
    iv = [math.exp(q - tq * sd), math.exp(q + tq * sd)]
    fitted = model(q)
    tt = np.linspace(0.0, float(t.max()), 200)
    curve = model(q, tt)
    lo, hi = model(q - tq * sd, tt), model(q + tq * sd, tt)
    warns = []
    if not best.success:
        warns.append(f"the fit did not converge ({best.message})")
    if y.max() < 0.3:
        warns.append("less than 30% released: D0 rests on the early t^1/2 part only")
    return {
        "names": ["drug_diffusivity_cm2_s"],
        "parameters": {"drug_diffusivity_cm2_s": d0},
        "intervals": {"drug_diffusivity_cm2_s": iv},
        "stderr": {"drug_diffusivity_cm2_s": d0 * sd},
        "effective_diffusivity_cm2_s": d_eff(d0), "hindrance_factor": d_eff(d0) / d0,
        "hindrance": hindrance, "swollen_radius_um": radius_um, "porosity": phi0,
        "model": "isothermal release from the swollen bead into a perfect sink: Crank's "
                 "sphere series (eq. 6.20) with D_eff = D0 H(phi0)",
        "f2": f2(100.0 * y, 100.0 * fitted),
        "f2_meaning": "FDA similarity factor of the fitted prediction against the measured "
                      "curve at the measured times (>= 50: similar)",
        "rms_residual": float(np.sqrt(np.mean((fitted - y) ** 2))),
        "chi2_reduced": chi2, "n_points": n, "success": bool(best.success),
        "fitted": fitted.tolist(), "time_s": t.tolist(), "released": y.tolist(),
        "band": {"time_s": tt.tolist(), "released": curve.tolist(), "lower": lo.tolist(),
                 "upper": hi.tolist()},
        "warnings": warns, "confidence": 0.95,
        "not_pinned": ["the partition coefficient and a finite release volume (not fitted: "
                       "perfect sink, K = 1)"]}
