"""GET /v1/jobs/{id}: one poll route for every kind of job.

A job's id says its kind (``sweep-...``, ``fit-...``, ``schedule-...``, ``drug-dose-...``;
a dose validation's id has no prefix).  This route answers for all of them with the same
body as the kind's own route (/v1/validations/{id}, /v1/fit/jobs/{id}, /v1/sweeps/{id},
which stay), and an unknown id is a 404 naming the kind the id claims.
"""

from __future__ import annotations

from typing import Any

from fastapi import APIRouter, Request
from fastapi.responses import Response

from dosing import UnknownValidationError

from .. import schemas as s
from ..analysis_schemas import EmpiricalFitJobResponse
from ..deps import PlannerDep, StateDep
from ..design_schemas import DesignJobResponse
from ..errors import job_kind
from ..fit_schemas import FitJobResponse, ReleaseFitJobResponse
from ..job_schemas import ValidationJob
from ..safe_route import SafeRoute
from ..service import validation
from .compute import compute
from .design import status as design_status
from .fit import _status as fit_status
from .sweep import SweepStatus, render

router = APIRouter(tags=["jobs"], route_class=SafeRoute)


JobResponse = (ValidationJob | ReleaseFitJobResponse | EmpiricalFitJobResponse | FitJobResponse
               | SweepStatus | DesignJobResponse)


@router.get("/v1/jobs/{job_id}", response_model=JobResponse,
            responses={
                404: {"model": s.ErrorResponse, "description": "no job of that kind with "
                                                               "that id"},
                429: {"model": s.ErrorResponse,
                      "description": "resuming it needs a queue slot"}})
async def job_route(job_id: str, request: Request, state: StateDep,
                    _: PlannerDep) -> Any:
    """Any job's state (validation, schedule, drug dose, fit, sweep); when done, its result
    (the same body as the kind's own poll route)."""
    kind = job_kind(job_id)
    try:
        if kind == "sweep":  # the rendered bytes (a big table is not parsed again here)
            body, media = await render(request, job_id, "json")
            return Response(body, media_type=media)
        if kind == "fit":
            return await compute(fit_status, state, job_id)
        if kind == "design":
            return await compute(design_status, state, job_id)
        return await compute(validation, state, job_id)
    except UnknownValidationError:
        raise UnknownValidationError(job_id, "job_id") from None


