"""``POST /v1/sensitivity``: Sobol or Morris indices of the dose time, answered at once
(front model; the request's size is bounded so it takes seconds at most), on the analysis
executor (:data:`api.routers.compute.ANALYSIS`), not the compute threads."""

from __future__ import annotations

from typing import Any

from fastapi import APIRouter

from dosing.studies.sensitivity import sensitivity
from dosing.units import PhysicalConstants

from ..safe_route import SafeRoute
from ..sensitivity_schemas import MAX_TRAJECTORIES, SensitivityRequest, SensitivityResponse
from ..service import to_gel
from .compute import ANALYSIS

router = APIRouter(tags=["sensitivity"], route_class=SafeRoute)


def run_sensitivity(body: SensitivityRequest) -> dict[str, Any]:
    """The analysis of one request (blocking)."""
    constants = PhysicalConstants(viscosity_pa_s=body.viscosity_pa_s,
                                  permeability_m2=body.permeability_m2,
                                  polymer_volume_m3=body.polymer_volume_m3)
    res = sensitivity(to_gel(body.gel), body.t_start, body.t_end, body.dose_fraction,
                      [v.model_dump() for v in body.vary], dry_radius_um=body.dry_radius_um,
                      constants=constants, method=body.method, samples=body.samples,
                      seed=body.seed, max_trajectories=MAX_TRAJECTORIES)
    return res.to_dict()


@router.post("/v1/sensitivity", response_model=SensitivityResponse)
async def post_sensitivity(body: SensitivityRequest) -> dict[str, Any]:
    """Global sensitivity of the dose time in seconds (SALib on the front model), on an
    executor of its own (never the threads front doses use; a few queued, then 429)."""
    return await ANALYSIS.run(run_sensitivity, body)
