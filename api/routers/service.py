"""GET /health: liveness, warm kernels, the planner's cache and queues."""

from __future__ import annotations

from typing import Any

from fastapi import APIRouter
from fastapi.concurrency import run_in_threadpool

from .. import schemas as s
from ..deps import StateDep
from ..version import package_version

router = APIRouter(tags=["service"])


@router.get("/health", response_model=s.HealthResponse)
async def health(state: StateDep) -> dict[str, Any]:
    """Liveness: 'ok' once the kernels are warm."""
    rep = state.warmup
    planner_info = await run_in_threadpool(state.describe)
    return {"status": "ok" if state.planner is not None else "starting",
            "version": package_version(),
            "kernels_warm": len(rep.warm) if rep else 0,
            "kernels_cold": list(rep.cold) if rep else [],
            "warmup_seconds": rep.seconds if rep else None,
            "planner": planner_info}
