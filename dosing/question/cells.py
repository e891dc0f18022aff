"""The registry of cells: which code answers each payload x population x heating x question.

``CELLS`` (like scipy's ``METHODS``) maps ``Request.cell_key`` to one :class:`Cell`: ``build``
(the cell's planner request, validated), ``now`` (no wait on a new full-solver run: a result,
``Pending``, or None: a job) and ``run`` (blocking).  All 16 cells answer; nothing else
branches on an axis (docs/architecture.md, "Where to add ...")."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from solver.errors import NotApplicableError, ParameterError

from ..answers import Pending
from .result import DoseResult, ScheduleResult


@dataclass(frozen=True)
class Cell:
    """One cell's code: ``build(request)``, ``now(planner, request)``, ``run(planner,
    request)`` (module doc)."""

    build: Callable[[Any], Any]
    now: Callable[[Any, Any], Any]
    run: Callable[[Any, Any], Any]


def _never(planner: Any, request: Any) -> None:
    """A cell with no answer short of its runs: always a job."""
    return None


# ------------------------------------------------------------------ builders
def _dose_fields(request: Any) -> dict[str, Any]:
    q = request.question
    return {"dose_fraction": q.fraction, "dose_volume_ul": q.volume_ul,
            "drug_mass_ug": q.drug_mass_ug,
            "concentration_ug_per_ul": q.concentration_ug_per_ul}


def _fluid_dose(request: Any) -> Any:
    from ..request import DoseRequest

    return DoseRequest(**request.case_fields(), **request.heating.fields(),
                       **_dose_fields(request), **request.population.fields())


def _drug_dose(request: Any) -> Any:
    from ..payload.release import DrugDoseRequest

    q = request.question
    for name, value in (("dose_volume_ul", q.volume_ul),
                        ("concentration_ug_per_ul", q.concentration_ug_per_ul)):
        if value is not None:
            raise ParameterError(name, value, "null with a drug (give dose_fraction of the "
                                 "load or drug_mass_ug)")
    return DrugDoseRequest(**request.case_fields(), **request.heating.fields(),
                           **request.payload.fields(), dose_fraction=q.fraction,
                           drug_mass_ug=q.drug_mass_ug)


def _drug_one_dose(request: Any) -> Any:
    _one_medium(request)
    return _drug_dose(request)


def _drug_batch_dose(request: Any) -> Any:
    """The reference bead's drug dose, its batch's medium checked before any run."""
    from ..population.medium import bead_count, medium_volume_ml

    p = request.payload
    if (p.medium_volume_ml is None) != (p.bead_count is None):
        name = "bead_count" if p.bead_count is None else "medium_volume_ml"
        raise ParameterError(name, None, "given with " + ("medium_volume_ml" if
                             name == "bead_count" else "bead_count") + " (both or neither)")
    if p.medium_volume_ml is not None:
        medium_volume_ml(p.medium_volume_ml)
        bead_count(p.bead_count)
    if request.question.fraction is None:
        raise ParameterError("dose_fraction", None, "a fraction of the batch's load (0-1)")
    req = _drug_dose(request)
    if req.drug.release_volume_ul is not None:
        raise ParameterError("drug.release_volume_ul", req.drug.release_volume_ul,
                             "null for a batch (give medium_volume_ml and bead_count)")
    if req.lead > 0.0:
        raise ParameterError("drug.wait", p.wait if p.wait is not None else p.wait_seconds,
                             "0 or null for a batch (a wait at T_start is not planned for "
                             "batches)")
    return req


def _one_medium(request: Any) -> None:
    """A shared medium is a drug batch's: refused elsewhere, naming the field."""
    for name in ("medium_volume_ml", "bead_count"):
        value = getattr(request.payload, name, None)
        if value is not None:
            raise ParameterError(name, value, "null without a drug and a size_distribution "
                                 "(the medium a drug batch shares)")


def _fluid_schedule(request: Any) -> Any:
    from ..request import ScheduleRequest

    q = request.question
    if q.doses_ug is not None:
        raise ParameterError("doses_ug", q.doses_ug, "null for a fluid schedule (doses in ug "
                             "are a drug's: give a drug)")
    return ScheduleRequest(**request.case_fields(), **request.heating.fields(),
                           doses=tuple(q.doses or ()), **q.fields())


def _batch_schedule(request: Any) -> Any:
    from ..population.cycles import reference_fields, schedule_sizes
    from ..request import ScheduleRequest

    q = request.question
    sizes = request.population.sizes
    case = {**request.case_fields(), **reference_fields(sizes, request.dry_radius_um,
                                                        request.swollen_radius_um)}
    req = ScheduleRequest(**case, **request.heating.fields(), doses=tuple(q.doses or ()),
                          **q.fields())
    schedule_sizes(req, sizes)
    return req


def _drug_schedule(request: Any) -> Any:
    from ..payload.cycles import DrugScheduleRequest

    q = request.question
    _one_medium(request)
    return DrugScheduleRequest(**request.case_fields(), **request.heating.fields(),
                               **request.payload.fields(), doses=q.doses,
                               doses_ug=q.doses_ug, **q.fields())


def _drug_batch_schedule(request: Any) -> Any:
    """A drug batch's schedule: into a perfect sink, doses of the batch's load, no wait."""
    from ..payload.cycles import DrugScheduleRequest
    from ..population.cycles import reference_fields, schedule_sizes

    q, p = request.question, request.payload
    _one_medium(request)  # a shared medium is planned for a drug batch's dose only
    if q.doses_ug is not None:
        raise ParameterError("doses_ug", q.doses_ug, "null for a batch (give doses as "
                             "fractions of the batch's load)")
    sizes = request.population.sizes
    case = {**request.case_fields(), **reference_fields(sizes, request.dry_radius_um,
                                                        request.swollen_radius_um)}
    req = DrugScheduleRequest(**case, **request.heating.fields(), **p.fields(),
                              doses=q.doses, **q.fields())
    if req.lead > 0.0:
        raise ParameterError("drug.wait", p.wait if p.wait is not None else p.wait_seconds,
                             "0 or null for a batch (a wait at T_start is not planned for "
                             "batches)")
    if req.drug.release_volume_ul is not None:
        raise ParameterError("drug.release_volume_ul", req.drug.release_volume_ul,
                             "null for a batch's schedule (a perfect sink)")
    schedule_sizes(req, sizes)
    return req


# ------------------------------------------------------------------ fluid doses
def _bead_now(planner: Any, request: Any) -> DoseResult | Pending:
    out = planner.answer(request.planned, validate=request.validate)
    if isinstance(out, Pending):
        return out
    return DoseResult(request.cell_name, out.answer, validation_id=out.validation_id)


def _bead_run(planner: Any, request: Any) -> DoseResult:
    return DoseResult(request.cell_name, planner.dose(request.planned,
                                                      validate=request.validate))


def _with_batch(bead: Any, batch: Any) -> Any:
    """The mean bead's answer (or its ``Pending``) with the batch's section beside it."""
    if not isinstance(bead, Pending):
        bead.batch = batch
    return bead


def _batch_jump_now(planner: Any, request: Any) -> DoseResult | Pending | None:
    from ..population.front import batch_answer

    if request.validate:  # the truth per interfacial-length band: a job
        return None
    try:
        batch = batch_answer(request.planned)
    except NotApplicableError:  # no front model: the truth per band (a job)
        return None
    return _with_batch(_bead_now(planner, request), batch)


def _batch_jump_run(planner: Any, request: Any) -> DoseResult:
    from ..population.bands import validated_batch
    from ..population.front import batch_answer

    req = request.planned
    try:
        batch = validated_batch(planner, req) if request.validate else batch_answer(req)
    except NotApplicableError:
        batch = validated_batch(planner, req)
    return _with_batch(_bead_run(planner, request), batch)


def _batch_protocol_now(planner: Any, request: Any) -> DoseResult | Pending | None:
    """The reduced model at every node (milliseconds); a node outside its region needs
    the full solver: from the cache when every run is there, else None (a job)."""
    from ..population.curves import OutsideRegion, batch_protocol_answer

    try:
        batch = batch_protocol_answer(request.planned, validate=request.validate)
    except OutsideRegion:
        batch = batch_protocol_answer(request.planned, validate=request.validate,
                                      planner=planner, wait=False)
        if batch is None:
            return None
    return _with_batch(_bead_now(planner, request), batch)


def _batch_protocol_run(planner: Any, request: Any) -> DoseResult:
    from ..population.curves import batch_protocol_answer

    batch = batch_protocol_answer(request.planned, validate=request.validate,
                                  planner=planner)
    return _with_batch(_bead_run(planner, request), batch)


# ------------------------------------------------------------------ drug doses
def _drug_now(planner: Any, request: Any) -> DoseResult | None:
    from ..payload.release import drug_dose_now

    ans = drug_dose_now(planner, request.planned, validate=request.validate)
    return None if ans is None else DoseResult(request.cell_name, ans)


def _drug_run(planner: Any, request: Any) -> DoseResult:
    from ..payload.release import plan_drug_dose

    return DoseResult(request.cell_name, plan_drug_dose(planner, request.planned,
                                                        validate=request.validate))


def _drug_batch_run(planner: Any, request: Any) -> DoseResult:
    from ..population.medium import drug_batch_dose

    p = request.payload
    return DoseResult(request.cell_name, None, batch=drug_batch_dose(
        request.planned, request.population.sizes, p.medium_volume_ml, p.bead_count))


# ------------------------------------------------------------------ schedules
def _schedule_now(planner: Any, request: Any) -> ScheduleResult | None:
    ans = planner.schedule_now(request.planned)
    return None if ans is None else ScheduleResult(request.cell_name, ans)


def _schedule_run(planner: Any, request: Any) -> ScheduleResult:
    return ScheduleResult(request.cell_name, planner.schedule(request.planned))


def _batch_schedule_run(planner: Any, request: Any) -> ScheduleResult:
    from ..population.cycles import batch_schedule_with

    return ScheduleResult(request.cell_name, batch_schedule_with(
        planner, request.planned, request.population.sizes), tags={"batch": True})


def _drug_batch_schedule_run(planner: Any, request: Any) -> ScheduleResult:
    from ..population.cycles import drug_batch_schedule_with

    return ScheduleResult(request.cell_name, drug_batch_schedule_with(
        planner, request.planned, request.population.sizes), tags={"batch": True})


def _drug_schedule_now(planner: Any, request: Any) -> ScheduleResult | None:
    from ..payload.drug import carried_by_fluid

    req = request.planned
    if req.check_protocol or req.correct or not carried_by_fluid(req.solute):
        return None  # drug runs: a job
    return _drug_schedule_run(planner, request)


def _drug_schedule_run(planner: Any, request: Any) -> ScheduleResult:
    from ..payload.cycles import plan_drug_schedule

    return ScheduleResult(request.cell_name, plan_drug_schedule(planner, request.planned))


_BEAD = Cell(_fluid_dose, _bead_now, _bead_run)
_DRUG = Cell(_drug_one_dose, _drug_now, _drug_run)
_DRUG_BATCH = Cell(_drug_batch_dose, _never, _drug_batch_run)
_DRUG_BATCH_SCHEDULE = Cell(_drug_batch_schedule, _never, _drug_batch_schedule_run)

CELLS: dict[tuple[str, str, str, str], Cell] = {
    ("fluid", "one", "jump", "dose"): _BEAD,
    ("fluid", "one", "protocol", "dose"): _BEAD,
    ("fluid", "batch", "jump", "dose"): Cell(_fluid_dose, _batch_jump_now, _batch_jump_run),
    ("fluid", "batch", "protocol", "dose"): Cell(_fluid_dose, _batch_protocol_now,
                                                 _batch_protocol_run),
    ("drug", "one", "jump", "dose"): _DRUG,
    ("drug", "one", "protocol", "dose"): _DRUG,
    ("drug", "batch", "jump", "dose"): _DRUG_BATCH,
    ("drug", "batch", "protocol", "dose"): _DRUG_BATCH,
    ("fluid", "one", "jump", "schedule"): Cell(_fluid_schedule, _schedule_now, _schedule_run),
    ("fluid", "one", "protocol", "schedule"): Cell(_fluid_schedule, _never, _schedule_run),
    ("fluid", "batch", "jump", "schedule"): Cell(_batch_schedule, _never, _batch_schedule_run),
    ("fluid", "batch", "protocol", "schedule"): Cell(_batch_schedule, _never,
                                                     _batch_schedule_run),
    ("drug", "one", "jump", "schedule"): Cell(_drug_schedule, _drug_schedule_now,
                                              _drug_schedule_run),
    ("drug", "one", "protocol", "schedule"): Cell(_drug_schedule, _drug_schedule_now,
                                                  _drug_schedule_run),
    ("drug", "batch", "jump", "schedule"): _DRUG_BATCH_SCHEDULE,
    ("drug", "batch", "protocol", "schedule"): _DRUG_BATCH_SCHEDULE,
}


def cell_for(key: tuple[str, str, str, str]) -> Cell:
    """The cell of ``key`` (every combination of the axes has one)."""
    return CELLS[key]
