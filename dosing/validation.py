"""The full solver's verdict on a dose: the validation report and the answer's error.

Two truths (``SolverSettings.interfacial_length``): regularized (ell > 0, default, issue 8:
ell, ell/2, ell/4 extrapolated to ell -> 0 by module ``ladder``, its bound in every estimate)
or the paper's model (ell = 0: both grids at N, 30-60 % apart in the front regime, the spread
reported).  docs/interfacial.md secs. 6-9."""

from __future__ import annotations

import functools
import math
from typing import Any

import numpy as np

from solver.gel import Gel, preset
from solver.phase import nucleation_level

from .answers import ValidationReport
from .ladder import dose_limit
from .runs.scenario import Scenario, Trajectory
from .truth import pct, role, uncertainty
from .units import expelled_volume

# Prior relative error of an unvalidated front-model time, by dose fraction: the largest
# validated estimate over ANB 302->308 K and HHT 304->308 K, rounded up (printed by
# `python -m dosing.fits.calibrate [--method ladder] [--interfacial-length 0]`).  Paper's model:
# gap to either grid at N = 400 (small doses worst: the full model's shell takes time to
# form).  Sharp-interface model against the direct truth (issue 12; no bead size: the
# moving grid at ell = 1e-4, standing for ell -> 0): gap plus the numerical bound, measured
# (`python -m dosing.fits.calibrate`, ~3.5 min of CPU; front, truth, truth's numerical bound,
# estimate):
#   f    ANB 302->308 K                     HHT 304->308 K
#   0.1  0.00060 0.00062 0.06%  2.2%        0.00051 0.00076 0.07% 49.0%
#   0.2  0.00256 0.00261 0.05%  1.7%        0.00218 0.00243 0.09% 11.6%
#   0.3  0.00616 0.00626 0.05%  1.7%        0.00531 0.00559 0.10%  5.5%
#   0.4  0.01180 0.01200 0.04%  1.8%        0.01032 0.01069 0.10%  3.7%
#   0.5  0.02009 0.02046 0.04%  1.8%        0.01785 0.01838 0.10%  3.0%
#   0.6  0.03203 0.03264 0.04%  1.9%        0.02899 0.02978 0.10%  2.8%
#   0.7  0.04942 0.05043 0.03%  2.1%        0.04570 0.04692 0.09%  2.8%
#   0.8  0.07617 0.07784 0.03%  2.2%        0.07237 0.07434 0.08%  2.8%
#   0.9  0.12470 0.12771 0.02%  2.4%        0.12309 0.12664 0.05%  2.9%
# (the HHT 10 % dose is mostly the nucleation delay at the edge, which the sharp model has
# not).  Against the ladder (issue 8, ``method='ladder'``): gap to the
# default ladder's limit plus that limit's error bound; measured
# 16/18/6.6/4.6/4.2/3.8/3.4/2.9/2.5 % (ANB) and 5800/3700/123/43/23/14/9.8/7.6/7.0 % (HHT):
# below 30 % the regularized HHT runs delivered the dose before their front nucleated, so
# the ladder could not pin the limit there (docs/interfacial.md, sec. 9).
PRIOR_FRACTIONS = (0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9)
PRIOR_GAPS = {"front": (4.4, 2.9, 2.2, 1.8, 1.5, 1.2, 1.0, 0.8, 0.6),
              "front-sharp": (60.0, 40.0, 1.3, 0.45, 0.25, 0.15, 0.10, 0.08, 0.08),
              "front-sharp-direct": (0.50, 0.12, 0.06, 0.04, 0.035, 0.03, 0.03, 0.03, 0.03)}
PRIOR_NOTE = "doses of 10-90 % for ANB 302->308 K and HHT 304->308 K"
PRIOR_GELS = ("ANB", "HHT")  # the presets the priors were measured on
NO_PRIOR_ESTIMATE = 1.0  # an unmeasured gel's estimate: order one, not a borrowed figure


def front_prior(fraction: float, model: str = "front-sharp") -> float:
    """The prior error of a front-model time for a dose fraction (interpolated, clamped)."""
    return float(np.interp(fraction, PRIOR_FRACTIONS, PRIOR_GAPS[model]))


def has_prior(gel: Gel | None) -> bool:
    """True when the priors were measured on this gel (a preset of PRIOR_GELS)."""
    return gel is None or gel.key() in _prior_keys()


@functools.cache
def _prior_keys() -> frozenset[tuple[float, ...]]:
    return frozenset(preset(name).key() for name in PRIOR_GELS)


def _run_entry(sc: Scenario, traj: Trajectory | BaseException | None, start_radius: float,
               radius: float, t_front: float | None, level: float | None) -> dict[str, Any]:
    s = sc.settings
    entry: dict[str, Any] = {"grid": s.grid, "n": s.n, "interfacial_length": s.interfacial_length,
                             "scenario_key": sc.key()}
    if isinstance(traj, Trajectory):
        try:
            entry["time"] = traj.time_to_radius(radius)
        except ValueError as exc:  # a run that never reaches the radius: its error, not ours
            entry["error"] = f"the run does not reach the dose's radius: {exc}"
            return entry
        entry["nucleation_time"] = None if level is None else traj.nucleation_time(level)
        entry["wall_seconds"] = traj.meta.get("wall_seconds")
        if traj.spinodal:
            entry["warning"] = (traj.diagnostics.get("message")
                                or "spinodal collapse (not converged)")
        if t_front is not None:
            target = expelled_volume(start_radius, radius)
            got = expelled_volume(start_radius, traj.radius_at(t_front))
            entry["front_volume_error"] = (got - target) / target
    else:
        entry["error"] = run_failure(traj)
    return entry


def run_failure(exc: BaseException | None) -> str:
    """Why a run failed, in plain words (never a Python exception's class name)."""
    from solver.errors import ParameterError, SolverError

    text = str(exc or "").strip()
    if isinstance(exc, SolverError):
        return f"the solver could not finish this run: {text}"
    if isinstance(exc, ParameterError):
        return f"the run's input {exc.field} is not usable: {text}"
    if exc is None:
        return "the run has no result"
    return f"the run failed: {text or 'its worker ended without a reason'}"


def validation_report(scs: list[Scenario], trajs: list[Any], start_radius: float,
                      radius: float, t_front: float | None) -> ValidationReport:
    """The truth's time for the dose, each run's, and the front model's errors.  ``scs``: the
    settings' validation runs (``SolverSettings.rungs``), ``trajs`` their trajectories or exceptions
    in order; regularized runs also report the edge nucleation (module ``ladder``).  The volume
    error is (V_full(t_front) - V) / V on the truth run (the paper's first grid, or finest rung)."""
    s = scs[0].settings
    sc0 = scs[0]
    level = (nucleation_level(sc0.gel, sc0.t_start, sc0.t_end, sc0.branch)  # type: ignore[arg-type]
             if s.regularized and sc0.t_end is not None else None)
    runs = [_run_entry(sc, tr, start_radius, radius, t_front, level)
            for sc, tr in zip(scs, trajs, strict=True)]
    times = [e.get("time") for e in runs]
    rep: dict[str, Any] = {
        "model": "regularized" if s.regularized else "paper",
        "method": s.method if s.regularized else "paper",
        "interfacial_length": s.interfacial_length, "settings": s.to_dict(), "runs": runs,
        "time": None, "error": None, "limit": None, "grid_spread": None,
        "front_time": t_front, "front_time_error": None, "front_volume_error": None,
        "uncertainty": None}
    if s.direct:
        for sc, e in zip(scs, runs, strict=True):
            e["role"] = role(s, sc.settings)
        truth = runs[0]
        if truth.get("time") is not None:
            bead = any(e["role"] == "ell_range" for e in runs)
            unc = uncertainty(s, runs, truth["time"], bead)
            rep.update(time=truth["time"], error=unc.numerical.relative,
                       uncertainty=unc.to_dict())
    elif s.regularized:
        if all(t is not None for t in times):
            lim = dose_limit([e["interfacial_length"] for e in runs], times,
                             [e["nucleation_time"] for e in runs])
            rep.update(time=lim.time, error=lim.error / lim.time, limit=lim.to_dict())
        truth = runs[-1]
    else:
        truth = runs[0]
        ok = [t for t in times if t is not None]
        if times[0] is not None:
            rep["time"] = times[0]
            if len(ok) > 1:
                rep["grid_spread"] = rep["error"] = (max(ok) - min(ok)) / times[0]
    if rep["time"] is not None and t_front is not None:
        rep["front_time_error"] = ((t_front - rep["time"]) / rep["time"]
                                   if rep["time"] > 0.0 else None)  # a 0 time: no ratio
        rep["front_volume_error"] = truth.get("front_volume_error")
    return ValidationReport(**rep)


def failure(rep: ValidationReport) -> str | None:
    """Why the report has no truth time (the failed runs' errors), or None."""
    if rep.time is not None:
        return None
    return "; ".join(f"{e['grid']} N = {e['n']}, ell = {e['interfacial_length']:g}: "
                     f"{e['error']}" for e in rep.runs if "error" in e) or "no run"


def _runs_text(rep: ValidationReport) -> str:
    return ", ".join(f"{e['time']:.5g} at ell = {e['interfacial_length']:g} (N = {e['n']})"
                     for e in rep.runs if "time" in e)


def _prior(model: str, fraction: float) -> tuple[float, str]:
    prior = front_prior(fraction, model)
    if model == "front-sharp-direct":
        return prior, (
            f"Not yet checked against the full solver for this scenario (ask for a "
            f"validation). For {PRIOR_NOTE}, this front model (the step-function model with "
            f"the sharp-interface front condition) was within {pct(prior)} of the direct "
            "truth (the regularized model on the moving grid at ell = 1e-4, standing for the "
            "limit ell -> 0), its numerical bound included (small doses are worst: the "
            "regularized model's front first has to nucleate at the edge).")
    if model == "front-sharp":
        return prior, (
            f"Not yet checked against the full solver for this scenario (ask for a "
            f"validation). For {PRIOR_NOTE}, this front model (the step-function model with "
            f"the sharp-interface front condition) was within {pct(prior)} of the "
            "regularized full model's limit ell -> 0 at this dose, that limit's own error "
            "included (small doses are worst: the regularized model's front first has to "
            "nucleate at the edge).")
    return prior, (
        f"Not yet checked against the full solver for this scenario (ask for a "
        f"validation). For {PRIOR_NOTE}, the paper's front model was within {pct(prior)} of "
        "the paper's full model on both of its grids at this dose (small doses are worst: in "
        "the full model the shrunken shell takes time to form). Much of that gap is the full "
        "model's own uncertainty in this regime: without an interfacial energy the speed of "
        "a sharp front is not fixed by the model, and different discretizations pick "
        "different speeds.")


def _regularized(model: str, time: float, rep: ValidationReport) -> tuple[float, str]:
    s, lim = rep.settings, rep.limit
    truth, abs_err = lim["time"], lim["error"]
    ladder = (f"the regularized full model (interfacial length ell, {s['grid']} grid, each "
              f"run grid-converged) gives {_runs_text(rep)}; its sharp-interface limit "
              f"ell -> 0 is {truth:.5g} +/- {abs_err:.2g} ({lim['method']}). ")
    if model == "full":
        est = abs_err / truth + s["rtol"]
        text = f"Answered by the full solver: {ladder}"
    else:
        est = (abs(time - truth) + abs_err) / time
        text = (f"The front model (a fast reduced model) gives {time:.5g}; {ladder}The "
                f"front model is {pct(abs(time - truth) / truth)} off that limit. ")
    lo, hi = min(time, truth - abs_err), max(time, truth + abs_err)
    return est, text + (f"The estimate ({pct(est)}) adds the limit's error bound; treat "
                        f"the true time as between {lo:.4g} and {hi:.4g}.")


def _direct(model: str, time: float, rep: ValidationReport) -> tuple[float, str]:
    """The direct truth's verdict: the error estimate is the numerical part (and, for the
    front model, its gap to the truth); the other two parts are stated beside it."""
    s, unc = rep.settings, rep.uncertainty
    truth = rep.time
    num = unc["numerical"]["relative"]
    num = s["rtol"] if num is None else max(num, s["rtol"])
    run = (f"the regularized full model at ell = {s['interfacial_length']:.3g} directly "
           f"(moving grid, {s['n']} cells) gives {truth:.5g}. ")
    if model == "full":
        est = num
        text = f"Answered by the full solver: {run}"
    else:
        # a dose so small that a time is 0 (D6: never negative) has no relative gap: the
        # estimate is then taken relative to the other time (issue 22, N4)
        gap = abs(time - truth) / truth if truth > 0.0 else 0.0
        denom = time if time > 0.0 else truth
        est = (abs(time - truth) + num * truth) / denom if denom > 0.0 else num
        text = (f"The front model (a fast reduced model, the sharp-interface limit "
                f"ell -> 0) gives {time:.5g}; {run}The front model is {pct(gap)} off it. ")
    rng = unc["interfacial_length_range"]["relative"]
    ratio = unc.get("delayed_transition_ratio")
    summary = (f"numerical {pct(num)}; interfacial length "
               + ("not applicable (no bead size)" if rng is None else
                  f"{pct(rng)} over the mesh length's range")
               + "; model form: the delayed-transition law gives "
               + ("no time (its runs failed)" if ratio is None else
                  f"{unc['delayed_transition_time']:.5g}, {ratio:.3g}x this truth"))
    return est, text + (f"The estimate ({pct(est)}) is the numerical bound"
                        + ("" if model == "full" else " plus that gap")
                        + f". The truth's uncertainty in three parts (each explained in "
                          f"`uncertainty`): {summary}; only the numerical part is in the "
                          "estimate.")


def _paper(model: str, time: float, rep: ValidationReport) -> tuple[float, str]:
    s = rep.settings
    times = {e["grid"]: e["time"] for e in rep.runs if "time" in e}
    failed = [e["grid"] for e in rep.runs if "error" in e]
    gaps = [abs(t - time) / time for t in times.values()]
    if model == "full":
        est = max([s["rtol"], *gaps])
        listing = ", ".join(f"{t:.6g} on the {g} grid" for g, t in times.items()
                            if g != s["grid"]) or "no answer"
        text = (f"Answered by the paper's full model: {time:.6g} on the {s['grid']} grid "
                f"(N = {s['n']}); its second, independent discretization gives {listing}. ")
    else:
        est = max(gaps)
        listing = ", ".join(f"{t:.4g} on the {g} grid" for g, t in times.items())
        text = (f"The front model (a fast reduced model) gives {time:.4g}; the paper's full "
                f"model gives {listing} (N = {s['n']}). ")
    spread = rep.grid_spread
    if spread is not None and spread > 0.01:
        text += (f"The two grids disagree by {pct(spread)}: here a sharp front forms and the "
                 "paper's model, which has no interfacial energy, does not fix its speed, so "
                 "each discretization picks its own (the regularized model, interfacial_length "
                 "> 0, does). ")
    elif spread is not None:
        text += f"The two grids agree to {pct(max(spread, 1e-6))}. "
    if failed:
        text += f"The {', '.join(failed)} grid failed to run, so it is not in the estimate. "
    lo, hi = min([time, *times.values()]), max([time, *times.values()])
    return est, text + (f"The estimate ({pct(est)}) is the largest gap between this answer "
                        f"and the full model's answers; treat the true time as between "
                        f"{lo:.4g} and {hi:.4g}.")


VALIDATION_COST = ("two moving-grid runs of the regularized model at the bead's ell (400 "
                   "and 200 cells: about a second each for ANB, HHT or an Omega = 300 gel), "
                   "two at the ends of the mesh length's range and, once per gel and jump, "
                   "the ell = 0 lattice at N = 200/400/800 for the model-form part (a few "
                   "seconds): about 10 s in all the first time, then cached")


def _no_prior(gel: Gel) -> tuple[float, str]:
    return NO_PRIOR_ESTIMATE, (
        f"Not yet checked against the full solver, and there is no prior for this gel "
        f"(Omega = {gel.omega:g}): the front model's priors were measured on {PRIOR_NOTE} "
        f"only, and a gel outside that set can differ by much more (the estimate "
        f"{pct(NO_PRIOR_ESTIMATE)} says the error is unknown, not measured). Ask for a "
        f"validation: {VALIDATION_COST}.")


def error_estimate(model: str, time: float, rep: ValidationReport | None,
                   fraction: float, gel: Gel | None = None,
                   method: str = "direct") -> tuple[float, str]:
    """(relative error of the answer's time, the reason in plain words).  Unvalidated: the
    prior measured on PRIOR_GELS (``method`` 'ladder': against the ladder's truth), or, for
    another ``gel``, no prior."""
    prior_model = model if model != "full" else "front-sharp"
    if prior_model == "front-sharp" and method == "direct":
        prior_model = "front-sharp-direct"
    if rep is None or rep.time is None:
        if not has_prior(gel):
            return _no_prior(gel)  # type: ignore[arg-type]
        return _prior(prior_model, fraction)
    if rep.uncertainty is not None:
        est, text = _direct(model, time, rep)
    else:
        est, text = (_regularized if rep.limit is not None else _paper)(model, time, rep)
    if math.isnan(est):
        est = front_prior(fraction, prior_model)
    return est, text
