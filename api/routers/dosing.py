"""Dosing routes: one dose's actuation time, a multi-dose schedule (200, or 202 + id)."""

from __future__ import annotations

from typing import Any

from fastapi import APIRouter, Request
from fastapi.responses import JSONResponse

from .. import schemas as s
from ..deps import PlannerDep, StateDep, service_state
from ..safe_route import SafeRoute
from ..service import Accepted, dose_time, schedule
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


@router.post("/dose-time", response_model=s.DoseTimeResponse | s.DrugDoseResponse
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


@router.post("/schedule", response_model=s.ScheduleResponse | s.DrugScheduleResponse,
             responses={
    202: {"model": s.PendingResponse, "headers": _LOCATION,
          "description": "queued as a job: poll validation_url"},
    429: _FULL})
async def schedule_route(body: s.ScheduleRequest, state: StateDep, _: PlannerDep) -> Any:
    """A multi-dose schedule, whatever its cell: the hold reading at once when asked alone;
    protocol check and correction (and every batch's, drug's or protocol's) as a job."""
    return answer_or_pending(await compute(schedule, state, body))
