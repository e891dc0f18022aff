"""The parameter uncertainty of a fitted gel carried to a dose time.

The dose time t(theta) of the front model (milliseconds per answer) is a function of the
fitted equilibrium parameters theta; with their covariance Sigma the delta method gives
var t = g Sigma g^T, g = dt/dtheta by central differences in the fit's own (internal)
parametrisation; the interval is t exp(+-1.96 sd(t)/t) (normal in log t).
``sample_dose_times`` is the brute-force check: t at parameter vectors
drawn from N(theta, Sigma).  A kinetics fit adds tau's relative uncertainty to the seconds
when the request uses its k0.  This interval is about the gel's parameters, beside the
model's numerical error estimate (``DoseAnswer.error_estimate``).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from solver.equilibrium import equilibrium
from solver.errors import NotApplicableError, ParameterError, SolverError
from solver.fit.equilibrium import gel_from_internal
from solver.gel import Gel

from ..model_choice import front_run
from ..units import PhysicalConstants, radius_after_dose, timescale_uncertainty
from .gel_store import diffusivity_interval, record_for

Z95 = 1.959963984540054


def _internal(record: dict[str, Any]) -> tuple[np.ndarray, np.ndarray, float]:
    fit = (record.get("swelling") or {}).get("fit") or {}
    internal = fit.get("internal")
    if not internal:
        raise ParameterError("gel", record.get("name"), "a stored gel with a swelling fit")
    return (np.array(internal["values"], dtype=float),
            np.array(internal["covariance"], dtype=float), float(internal["t_ref"]))


def dose_time(gel: Gel, t_start: float, t_end: float, branch: str, fraction: float,
              sharp: bool) -> float:
    """The front model's dimensionless time to release ``fraction`` of the stored fluid."""
    a0 = equilibrium(gel, t_start, branch).stretch
    fr = front_run(gel, t_start, t_end, branch, sharp)
    return float(fr.time_to_radius(radius_after_dose(a0, fraction)))


SMOOTH_N = 100  # Lagrangian cells of a smooth jump's full run (no interface to resolve)


def full_dose_time(gel: Gel, t_start: float, t_end: float, branch: str,
                   fraction: float) -> float:
    """The full solver's dimensionless dose time where the front model does not apply (a
    smooth jump: no coexistence on the path, so no interface and no interfacial length
    matters): the paper's model on SMOOTH_N Lagrangian cells, stopped at the dose radius
    (eqs. PDE_Dimless to Boundary_Dimless); the horizon grows x4 up to 64 tau."""
    from ..runs.full import full_solver

    simulate = full_solver()

    target = radius_after_dose(equilibrium(gel, t_start, branch).stretch, fraction)
    until = 1.0
    while True:
        res = simulate(gel, t_start, t_end, until=until, stop=target, branch=branch,
                       grid="lagrangian", n=SMOOTH_N, integrator="implicit")
        if res.status == "stopped" and res.terminal_time is not None:
            return float(res.terminal_time)
        if until >= 64.0:
            raise SolverError(f"a(t) does not reach the dose radius {target:.6g} by t = 64",
                              {"gel": gel.name})
        until *= 4.0


def _time_at(q: np.ndarray, t_ref: float, base: Gel, args: tuple) -> float:
    g = gel_from_internal(q, t_ref, name=base.name).with_permeability(
        base.permeability.law, base.permeability.beta)
    return dose_time(g, *args)


def dose_time_interval(record: dict[str, Any], gel: Gel, t_start: float, t_end: float,
                       branch: str, fraction: float, sharp: bool) -> dict[str, Any]:
    """Delta-method 95% interval of the dose time from the fit's covariance (module doc)."""
    q, cov, t_ref = _internal(record)
    args = (t_start, t_end, branch, fraction, sharp)
    t0 = _time_at(q, t_ref, gel, args)
    sd = np.sqrt(np.clip(np.diag(cov), 0.0, None))
    if np.any(sd > 1e3):
        return {"method": "delta", "time": None, "note": "some fitted parameters are not "
                "identifiable (unbounded intervals): no dose-time interval; fix them in the fit"}
    grad = np.zeros(q.size)
    for j in np.nonzero(sd > 0.0)[0]:
        h = 0.1 * sd[j]
        qp, qm = q.copy(), q.copy()
        qp[j] += h
        qm[j] -= h
        try:
            grad[j] = (_time_at(qp, t_ref, gel, args) - _time_at(qm, t_ref, gel, args)) / (2 * h)
        except (ParameterError, NotApplicableError, SolverError) as exc:
            return {"method": "delta", "time": None,
                    "note": f"the front model fails within the parameters' uncertainty ({exc})"}
    se = float(math.sqrt(max(grad @ cov @ grad, 0.0)))
    rel = Z95 * se / t0  # in log t: a time is positive and its spread skewed to the right
    return {"method": "delta", "confidence": 0.95, "time_center": t0, "time_stderr": se,
            "time": [t0 * math.exp(-rel), t0 * math.exp(rel)], "relative_half_width": rel,
            "note": "from the covariance of the swelling fit (delta method in log t, front "
                    "model)"}


def sample_dose_times(record: dict[str, Any], gel: Gel, t_start: float, t_end: float,
                      branch: str, fraction: float, sharp: bool, n: int = 200,
                      seed: int = 0) -> tuple[np.ndarray, int]:
    """Dose times at ``n`` parameter vectors drawn from the fit's normal approximation, and
    how many draws had no answer (the front model did not apply)."""
    q, cov, t_ref = _internal(record)
    rng = np.random.default_rng(seed)
    draws = rng.multivariate_normal(q, cov, size=n, method="eigh")
    out, failed = [], 0
    for qq in draws:
        try:
            out.append(_time_at(qq, t_ref, gel, (t_start, t_end, branch, fraction, sharp)))
        except (ParameterError, NotApplicableError, SolverError, ValueError):
            failed += 1
    return np.array(out), failed


def objective_spread(rec: dict[str, Any]) -> float:
    """|ln ratio| of the two objectives' dose times where a stored swelling fit's report
    flagged them as disagreeing (0 otherwise)."""
    dj = ((rec.get("swelling") or {}).get("fit") or {}).get("dose_time_by_objective") or {}
    ratio = dj.get("ratio")
    if not dj.get("disagree") or not ratio or not math.isfinite(ratio) or ratio <= 0:
        return 0.0
    return abs(math.log(ratio))


def attach_parameter_interval(req: Any, answer: Any) -> Any:
    """Set ``answer.timescale_uncertainty`` (every answer: the seconds' range from the
    timescale constants, or the kinetics fit's interval of D) and, for a dose of a stored
    fitted gel, ``answer.parameter_interval`` (front model answers only; the full solver
    is too slow to differentiate per request)."""
    d_iv = diffusivity_interval(req.gel) if req.constants.calibrated else None
    answer.timescale_uncertainty = timescale_uncertainty(
        req.gel.omega, req.t_end, req.constants, answer.seconds,
        None if d_iv is None else _scaled_interval(d_iv, req.t_end, req.constants))
    rec = record_for(req.gel)
    if rec is None or not (rec.get("swelling") or {}).get("fit"):
        return answer
    if answer.model == "full":
        answer.parameter_interval = {"method": "delta", "time": None, "note": "the parameter "
                                     "interval needs the front model; this dose uses the full "
                                     "solver"}
        return answer
    iv = dose_time_interval(rec, req.gel, req.t_start, req.t_end, req.branch, req.fraction,
                            req.settings.regularized)
    if iv.get("time") is not None and answer.seconds is not None:
        rel = iv["relative_half_width"]
        joint = joint_relative_half_width(rec, req) if d_iv is not None else None
        if joint is not None:
            rel = joint
            iv["note"] += ("; seconds: swelling and kinetics jointly (tau refitted as the "
                           "swelling parameters move: their correlation kept)")
            iv["method"] = "delta, joint"
        elif d_iv is not None:
            rel_k = 0.5 * math.log(d_iv[1] / d_iv[0])
            rel = math.hypot(rel, rel_k)
            iv["note"] += ("; seconds include the kinetics fit's uncertainty in D (added in "
                           "quadrature: the kinetics fit was not made on this gel's swelling "
                           "fit with the front model)")
        else:
            iv["note"] += ("; the seconds also carry the timescale constants' uncertainty "
                           "(timescale_uncertainty), not included here")
        spread = objective_spread(rec)
        if spread:  # the objectives disagreed when the gel was fitted (dosing.fits.gel)
            rel += spread
            iv["relative_half_width"] = iv["relative_half_width"] + spread
            if iv.get("time") is not None and iv.get("time_center") is not None:
                t0 = iv["time_center"]
                w = iv["relative_half_width"]
                iv["time"] = [t0 * math.exp(-w), t0 * math.exp(w)]
            iv["note"] += (f"; widened by {spread:.3g} in ln t: the swelling fit's two "
                           "objectives disagreed on its dose time (ratio "
                           f"{math.exp(spread):.3g})")
        s = answer.seconds
        iv["seconds"] = [s * math.exp(-rel), s * math.exp(rel)]
        iv["seconds_relative_half_width"] = rel
    answer.parameter_interval = iv
    return answer


def _scaled_interval(d_iv: tuple[float, float], t_end: float,
                     constants: PhysicalConstants) -> tuple[float, float]:
    """A kinetics fit's interval of D (at its temperature) carried to T_end as D itself."""
    f = constants.diffusivity(t_end) / constants.diffusivity_m2_s / 1.0
    return d_iv[0] * f, d_iv[1] * f


def _half_time(gel: Gel, t_start: float, t_end: float, branch: str, sharp: bool) -> float:
    """The front model's dimensionless time to half the radius change of a jump: what a
    kinetics fit matches (tau = t_data / t_model), so tau moves as 1 / this."""
    fr = front_run(gel, t_start, t_end, branch, sharp)
    lo, hi = fr.radius_range
    return float(fr.time_to_radius(0.5 * (lo + hi)))


def joint_relative_half_width(record: dict[str, Any], req: Any) -> float | None:
    """The 95% half-width of log(seconds) from the swelling and kinetics fits together.

    seconds = t_dose(theta) tau(theta), and a kinetics fit made on this gel matched its data
    with the model's own times, so tau(theta) = tau_fit h(theta_fit) / h(theta) (h: the
    model's time to half the kinetics jump's change).  The delta method on
    log t_dose - log h over the swelling covariance keeps their correlation (both move
    with the dry size and chi); the kinetics fit's own tau uncertainty (given theta) adds in
    quadrature.  None when the kinetics fit used the full solver or a front model fails."""
    kin = (record.get("kinetics") or {}).get("fit") or {}
    if kin.get("model") not in ("front", "front-sharp") or kin.get("t_start") is None:
        return None
    d_iv = kin.get("diffusivity_interval_cm2_s")
    if not d_iv:
        return None
    q, cov, t_ref = _internal(record)
    sd = np.sqrt(np.clip(np.diag(cov), 0.0, None))
    if np.any(sd > 1e3):
        return None
    sharp_k = kin["model"] == "front-sharp"
    dose_args = (req.t_start, req.t_end, req.branch, req.fraction, req.settings.regularized)
    kin_args = (float(kin["t_start"]), float(kin["t_end"]), kin.get("branch") or "swollen",
                sharp_k)

    def log_ratio(qq: np.ndarray) -> float:
        g = gel_from_internal(qq, t_ref, name=req.gel.name).with_permeability(
            req.gel.permeability.law, req.gel.permeability.beta)
        return math.log(dose_time(g, *dose_args)) - math.log(_half_time(g, *kin_args))

    grad = np.zeros(q.size)
    try:
        for j in np.nonzero(sd > 0.0)[0]:
            h = 0.1 * sd[j]
            qp, qm = q.copy(), q.copy()
            qp[j] += h
            qm[j] -= h
            grad[j] = (log_ratio(qp) - log_ratio(qm)) / (2 * h)
    except (ParameterError, NotApplicableError, SolverError, ValueError):
        return None
    rel_s = Z95 * math.sqrt(max(float(grad @ cov @ grad), 0.0))
    rel_k = 0.5 * math.log(d_iv[1] / d_iv[0])
    return math.hypot(rel_s, rel_k)
