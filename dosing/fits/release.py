"""Fit a drug's free diffusivity D0 to a measured cumulative release curve, with f2.

Built: isothermal release (``t_end == t_start``), the case a pharmaceutics lab measures first.
The bead sits at its equilibrium stretch a0 at T (eq. EqlEqn), porosity phi0 = 1 - a0^-3; the
drug diffuses through the pore fluid with D_eff = D0 H(phi0) (the hindrance law of
``solver.solute.hindrance``: free-volume with the sieve r_s / xi from Stokes-Einstein, Ogston,
or none) out of a sphere of radius a0 R_dry into a perfect sink: Crank's series
(``solver.solute.crank.crank_sphere``, Crank eq. 6.20).  Under a heating ``protocol`` (the
grammar of ``dosing.heating.grammar``: "Heat to 308 K at 5 K/min"; an instant jump is "Bath at
308 K") the bead shrinks while the drug diffuses: the model is the solute transport on the
full solver's mechanics of the protocol (``dosing.fits.release_steps``: one mechanics
run, memoised, serves every trial D0; each trial is one solute run).  D0 is the drug's
diffusivity in water at the release temperature (isothermal) or the protocol's hottest
(``drug_diffusivity_temperature_K``).

Residuals are absolute differences in released fraction, the noise estimated from them;
D0 is fitted in log form (95% interval exp(q +- t sd)), as in ``solver.fit.result``.

The goodness of fit is the chi-square and the residuals.  Beside them the report states the
similarity of the prediction and the data as two dissolution profiles: f1 and f2 (FDA,
Guidance for Industry: Dissolution Testing of Immediate Release Solid Oral Dosage Forms,
1997; Moore & Flanner 1996), f2 = 50 log10(100 / sqrt(1 + mean((R_t - T_t)^2))) with R, T in
percent released at the same times, on the guidance's points (``dosing.analysis``).
"""

from __future__ import annotations

import math
import time
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np
from scipy.optimize import least_squares

from solver.equilibrium import equilibrium
from solver.errors import ParameterError, require_finite_positive
from solver.fit.result import covariance_from_jacobian, t_quantile
from solver.gel import check_temperature
from solver.solute.crank import crank_sphere

from ..analysis.similarity import fda_f2
from ..payload.drug import DrugModel
from ..request import resolve_gel
from ..runs.scenario import SolverSettings
from ..units import REFERENCE_TEMPERATURE_K, PhysicalConstants
from .csv_tables import read_table
from .gel_store import calibrated_constants

D_BOUNDS = (1e-12, 1e-3)  # cm^2/s: the fit's bounds on D0


def f2(reference: Any, test: Any, *, fda_85_rule: bool = False) -> float:
    """The FDA similarity factor of two profiles in percent released at the same times.

    ``fda_85_rule``: the guidance's points (``dosing.analysis.similarity.points_used``: no
    point after the first at which both products exceed 85 %); t = 0 points (both 0) are
    dropped.  Two profiles with units and the full rules: ``dosing.analysis.similarity``."""
    r = np.asarray(reference, dtype=float)
    t = np.asarray(test, dtype=float)
    if r.shape != t.shape or r.ndim != 1 or r.size == 0:
        raise ParameterError("f2", f"{r.shape} and {t.shape}", "two profiles of equal length")
    if fda_85_rule:
        return fda_f2(r, t)
    keep = ~((r == 0.0) & (t == 0.0))
    d = r[keep] - t[keep]
    if d.size == 0:
        raise ParameterError("f2", "no points", "at least one time with release > 0")
    return float(50.0 * math.log10(100.0 / math.sqrt(1.0 + float(np.mean(d * d)))))


def similarity_of_fit(time_s: Any, measured: Any, predicted: Any) -> dict[str, Any]:
    """f1/f2 of a prediction against a measured curve (fractions at the same times) under
    the FDA rules (``dosing.analysis.similarity``): a similarity of two profiles, not a
    goodness of fit (that is the fit's chi-square and residuals)."""
    from ..analysis.profiles import Profile
    from ..analysis.similarity import compare

    ts = np.asarray(time_s, float)
    meas = Profile(ts, 100.0 * np.asarray(measured, float)[:, None], "s", 1.0, "measured")
    pred = Profile(ts, 100.0 * np.asarray(predicted, float)[:, None], "s", 1.0, "predicted")
    c = compare(meas, pred, bootstrap=False, prediction=True)
    return {"f2": c.f2, "f1": c.f1, "times_used_s": c.times_used, "points_used": c.points_used,
            "conditions": c.conditions, "conditions_met": c.conditions_met,
            "outcome": c.outcome, "f1_outcome": c.f1_outcome,
            "meaning": "FDA similarity (1997 guidance rules) of the prediction and the measured "
                       "profile as two dissolution profiles: not a goodness of fit (see "
                       "chi2_reduced, rms_residual and residuals)"}


RELEASE_UNITS = ("fraction", "percent", "ug")


def read_release_csv(source: str | Path, loaded_ug: float | None = None,
                     info: dict[str, Any] | None = None) -> tuple[np.ndarray, np.ndarray]:
    """(time in s, released fraction) from a lab's CSV (``dosing.fits.csv_tables``: time_s/min/h;
    ``released`` as a fraction, ``released (%)``, or a mass ``released_ug`` with
    ``loaded_ug``)."""
    tab = read_table(source, "time", ("released",))
    if info is not None:
        info.update(tab.to_dict())
    unit = "ug" if "ug" in tab.units["released"] else "fraction"  # percent: read as a fraction
    return release_data(tab.columns["time"], tab.columns["released"], unit, loaded_ug)


def release_data(time_s: Any, released: Any, unit: str = "fraction",
                 loaded_ug: float | None = None) -> tuple[np.ndarray, np.ndarray]:
    """(time in s, released fraction), checked: ``unit`` 'fraction', 'percent' or 'ug' (a
    mass, with ``loaded_ug``); every way in (CSV, HTTP, Python) reads its data here."""
    t = np.asarray(time_s, dtype=float)
    y = np.asarray(released, dtype=float)
    if unit not in RELEASE_UNITS:
        raise ParameterError("released_unit", unit, " or ".join(map(repr, RELEASE_UNITS)))
    if t.shape != y.shape or t.ndim != 1:
        raise ParameterError("released", f"{y.size} values for {t.size} times",
                             "one release per time")
    if unit == "percent":
        y = y / 100.0
    elif unit == "ug":
        if loaded_ug is None:
            raise ParameterError("loaded_ug", None, "a finite number > 0 (ug per bead or per "
                                 "sample) to turn a released mass into a fraction")
        with np.errstate(over="ignore"):  # an overflow is refused just below as non-finite
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
                dry_radius_um: float, *, protocol: Any = None, hindrance: str = "none",
                mesh_size_nm: float | None = None, fiber_radius_nm: float | None = None,
                constants: PhysicalConstants | None = None,
                settings: SolverSettings | None = None) -> dict[str, Any]:
    """Fit D0 (cm^2/s) to a cumulative release curve, isothermal (``t_end`` None or
    ``t_start``) or under a heating ``protocol`` (step texts from ``t_start``; module doc);
    the report has ``parameters``/``intervals``/``stderr`` with ``drug_diffusivity_cm2_s``,
    the effective D, the fitted curve and a 95% band, the goodness of fit (``chi2_reduced``,
    ``rms_residual``, ``residuals``) and, apart from it, ``similarity``: f1/f2 of the
    prediction and the data under the FDA rules (``f2`` its value).
    ``settings``: the full solver's, under a protocol (default the truth's)."""
    t = np.asarray(time_s, dtype=float)
    y = np.asarray(released, dtype=float)
    g = resolve_gel(gel)
    t0 = check_temperature(t_start, "t_start")
    if protocol is not None and t_end is not None:
        raise ParameterError("t_end", t_end, "None when a protocol is given (give one of "
                             "--t-end or --protocol)")
    if t_end is not None and abs(check_temperature(t_end, "t_end") - t0) > 1e-9:
        raise ParameterError("t_end", t_end, f"equal to t_start = {t0:g} K (isothermal "
                             "release)", "a release under heating is fitted with a protocol "
                             "('Heat to 308 K at 5 K/min'; an instant jump: 'Bath at 308 K')")
    r_um = require_finite_positive("dry_radius_um", dry_radius_um)
    c = calibrated_constants(g, constants or PhysicalConstants()).for_gel(g.omega)
    n = t.size
    if n < 3:
        raise ParameterError("data", f"{n} points", "at least 3 points")
    drug = DrugModel(diffusivity_cm2_s=1e-6, hindrance=hindrance, mesh_size_nm=mesh_size_nm,
                     fiber_radius_nm=fiber_radius_nm)
    extra: dict[str, Any] = {}
    if protocol is None:
        a0 = equilibrium(g, t0, "swollen").stretch
        model_fn, t_ref = _isothermal(drug, a0, t0, r_um, c), t0
        extra["model"] = ("isothermal release from the swollen bead into a perfect sink: "
                          "Crank's sphere series (eq. 6.20) with D_eff = D0 H(phi0)")
    else:
        from ..runs.mechanics import protocol_mechanics
        from . import release_steps as fp

        prot = fp.parse_protocol(t0, protocol)
        mech = protocol_mechanics(g, prot, r_um, float(t.max()), c, settings)
        a0, t_ref = mech.start_radius, mech.t_ref
        spent = [0, 0.0]

        def model_fn(d0: float, tt: np.ndarray) -> np.ndarray:
            started = time.process_time()
            out = fp.released_under(mech, drug, d0, c, r_um, tt)
            spent[0] += 1
            spent[1] += time.process_time() - started
            return out

        extra.update(model=fp.model_text(mech), protocol=prot.to_dict(),
                     squeezed_released=fp.squeezed_under(mech, t).tolist(),
                     _cost=(mech, spent))
    phi0 = 1.0 - a0**-3
    rep = _fit_log_d0(t, y, model_fn, start_d0(t, y, a0 * r_um))
    d0 = rep["parameters"]["drug_diffusivity_cm2_s"]
    factor = _factor(drug, d0, a0, t_ref, c)
    cost_of = extra.pop("_cost", None)
    if cost_of is not None:
        from .release_steps import cost

        extra["cost"] = cost(cost_of[0], cost_of[1][0], cost_of[1][1])
    not_pinned = ["the partition coefficient and a finite release volume (not fitted: "
                  "perfect sink, K = 1)"]
    if protocol is not None:
        not_pinned.append("the gel's timescale tau (taken as the gel's, calibrated by a "
                          "kinetics fit or the paper's constants): the squeezing's pace "
                          "under the protocol")
    return {**rep, "effective_diffusivity_cm2_s": d0 * factor, "hindrance_factor": factor,
            "hindrance": hindrance, "swollen_radius_um": a0 * r_um, "porosity": phi0,
            "drug_diffusivity_temperature_K": t_ref, **at_reference(rep, t_ref), **extra,
            "f2_meaning": "FDA similarity factor (1997 guidance: zero excluded, one point "
                          "after 85 % of both) of the fitted prediction and the measured "
                          "curve as two dissolution profiles (50-100: similar); a similarity, "
                          "not a goodness of fit: that is chi2_reduced, rms_residual and "
                          "residuals",
            "confidence": 0.95, "not_pinned": not_pinned}


def at_reference(rep: dict[str, Any], t_fit: float) -> dict[str, Any]:
    """The fitted D0 carried from the fit's temperature to the 25 degC at which an input
    D0 is read (``DrugModel.reference_temperature_k``): Stokes-Einstein, D ~ T / eta(T)
    with water's eta (issue 36: the two stood side by side at different temperatures)."""
    t0 = REFERENCE_TEMPERATURE_K
    # the drug's own carrier of D0 between temperatures (DrugModel.d0_cm2_s), per unit D0
    f = DrugModel(diffusivity_cm2_s=1e-6, reference_temperature_k=t_fit).d0_cm2_s(t0) / 1e-6
    d0 = rep["parameters"]["drug_diffusivity_cm2_s"]
    iv = (rep.get("intervals") or {}).get("drug_diffusivity_cm2_s")
    return {"drug_diffusivity_reference_K": t0,
            "drug_diffusivity_at_reference_cm2_s": d0 * f,
            "drug_diffusivity_at_reference_interval_cm2_s":
                None if iv is None else [iv[0] * f, iv[1] * f],
            "drug_diffusivity_note": (
                f"D0 fitted at {t_fit:g} K (the release temperature); at {t0:g} K, where an "
                f"input D0 is read, it is {d0 * f:.3g} cm^2/s (Stokes-Einstein, x{f:.3g})")}


def _factor(drug: DrugModel, d0: float, a0: float, t_ref: float,
            c: PhysicalConstants) -> float:
    """H(phi0) of the swollen start for a drug of free diffusivity ``d0`` at ``t_ref`` (its
    Stokes-Einstein radius, hence the sieve, follows D0)."""
    trial = replace(drug, diffusivity_cm2_s=d0, reference_temperature_k=t_ref)
    return float(trial.hindrance_law(a0, t_ref, c).factor(1.0 - a0**-3))


def _isothermal(drug: DrugModel, a0: float, t0: float, r_um: float,
                c: PhysicalConstants) -> Any:
    """Crank's series for the swollen bead: released fraction at ``tt`` for D0."""
    def model_fn(d0: float, tt: np.ndarray) -> np.ndarray:
        return crank_sphere(tt, d0 * _factor(drug, d0, a0, t0, c) * 1e8, a0 * r_um)  # um^2/s

    return model_fn


def start_d0(t: np.ndarray, y: np.ndarray, radius_um: float) -> float:
    """A start for D0 (cm^2/s) from the curve: Crank's half-release time t_1/2 = 0.0305
    a^2 / D, or with less than half released the early law M = 6 sqrt(D t / (pi a^2))."""
    order = np.argsort(t)
    ts, ys = t[order], y[order]
    if ys.max() >= 0.5:
        t_half = float(ts[np.argmax(ys >= 0.5)])
        d = 0.0305 * radius_um**2 / max(t_half, 1e-9)
    else:
        d = math.pi * radius_um**2 * (max(float(ys[-1]), 1e-3) / 6.0) ** 2 / max(ts[-1], 1e-9)
    return float(np.clip(d * 1e-8, 10 * D_BOUNDS[0], 0.1 * D_BOUNDS[1]))  # um^2/s -> cm^2/s


def _fit_log_d0(t: np.ndarray, y: np.ndarray, model_fn: Any, guess: float
                ) -> dict[str, Any]:
    """Least squares of ``model_fn(D0, t) - y`` in q = log D0 from the curve's own start
    ``guess`` (then decades around it, if that fit is poor); the linearised 95% interval
    exp(q +- t sd), f2, the fitted curve and its band."""
    n = t.size

    def fun(x: np.ndarray) -> np.ndarray:
        return model_fn(math.exp(float(x[0])), t) - y

    best = None
    for d0 in (guess, 10 * guess, 0.1 * guess, 100 * guess, 0.01 * guess):
        d0 = float(np.clip(d0, 10 * D_BOUNDS[0], 0.1 * D_BOUNDS[1]))
        res = least_squares(fun, [math.log(d0)], bounds=([math.log(D_BOUNDS[0])],
                                                         [math.log(D_BOUNDS[1])]),
                            x_scale="jac", xtol=1e-8, ftol=1e-10, max_nfev=60)
        if best is None or res.cost < best.cost:
            best = res
        if best.success and best.cost < 0.5 * n * 0.05**2:  # a fit within 5%: no more starts
            break
    assert best is not None
    cov, chi2 = covariance_from_jacobian(best.jac, best.fun, 1)
    q = float(best.x[0])
    sd = math.sqrt(max(cov[0, 0], 0.0))
    tq = t_quantile(n - 1)
    lo_q, hi_q = (math.log(b) for b in D_BOUNDS)
    unpinned = not (math.isfinite(sd) and tq * sd <= hi_q - lo_q)
    if unpinned:  # a flat misfit: the interval is D0's whole range (no exp overflow)
        sd = (hi_q - lo_q) / tq
    d0 = math.exp(q)
    fitted = model_fn(d0, t)
    tt = np.linspace(0.0, float(t.max()), 200)
    warns = []
    if not best.success:
        warns.append(f"the fit did not converge ({best.message})")
    if y.max() < 0.3:
        warns.append("less than 30% released: D0 rests on the early t^1/2 part only")
    if unpinned:
        warns.append(f"the interval spans D0's whole range {D_BOUNDS}: the data do not pin "
                     "it")
    if min(abs(q - math.log(b)) for b in D_BOUNDS) < 1e-6:
        warns.append(f"D0 at its bound {D_BOUNDS}: the curve does not pin it")
    return {
        "names": ["drug_diffusivity_cm2_s"],
        "parameters": {"drug_diffusivity_cm2_s": d0},
        "intervals": {"drug_diffusivity_cm2_s": [math.exp(max(q - tq * sd, lo_q)),
                                                 math.exp(min(q + tq * sd, hi_q))]},
        "stderr": {"drug_diffusivity_cm2_s": d0 * sd},
        "interval_kind": "linearised (Jacobian of log D0, Student t)",
        "f2": fda_f2(100.0 * y, 100.0 * fitted, t),
        "similarity": similarity_of_fit(t, y, fitted),
        "residuals": (y - fitted).tolist(),
        "rms_residual": float(np.sqrt(np.mean((fitted - y) ** 2))),
        "chi2_reduced": chi2, "n_points": n, "success": bool(best.success),
        "fitted": fitted.tolist(), "time_s": t.tolist(), "released": y.tolist(),
        "band": {"time_s": tt.tolist(), "released": model_fn(d0, tt).tolist(),
                 "lower": model_fn(math.exp(max(q - tq * sd, lo_q)), tt).tolist(),
                 "upper": model_fn(math.exp(min(q + tq * sd, hi_q)), tt).tolist()},
        "warnings": warns}
