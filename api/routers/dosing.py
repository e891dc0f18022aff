"""Dosing routes: one dose's actuation time, a multi-dose schedule (200, or 202 + id)."""

from __future__ import annotations

from typing import Any

from fastapi import APIRouter, Request
from fastapi.responses import JSONResponse

from solver.errors import ParameterError

from .. import schemas as s
from .. import stored_jobs
from ..deps import PlannerDep, StateDep, service_state
from ..drug_schemas import DrugDoseResponse, DrugScheduleResponse
from ..safe_route import SafeRoute
from ..service import Accepted, dose_time, schedule, to_schedule_request
from .compute import compute

router = APIRouter(prefix="/v1", tags=["dosing"], route_class=SafeRoute)

_FULL = {"model": s.ErrorResponse, "description": "queue full: the message says which",
         "headers": {"Retry-After": {"description": "seconds to wait",
                                     "schema": {"type": "integer"}}}}
_LOCATION = {"Location": {"description": "the validation_url to poll",
                          "schema": {"type": "string"}}}


def answer_or_pending(out: dict[str, Any] | Accepted) -> Any:
    """An answer (200, the route's model), or 202 with the poll fields and a Location."""
    if not isinstance(out, Accepted):
        return out
    return JSONResponse(s.PendingResponse(**out.to_dict()).model_dump(), status_code=202,
                        headers={"Location": out.validation_url})


@router.post("/dose-time", response_model=s.DoseTimeResponse | DrugDoseResponse
             | s.ProtocolDoseResponse, responses={
    202: {"model": s.PendingResponse, "headers": _LOCATION,
          "description": "needs the full solver: poll validation_url, then ask again (a "
                         "drug dose: the validation's result is the answer)"},
    429: _FULL})
async def dose(body: s.DoseTimeRequest, planner: PlannerDep, request: Request) -> Any:
    """How long to heat a bead to release a dose (front model at once, or 202; a drug dose
    whose runs are not cached is a job: 202, its validation's result is the answer)."""
    # one dependency: the service's busiest route (docs/speed.md sec. 6.1)
    return answer_or_pending(await compute(dose_time, planner, body, service_state(request)))


@router.post("/schedule", response_model=s.ScheduleResponse | DrugScheduleResponse,
             responses={
    202: {"model": s.PendingResponse, "headers": _LOCATION,
          "description": "queued as a job: poll validation_url"},
    429: _FULL})
async def schedule_route(body: s.ScheduleRequest, state: StateDep, _: PlannerDep) -> Any:
    """A multi-dose schedule: hold times at once; protocol check and correction as a job
    (a batch's, with a size_distribution: always a job)."""
    if body.size_distribution is not None:
        return answer_or_pending(await compute(batch_schedule, state, body))
    return answer_or_pending(await compute(schedule, state, body))


# ------------------------------------------------- a batch's schedule (issue 26)
BATCH_SCHEDULE_NOTE = (
    "A batch's schedule runs every size of its quadrature on the full solver through the "
    "shooting (a stored job). Poll validation_url; once done, its result is the answer.")


def _batch_request(body: s.ScheduleRequest) -> tuple[Any, dict[str, Any]]:
    """The planner's schedule request and the batch (ParameterError names a bad field)."""
    from dosing.batch_schedule import reference_fields, schedule_sizes

    if body.drug is not None:
        raise ParameterError("size_distribution", "a batch", "null with a drug (a drug "
                             "batch's schedule is not built yet)")
    dist = body.size_distribution.model_dump(exclude_none=True)
    req = to_schedule_request(body.model_copy(update=reference_fields(
        dist, body.dry_radius_um, body.swollen_radius_um)))
    schedule_sizes(req, dist)
    return req, dist


def batch_schedule(state: Any, body: s.ScheduleRequest) -> Accepted:
    """A batch's schedule as a stored job, its request checked first (422 naming the
    field)."""
    _batch_request(body)
    return Accepted(stored_jobs.submit(state, "batch-schedule", body), BATCH_SCHEDULE_NOTE)


def _batch_schedule_result(planner: Any, body: s.ScheduleRequest) -> dict[str, Any]:
    from dosing.batch_schedule import batch_schedule_with

    req, dist = _batch_request(body)
    return {"batch": True, **batch_schedule_with(planner, req, dist).to_dict()}


stored_jobs.register(stored_jobs.JobKind("batch-schedule", s.ScheduleRequest,
                                         _batch_schedule_result))
