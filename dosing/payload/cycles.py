"""Multi-dose schedules in drug mass: hold reading, protocol check, shooting, leakage.

The three readings of ``dosing.question.schedule`` with the drug tracked: doses d_1..d_n are
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
from dataclasses import asdict, dataclass, field
from itertools import accumulate
from typing import Any

import numpy as np

from solver.errors import ParameterError, require_finite_positive

from ..answers import HoldRow
from ..question.events import schedule_events
from ..question.schedule import ScheduleViews, hold_schedule, with_seconds
from ..question.shooting import Short, corrected, read_off
from ..request import ScheduleCase, ScheduleRequest
from ..runs.solute import DrugRuns, drug_settings, runs_for
from ..truth import Part, Uncertainty, truth_text
from ..units import timescale, volume_to_ul
from .drug import StatedTruth, carried_by_fluid, leak_time
from .release import DrugCase, DrugHeatings, first_heating

LEAK_WARNING = 0.1  # a rest leaking more than this share of the next dose is flagged


@dataclass(frozen=True)
class DrugHoldRow(HoldRow):
    """A drug schedule's hold row: the fluid one's fields, and the dose in ug (with a load)."""

    dose_ug: float | None = None


@dataclass(frozen=True)
class DrugScheduleRequest(DrugCase, ScheduleCase):
    """Drug doses (``doses`` fractions of the load, or ``doses_ug``): the
    :class:`~dosing.request.ScheduleCase` fields (rests, check, correction, tolerance) and
    the :class:`~dosing.payload.release.DrugCase` ones (the drug, the wait at T_start)."""

    doses: Sequence[float] | None = None
    doses_ug: Sequence[float] | None = None
    fractions: tuple[float, ...] = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        self.resolve_heating()
        dry = self.resolve_drug()
        object.__setattr__(self, "fractions", self._resolve_doses(self.load_ug))
        self.resolve_schedule(len(self.fractions), dry)
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
        return ScheduleRequest(**self.case_fields(), doses=self.fractions, rests=self.rests,
                               check_protocol=False, correct=False)


@dataclass
class DrugScheduleAnswer(StatedTruth, ScheduleViews):
    """A drug schedule under each reading, with leakage and warnings."""

    model: str
    doses: list[float]
    doses_ug: list[float] | None
    load_ug: float | None
    rests: list[float]
    wait: float
    hold: list[DrugHoldRow]
    protocol_check: dict[str, Any] | None
    corrected: dict[str, Any] | None
    warnings: list[str]
    leak_time_10pct: float
    effective_diffusivity_cm2_s: float
    timescale_seconds: float | None
    note: str
    uncertainty: Uncertainty | None = None
    # the schedule as a lab runs it, one row per step (dosing.question.events)
    events: list[dict[str, Any]] = field(default_factory=list)


def _reading(run: DrugHeatings, rel: Any, durations: Sequence[float]) -> dict[str, Any]:
    """What each heating delivers (drug, its squeezed part, fluid) and each rest leaks."""
    req = run.req
    win = run.windows(durations)
    a3 = rel.radius**3

    def at(arr: Any, t: float) -> float:
        return float(np.interp(t, rel.t, arr))

    scale = req.start_radius**3 - 1.0
    drug = run.delivered(rel, durations)
    squeezed = [rel.squeezed_at(e) - rel.squeezed_at(s) for s, e in win]
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
    half = DrugHeatings(req, runs, req.fractions, settings=s.check())
    coarse = _reading(half, half.run(times), times)["delivered_fractions"]
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


def _shoot(run: DrugHeatings, guesses: Sequence[float]) -> tuple[dict[str, Any], list[str]]:
    """The corrected schedule (:func:`dosing.question.shooting.corrected`, partial: a dose
    no actuation time meets is a warning, the doses before it kept), with warnings for it
    and for leaky rests."""
    req = run.req
    res, short = corrected(run, guesses, lambda d: _reading(run, run.run(d), d),
                           what="the drug doses",
                           partial=True)
    warnings: list[str] = []
    if short is not None:
        k = short.k
        warnings.append(f"corrected: no actuation time meets dose {k + 1} "
                        f"({req.fractions[k]:.3g} of the load): heating then delivers "
                        f"at most {short.most:.3g}; doses from {k + 1} on are not corrected")
    if not res["actuation_times"]:
        return res, warnings
    return res, warnings + _leak_warnings(req, res, "corrected")


def hold_reading(planner: Any, run: DrugHeatings,
                 tau: float | None) -> tuple[str, list[DrugHoldRow]]:
    """(model, rows) of the hold reading: the doses read off one continuous heating (with
    D0 = 0 the fluid schedule's, else one drug run read off at each cumulative dose)."""
    req = run.req
    load = req.load_ug
    if carried_by_fluid(run.solute):
        model, rows = hold_schedule(planner, req.fluid_schedule())
        return (f"{model} (D0 = 0: drug = fluid on one heating)",
                [DrugHoldRow(**asdict(r), dose_ug=None if load is None
                             else r.dose_fraction * load) for r in rows])
    total = DrugHeatings(req, run.runs, [sum(req.fractions)], run.settings)
    got = read_off(total, [], 0, *first_heating(req, sum(req.fractions)))
    run.count += total.count  # the schedule's runs include its hold reading's
    if isinstance(got, Short):
        raise ParameterError("doses", list(req.fractions), f"summing to below {got.most:.4f}",
                             "one continuous heating releases at most that")
    ends = [got.result.time_to_release(c, after=req.lead) - req.lead
            for c in accumulate(req.fractions)]
    rows, prev = [], 0.0
    for d, c, e in zip(req.fractions, accumulate(req.fractions), ends, strict=True):
        rows.append(DrugHoldRow(dose_fraction=d, cumulative_fraction=c, start=prev, end=e,
                                actuation_time=e - prev,
                                actuation_seconds=None if tau is None else (e - prev) * tau,
                                error_estimate=None,
                                dose_ug=None if load is None else d * load))
        prev = e
    return "full", rows


def plan_drug_schedule(planner: Any, req: DrugScheduleRequest,
                       runs: DrugRuns | None = None) -> DrugScheduleAnswer:
    """Plan ``req``: hold times, the protocol check and the corrected schedule."""
    runs = runs or runs_for(planner)
    run = DrugHeatings(req, runs, req.fractions)
    solute = run.solute
    dry = req.bead_dry_radius_um
    tau = timescale(dry, req.t_end, req.constants).seconds if dry is not None else None
    warnings: list[str] = []
    model, hold = hold_reading(planner, run, tau)
    load = req.load_ug
    guesses = [row.actuation_time for row in hold]
    checked = None
    if req.check_protocol:
        checked = _reading(run, run.run(guesses), guesses)
        warnings += _leak_warnings(req, checked, "protocol check")
    corrected = None
    if req.correct:
        corrected, more = _shoot(run, guesses)
        warnings += more
    with_seconds(tau, checked, corrected)
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
    ans = DrugScheduleAnswer(
        model=model, doses=list(req.fractions),
        doses_ug=None if load is None else [f * load for f in req.fractions], load_ug=load,
        rests=list(req.rests), wait=req.lead, hold=hold, protocol_check=checked,
        corrected=corrected, warnings=warnings, leak_time_10pct=leak_time(solute,
                                                                           req.start_radius),
        effective_diffusivity_cm2_s=d0 * float(solute.hindrance.factor(phi0)),
        timescale_seconds=tau, note=note, interfacial_length=s.interfacial_length,
        bead_dry_radius_um=req.bead_dry_radius_um, truth=truth_text(req),
        uncertainty=unc)
    ans.events = schedule_events(ans, req)
    return ans
