"""Multi-dose schedules in drug mass: hold reading, protocol check, shooting, leakage.

The three readings of ``dosing.schedule`` with the drug tracked: doses d_1..d_n are
fractions of the loaded drug (or ug), with rests at T_start between heatings at T_end.
1. hold: the doses read off one continuous heating (with D0 = 0 drug = fluid there, so
   these are the fluid schedule's hold times);
2. protocol check: those actuation times in the real heat/rest protocol (full solver with
   the drug): the drug each heating delivers (and how: squeezed out or diffused), the
   fluid it delivers, and the drug that leaks during each rest.  While it rests the bead
   takes up drug-free medium, so the next heating's fluid is diluted;
3. corrected: each actuation time shot (read off a longer heating, then secant on the exact
   protocol) so that its heating delivers the drug dose within the tolerance; a heating's
   delivery depends only on the earlier steps, so the doses are met one after another.
Warnings: a rest (or the wait before the first heating) that leaks more than a tenth of the
next dose, and a dose no actuation time can meet.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from itertools import accumulate
from typing import Any

from solver.errors import ParameterError, SolverError, require_finite_positive

from .drug import (
    DrugModel,
    DrugRequest,
    DrugRuns,
    DrugScenario,
    StatedTruth,
    carried_by_fluid,
    drug_settings,
    leak_time,
    runs_for,
)
from .drug_dose import MAX_HORIZON, resolve_wait
from .protocol import heat_cool_protocol, windows
from .request import Jump, ScheduleRequest, _resolve_scenario, resolve_rests
from .scenario import SolverSettings, Step
from .schedule import hold_schedule
from .truth import Part, Uncertainty, truth_text
from .units import PhysicalConstants, timescale, volume_to_ul

MAX_EXTENSIONS = 4
MAX_SECANT = 10
LEAK_WARNING = 0.1  # a rest leaking more than this share of the next dose is flagged


@dataclass(frozen=True)
class DrugScheduleRequest(DrugRequest):
    """Drug doses (``doses`` fractions of the load, or ``doses_ug``) with ``rests`` (tau)
    or ``rests_seconds`` at T_start between them, after ``wait`` at T_start."""

    gel: Any
    t_start: float
    t_end: float
    drug: DrugModel | dict[str, Any]
    doses: Sequence[float] | None = None
    doses_ug: Sequence[float] | None = None
    rests: Sequence[float] | None = None
    rests_seconds: Sequence[float] | None = None
    wait: float | None = None
    wait_seconds: float | None = None
    dry_radius_um: float | None = None
    swollen_radius_um: float | None = None
    constants: PhysicalConstants | dict[str, Any] | None = None
    branch: str | None = None
    settings: Any = None
    check_protocol: bool = True
    correct: bool = True
    tolerance: float = 0.01
    jump: Jump = field(init=False, repr=False, compare=False)
    bead_dry_radius_um: float | None = field(init=False, repr=False, compare=False)
    load_ug: float | None = field(init=False, repr=False, compare=False)
    fractions: tuple[float, ...] = field(init=False, repr=False, compare=False)
    lead: float = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        jump, dry = _resolve_scenario(self)
        drug = DrugModel.from_any(self.drug)
        object.__setattr__(self, "drug", drug)
        load = drug.load(None if dry is None else volume_to_ul(jump.stored_volume, dry),
                         jump.start_radius, self.constants)
        object.__setattr__(self, "load_ug", load)
        object.__setattr__(self, "fractions", self._resolve_doses(load))
        object.__setattr__(self, "rests", resolve_rests(self.rests, self.rests_seconds,
                                                        len(self.fractions), dry, self.t_end,
                                                        self.constants))
        object.__setattr__(self, "lead", resolve_wait(self.wait, self.wait_seconds, dry,
                                                      self.t_end, self.constants))
        tol = require_finite_positive("tolerance", self.tolerance)
        if tol > 0.2:
            raise ParameterError("tolerance", self.tolerance, "0 < tolerance <= 0.2")
        object.__setattr__(self, "tolerance", tol)
        self.solute  # noqa: B018 - validates the release volume against the bead

    def _resolve_doses(self, load: float | None) -> tuple[float, ...]:
        if (self.doses is None) == (self.doses_ug is None):
            raise ParameterError("doses", self.doses,
                                 "exactly one of doses (fractions of the load) or doses_ug")
        name = "doses" if self.doses_ug is None else "doses_ug"
        values = list(getattr(self, name) or ())
        if not values:
            raise ParameterError(name, values, "a non-empty list")
        out = []
        for i, v in enumerate(values):
            x = require_finite_positive(f"{name}[{i}]", v)
            if name == "doses_ug":
                if load is None:
                    raise ParameterError("drug.load_ug", None, "a finite number > 0 (ug per "
                                         "bead) to turn doses_ug into fractions of the load")
                x /= load
            out.append(x)
        total = sum(out)
        if not total < 1.0:
            scale = 1.0 if name == "doses" else load
            raise ParameterError(name, values, f"doses summing to less than {scale:.4g}"
                                 + (" ug" if name == "doses_ug" else " (the load)"),
                                 "together they ask for more drug than the bead holds")
        return tuple(out)

    def fluid_schedule(self) -> ScheduleRequest:
        """The same schedule read as fluid fractions (for the hold times with D0 = 0)."""
        return ScheduleRequest(self.gel, self.t_start, self.t_end, doses=self.fractions,
                               rests=self.rests, dry_radius_um=self.bead_dry_radius_um,
                               constants=self.constants, branch=self.branch,
                               settings=self.settings, check_protocol=False, correct=False)




@dataclass
class DrugScheduleAnswer(StatedTruth):
    """A drug schedule under each reading, with leakage and warnings."""

    model: str
    doses: list[float]
    doses_ug: list[float] | None
    load_ug: float | None
    rests: list[float]
    wait: float
    hold: list[dict[str, Any]]
    protocol_check: dict[str, Any] | None
    corrected: dict[str, Any] | None
    warnings: list[str]
    leak_time_10pct: float
    effective_diffusivity_cm2_s: float
    timescale_seconds: float | None
    note: str
    uncertainty: Uncertainty | None = None


class _Runner:
    """Drug runs of protocols for one request."""

    def __init__(self, planner: Any, req: DrugScheduleRequest, runs: DrugRuns,
                 settings: SolverSettings | None = None) -> None:
        self.req, self.runs = req, runs
        self.solute = req.solute
        self.count = 0
        self.settings = settings or drug_settings(req.settings)

    def steps(self, durations: Sequence[float]) -> tuple[Step, ...]:
        r = self.req
        lead = ((r.lead, r.t_start),) if r.lead > 0.0 else ()
        return (*lead, *heat_cool_protocol(durations, r.rests, r.t_start, r.t_end))

    def __call__(self, durations: Sequence[float]) -> Any:
        r = self.req
        self.count += 1
        return self.runs.run(DrugScenario(r.gel, r.t_start, self.steps(durations), self.solute,
                                          r.branch, self.settings))

    def windows(self, durations: Sequence[float]) -> list[tuple[float, float]]:
        return [(a + self.req.lead, b + self.req.lead)
                for a, b in windows(durations, self.req.rests)]


def _reading(run: _Runner, rel: Any, durations: Sequence[float]) -> dict[str, Any]:
    """What each heating delivers (drug, its squeezed part, fluid) and each rest leaks."""
    req = run.req
    win = run.windows(durations)
    import numpy as np

    a3 = rel.radius**3

    def at(arr: Any, t: float) -> float:
        return float(np.interp(t, rel.t, arr))

    scale = req.start_radius**3 - 1.0
    drug = [at(rel.released_fraction, e) - at(rel.released_fraction, s) for s, e in win]
    sq = rel.squeezed_fraction if np.size(rel.squeezed_fraction) == np.size(rel.t) \
        else rel.advected_fraction  # the D0 = 0 twin's release (grid-independent)
    squeezed = [at(sq, e) - at(sq, s) for s, e in win]
    fluid = [(at(a3, s) - at(a3, e)) / scale for s, e in win]
    leaks = [at(rel.released_fraction, win[k + 1][0]) - at(rel.released_fraction, win[k][1])
             for k in range(len(win) - 1)]
    before = at(rel.released_fraction, win[0][0])
    load = req.load_ug
    out = {"actuation_times": list(map(float, durations)),
           "protocol": [list(s) for s in run.steps(durations)],
           "delivered_fractions": drug, "relative_errors": [
               g / f - 1.0 for g, f in zip(drug, req.fractions, strict=False)],
           "squeezed_fractions": squeezed,
           "peclet_numbers": [rel.peclet(s, e) for s, e in win],
           "diffused_fractions": [d - s for d, s in zip(drug, squeezed, strict=True)],
           "fluid_fractions": fluid,
           "drug_per_fluid": [d / f if f > 0 else None for d, f in zip(drug, fluid,
                                                                        strict=True)],
           "rest_leak_fractions": leaks, "leaked_before_heating": before,
           "in_gel_after": at(rel.in_gel_fraction, win[-1][1]),
           "mass_balance_error": rel.mass_balance_error}
    if load is not None:
        out.update(delivered_ug=[d * load for d in drug], rest_leak_ug=[x * load for x in leaks],
                   leaked_before_heating_ug=before * load)
        vol, dry = req.drug.release_volume_ul, req.bead_dry_radius_um
        if vol is not None and dry is not None:  # the medium grows by the expelled fluid
            unit = volume_to_ul(4.0 * math.pi / 3.0, dry)
            out["medium_concentration_ug_per_ul"] = [
                at(rel.released_fraction, e) * load / (vol + unit * (req.start_radius**3
                                                                      - at(a3, e)))
                for _, e in win]
    return out


def _schedule_uncertainty(planner: Any, req: DrugScheduleRequest, runs: DrugRuns,
                          reading: dict[str, Any] | None, s: Any) -> Uncertainty | None:
    """A simulated schedule's uncertainty in the three parts: numerical, the same protocol
    run on n / 2 cells (the largest change of a delivered dose, relative to the dose); the
    interfacial-length and model-form parts are the single doses' (not measured here)."""
    if reading is None:
        return None
    times = reading["actuation_times"]
    half = _Runner(planner, req, runs, settings=s.check())
    coarse = _reading(half, half(times), times)["delivered_fractions"]
    fine = reading["delivered_fractions"]  # (a schedule not met has fewer heatings)
    gap = max(abs(c - f) / d for c, f, d in zip(coarse, fine, req.fractions[:len(fine)],
                                                strict=True))
    numerical = Part(gap, f"numerical: {gap:.2%}, the largest change of a delivered dose when "
                          f"the protocol ({', '.join(f'{t:.4g}' for t in times)}) runs on "
                          f"{half.settings.n} cells instead of {s.n} (ell = "
                          f"{s.interfacial_length:.3g})")
    how = ("not measured for a schedule: validate the single fluid doses of the same bead "
           "and jump (HTTP validate_full, CLI dose --validate); their answers state it")
    return Uncertainty(numerical, Part(None, f"interfacial length: {how}"),
                       Part(None, f"model form: {how}"))


def _leak_warnings(req: DrugScheduleRequest, reading: dict[str, Any], label: str) -> list[str]:
    out = []
    if reading["leaked_before_heating"] > LEAK_WARNING * req.fractions[0]:
        out.append(f"{label}: the wait before the first heating leaks "
                   f"{reading['leaked_before_heating']:.3g} of the load, more than a tenth of "
                   f"the first dose ({req.fractions[0]:.3g})")
    for k, leak in enumerate(reading["rest_leak_fractions"]):
        nxt = req.fractions[k + 1]
        if leak > LEAK_WARNING * nxt:
            out.append(f"{label}: rest {k + 1} leaks {leak:.3g} of the load, more than a "
                       f"tenth of the next dose ({nxt:.3g})")
    return out


def _read_off(run: _Runner, durations: list[float], k: int, guess: float
              ) -> tuple[float | None, float]:
    """(duration of heating k delivering dose k read off a longer heating, or None if no
    heating reaches it; the most it delivers)."""
    target = run.req.fractions[k]
    horizon = max(2.0 * guess, guess + 0.05)
    most = 0.0
    for _ in range(MAX_EXTENSIONS):
        rel = run([*durations, horizon])
        start = run.windows([*durations, horizon])[k][0]
        try:
            return rel.time_to_release(target, after=start) - start, 0.0
        except ValueError:
            most = float(rel.released_fraction[-1] - rel.released_at(start))
            late = float(rel.released_fraction[-1] - rel.released_at(start + horizon / 2.0))
            # a drug the collapsed shell holds: even the late rate kept to the cap falls short
            if horizon >= MAX_HORIZON or most + max(late, 0.0) * (
                    MAX_HORIZON - horizon) / (horizon / 2.0) < target:
                break
            horizon = min(4.0 * horizon, MAX_HORIZON)
    return None, most


def _secant(run: _Runner, durations: list[float], k: int, d0: float, tol: float) -> float:
    """Refine heating k's duration until its drug meets the dose within ``tol``."""
    target = run.req.fractions[k]

    def got(d: float) -> float:
        trial = [*durations, d]
        return _reading(run, run(trial), trial)["delivered_fractions"][k]

    g0 = got(d0)
    if abs(g0 / target - 1.0) <= tol:
        return d0
    d1 = d0 * (target / g0) if g0 > 0 else 1.5 * d0
    g1 = got(d1)
    for _ in range(MAX_SECANT):
        if abs(g1 / target - 1.0) <= tol or g1 == g0:
            break
        d0, g0, d1 = d1, g1, max(d1 + (target - g1) * (d1 - d0) / (g1 - g0), 1e-6)
        g1 = got(d1)
    return d1


def _shoot(run: _Runner, guesses: Sequence[float]) -> tuple[dict[str, Any], list[str]]:
    req = run.req
    tol = req.tolerance / 2.0
    durations: list[float] = []
    warnings: list[str] = []
    for k, g in enumerate(guesses):
        d, most = _read_off(run, durations, k, g)
        if d is None:
            warnings.append(f"corrected: no actuation time meets dose {k + 1} "
                            f"({req.fractions[k]:.3g} of the load): heating then delivers "
                            f"at most {most:.3g}; doses from {k + 1} on are not corrected")
            break
        durations.append(_secant(run, durations, k, d, tol))
    if not durations:
        return {"actuation_times": [], "met": False, "runs": run.count}, warnings
    res = _reading(run, run(durations), durations)
    errs = [abs(e) for e in res["relative_errors"]]
    res.update(runs=run.count, max_relative_error=max(errs),
               met=len(durations) == len(req.fractions) and max(errs) <= req.tolerance)
    if len(durations) == len(req.fractions) and max(errs) > req.tolerance:
        raise SolverError(f"shooting did not meet the drug doses within {req.tolerance:.2%} "
                          f"(worst {max(errs):.2%})", res)
    return res, warnings + _leak_warnings(req, res, "corrected")


def _seconds(res: dict[str, Any] | None, tau: float | None) -> None:
    if res is not None and "actuation_times" in res:
        res["actuation_seconds"] = (None if tau is None
                                    else [d * tau for d in res["actuation_times"]])


def plan_drug_schedule(planner: Any, req: DrugScheduleRequest,
                       runs: DrugRuns | None = None) -> DrugScheduleAnswer:
    """Plan ``req``: hold times, the protocol check and the corrected schedule."""
    runs = runs or runs_for(planner)
    run = _Runner(planner, req, runs)
    solute = req.solute
    dry = req.bead_dry_radius_um
    tau = timescale(dry, req.t_end, req.constants).seconds if dry is not None else None
    warnings: list[str] = []
    if carried_by_fluid(solute):
        model, rows = hold_schedule(planner, req.fluid_schedule())
        hold = [row.to_dict() for row in rows]
        model = f"{model} (D0 = 0: drug = fluid on one heating)"
    else:
        model = "full"
        hold = []
        horizon = 0.5
        for _ in range(MAX_EXTENSIONS + 1):
            rel = run([horizon])
            try:
                ends = [rel.time_to_release(c, after=req.lead) - req.lead
                        for c in accumulate(req.fractions)]
                break
            except ValueError:
                if horizon >= MAX_HORIZON:
                    raise ParameterError("doses", list(req.fractions), f"summing to below "
                                         f"{rel.released_fraction[-1]:.4f}", "one continuous "
                                         "heating releases at most that") from None
                horizon = min(4.0 * horizon, MAX_HORIZON)
        prev = 0.0
        for d, c, e in zip(req.fractions, accumulate(req.fractions), ends, strict=True):
            hold.append({"dose_fraction": d, "cumulative_fraction": c, "start": prev, "end": e,
                         "actuation_time": e - prev,
                         "actuation_seconds": None if tau is None else (e - prev) * tau})
            prev = e
    load = req.load_ug
    for row in hold:
        row["dose_ug"] = None if load is None else row["dose_fraction"] * load
    guesses = [row["actuation_time"] for row in hold]
    checked = None
    if req.check_protocol:
        checked = _reading(run, run(guesses), guesses)
        warnings += _leak_warnings(req, checked, "protocol check")
    corrected = None
    if req.correct:
        corrected, more = _shoot(run, guesses)
        warnings += more
    _seconds(checked, tau)
    _seconds(corrected, tau)
    s = drug_settings(req.settings)
    unc = _schedule_uncertainty(planner, req, runs, corrected or checked, s)
    d0 = req.drug.d0_cm2_s(req.t_end, req.constants)
    phi0 = 1.0 - 1.0 / req.start_radius**3
    of_load = "" if load is None else f" ({load:.4g} ug)"
    note = (f"Doses are drug, as fractions of the load{of_load}. "
            "Hold times read the doses off one continuous heating; the protocol check runs "
            f"those times as heat at T_end / rest at T_start (full solver, {s.grid} grid, "
            f"N = {s.n}, interfacial length {s.interfacial_length:g}, with the drug on its "
            "cells): during each rest the bead leaks drug by diffusion and takes up drug-free "
            "medium, which dilutes the fluid the next heating expels. The corrected times "
            f"meet each drug dose within {req.tolerance:.0%} on the same solver. A heating's "
            "squeezed part is the release of the same mechanics with D0 = 0, the diffused "
            "part the rest. " + req.drug.mesh_note(req.start_radius, req.constants)
            + f" D0 = {d0:.3g} cm^2/s at T_end ({req.drug.reference_temperature_k:g} K "
            "reference, Stokes-Einstein with water's viscosity). The permeability does not "
            "depend on temperature at fixed porosity (k0 as given).")
    if "front" in model and s.regularized and not s.direct:
        note += (" With D0 = 0 the hold times are the front model's sharp-interface limit "
                 "(ell -> 0) while the protocol runs use the ladder's coarsest ell, whose front "
                 "first has to nucleate at the edge: part of the correction is that delay.")
    return DrugScheduleAnswer(
        model=model, doses=list(req.fractions),
        doses_ug=None if load is None else [f * load for f in req.fractions], load_ug=load,
        rests=list(req.rests), wait=req.lead, hold=hold, protocol_check=checked,
        corrected=corrected, warnings=warnings, leak_time_10pct=leak_time(solute,
                                                                           req.start_radius),
        effective_diffusivity_cm2_s=d0 * float(solute.hindrance.factor(phi0)),
        timescale_seconds=tau, note=note, interfacial_length=s.interfacial_length,
        bead_dry_radius_um=req.bead_dry_radius_um, truth=truth_text(req),
        uncertainty=unc)
