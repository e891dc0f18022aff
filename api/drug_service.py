"""The service layer of drug doses and schedules (requests with a ``drug``).

A drug dose without diffusion is the fluid answer (milliseconds); otherwise drug runs of
the full solver answer it: at once when they are all cached, else as a stored job (202;
poll /v1/validations/drug-dose-<id>, whose result is the answer), so that no HTTP worker
thread waits on a run (issue 22, N1).  A drug schedule is answered at once under the hold
reading with D0 = 0, else as a job (202; poll /v1/validations/schedule-<id>, the queue of
the schedule jobs).
"""

from __future__ import annotations

from typing import Any

from dosing import SolverSettings
from dosing.drug import DrugModel
from dosing.drug_dose import DrugDoseRequest, plan_drug_dose
from dosing.drug_schedule import DrugScheduleRequest, plan_drug_schedule

from . import schemas as s


def _drug(body: Any) -> DrugModel:
    return DrugModel(**body.drug.model_kwargs())


def _constants(c: Any) -> dict[str, Any] | None:
    return None if c is None else c.model_dump(exclude_none=True)


def to_drug_dose_request(body: s.DoseTimeRequest, to_gel: Any) -> DrugDoseRequest:
    """The planner's drug dose request (ParameterError names a bad field)."""
    from solver.errors import ParameterError

    for name in ("dose_volume_ul", "concentration_ug_per_ul"):
        if getattr(body, name) is not None:
            raise ParameterError(name, getattr(body, name), "null with a drug (give "
                                 "dose_fraction of the load or drug_mass_ug)")
    return DrugDoseRequest(
        to_gel(body.gel), body.t_start, body.t_end, _drug(body),
        dose_fraction=body.dose_fraction, drug_mass_ug=body.drug_mass_ug, wait=body.drug.wait,
        wait_seconds=body.drug.wait_seconds, dry_radius_um=body.dry_radius_um,
        swollen_radius_um=body.swollen_radius_um, constants=_constants(body.constants),
        branch=body.branch, settings=SolverSettings(interfacial_length=body.interfacial_length,
                                method=body.validation_method))


def to_drug_schedule_request(body: s.ScheduleRequest, to_gel: Any) -> DrugScheduleRequest:
    """The planner's drug schedule request."""
    rests = body.rests if body.rests is not None or body.rests_seconds is not None \
        else [0.0] * (len(body.doses) - 1)
    return DrugScheduleRequest(
        to_gel(body.gel), body.t_start, body.t_end, _drug(body), doses=tuple(body.doses),
        rests=rests, rests_seconds=body.rests_seconds, wait=body.drug.wait,
        wait_seconds=body.drug.wait_seconds, dry_radius_um=body.dry_radius_um,
        swollen_radius_um=body.swollen_radius_um, constants=_constants(body.constants),
        branch=body.branch, check_protocol=body.check_protocol, correct=body.correct,
        tolerance=body.tolerance,
        settings=SolverSettings(interfacial_length=body.interfacial_length,
                                method=body.validation_method))


def dose_answer(planner: Any, body: s.DoseTimeRequest, to_gel: Any) -> dict[str, Any]:
    """A drug dose's answer (blocking: a drug run takes seconds; cached)."""
    req = to_drug_dose_request(body, to_gel)
    ans = plan_drug_dose(planner, req, validate=body.validate_full)
    return {"status": "answered", "drug": True, **ans.to_dict()}


class RunNotCached(LookupError):
    """A drug run the answer needs is not in the cache (:class:`CachedRuns`)."""


class CachedRuns:
    """A planner's drug runs, cached ones only: a missing run raises RunNotCached instead
    of computing it."""

    def __init__(self, runs: Any) -> None:
        self.runs = runs

    def run(self, sc: Any) -> Any:
        """The cached run for ``sc``, or RunNotCached."""
        hit = self.runs.cached(sc)
        if hit is None:
            raise RunNotCached(sc.key())
        return hit


def dose_now(planner: Any, body: s.DoseTimeRequest, to_gel: Any) -> dict[str, Any] | None:
    """A drug dose's answer when nothing needs a new run (no diffusion, or every run cached),
    else None: the caller queues it as a job (:func:`dose_answer` then runs)."""
    from dosing.drug import runs_for

    req = to_drug_dose_request(body, to_gel)
    try:
        ans = plan_drug_dose(planner, req, runs=CachedRuns(runs_for(planner)),
                             validate=body.validate_full)
    except RunNotCached:
        return None
    return {"status": "answered", "drug": True, **ans.to_dict()}


def schedule_is_quick(body: s.ScheduleRequest, to_gel: Any) -> bool:
    """True for the hold reading of a drug carried by the fluid alone (answered at once)."""
    req = to_drug_schedule_request(body, to_gel)
    from dosing.drug import carried_by_fluid

    return not (req.check_protocol or req.correct) and carried_by_fluid(req.solute)


def schedule_result(planner: Any, body: s.ScheduleRequest, to_gel: Any) -> dict[str, Any]:
    """A drug schedule (blocking; a stored schedule job runs it unless it is quick)."""
    req = to_drug_schedule_request(body, to_gel)
    return {"drug": True, **plan_drug_schedule(planner, req).to_dict()}
