"""Physics routes (no planner): the preset gels, equilibria (eq. EqlEqn), jump classes."""

from __future__ import annotations

from typing import Any

from fastapi import APIRouter

from .. import schemas as s
from ..safe_route import SafeRoute
from ..service import classify_answer, equilibrium_answer, presets_answer
from .compute import compute

router = APIRouter(prefix="/v1", tags=["physics"], route_class=SafeRoute)


@router.get("/gels", response_model=s.GelsResponse)
async def gels() -> dict[str, Any]:
    """The preset gels with their parameters and fold temperatures."""
    return await compute(presets_answer)


@router.post("/equilibrium", response_model=s.EquilibriumResponse)
async def equilibrium(req: s.EquilibriumRequest) -> dict[str, Any]:
    """Every free-swelling equilibrium at a temperature (eq. EqlEqn), and the folds."""
    return await compute(equilibrium_answer, req)


@router.post("/classify", response_model=s.ClassifyResponse)
async def classify(req: s.ClassifyRequest) -> dict[str, Any]:
    """What a temperature jump does: smooth, front, delayed front or spinodal."""
    return await compute(classify_answer, req)
