"""GET /v1/validations/{id}: a full-solver job's state, and its result when done."""

from __future__ import annotations

from typing import Any

from fastapi import APIRouter

from .. import schemas as s
from ..deps import PlannerDep, StateDep
from ..safe_route import SafeRoute
from ..service import validation
from .compute import compute

router = APIRouter(prefix="/v1", tags=["dosing"], route_class=SafeRoute)


@router.get("/validations/{validation_id}", response_model=s.ValidationResponse, responses={
    404: {"model": s.ErrorResponse, "description": "unknown id"},
    429: {"model": s.ErrorResponse, "description": "resuming it needs a queue slot"}})
async def validation_route(validation_id: str, state: StateDep, _: PlannerDep) -> dict[str, Any]:
    """State of a full-solver job (a dose validation or a schedule job, both kept in the
    cache across restarts); when done, the full solver's answer."""
    return await compute(validation, state, validation_id)
