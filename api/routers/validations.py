"""GET /v1/validations/{id}: a full-solver job's state, and its result when done."""

from __future__ import annotations

from typing import Any

from fastapi import APIRouter

from dosing import UnknownValidationError

from .. import schemas as s
from ..deps import PlannerDep, StateDep
from ..errors import job_kind
from ..job_schemas import ValidationJob
from ..safe_route import SafeRoute
from ..service import validation
from .compute import compute

router = APIRouter(prefix="/v1", tags=["dosing"], route_class=SafeRoute)


@router.get("/validations/{validation_id}", response_model=ValidationJob, responses={
    404: {"model": s.ErrorResponse, "description": "unknown id"},
    429: {"model": s.ErrorResponse, "description": "resuming it needs a queue slot"}})
async def validation_route(validation_id: str, state: StateDep, _: PlannerDep) -> dict[str, Any]:
    """State of a full-solver job (a dose validation or a schedule job, both kept in the
    cache across restarts); when done, the full solver's answer (typed by ``kind``).  A fit
    or sweep id is a 404 pointing to /v1/jobs/{id}."""
    if job_kind(validation_id) in ("fit", "sweep"):
        raise UnknownValidationError(validation_id, "validation_id",
                                     f"poll /v1/jobs/{validation_id}")
    return await compute(validation, state, validation_id)
