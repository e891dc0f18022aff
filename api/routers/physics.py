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
    """The preset gels with their parameters and fold temperatures, and the stored fitted
    gels (``thermogel fit ... --save NAME`` or POST /v1/fit/* with ``save``)."""
    return {**await compute(presets_answer), "fitted": await compute(fitted_gels_answer)}


def fitted_gels_answer() -> list[dict[str, Any]]:
    """The stored fitted gels with their folds (blocking: reads the store)."""
    from dosing.fits.gel_store import GelStore
    from solver.equilibrium import folds
    from solver.gel import Gel

    out = []
    for g in GelStore().summaries():
        try:
            g["folds"] = [f.to_dict() for f in folds(Gel.from_dict(g["gel"]))]
        except Exception:  # a fitted gel whose fold search fails is listed without folds
            g["folds"] = []
        out.append(g)
    return out


@router.post("/equilibrium", response_model=s.EquilibriumResponse)
async def equilibrium(req: s.EquilibriumRequest) -> dict[str, Any]:
    """Every free-swelling equilibrium at a temperature (eq. EqlEqn), and the folds."""
    return await compute(equilibrium_answer, req)


@router.post("/classify", response_model=s.ClassifyResponse)
async def classify(req: s.ClassifyRequest) -> dict[str, Any]:
    """What a temperature jump does: smooth, front, delayed front or spinodal."""
    return await compute(classify_answer, req)
