"""GET /health: liveness, warm kernels, the planner's cache and queues."""

from __future__ import annotations

import asyncio
import contextlib
from typing import Any

from fastapi import APIRouter

from .. import schemas as s
from ..deps import StateDep
from ..safe_route import SafeRoute
from ..version import package_version

router = APIRouter(tags=["service"], route_class=SafeRoute)


PROBE_WAIT_S = 0.1  # how long /health waits for its look at the cache file (else the last count)


@router.get("/health", response_model=s.HealthResponse)
async def health(state: StateDep) -> dict[str, Any]:
    """Liveness: 'ok' once the kernels are warm; 'degraded' after a server fault (a full
    disk, a malformed cache), with why.  Answered on the event loop with no lock the
    compute threads hold; its look at the cache file runs on a thread of its own and is
    waited for at most 0.1 s (else the last count is shown)."""
    rep = state.warmup
    probe = state.probe()
    if probe is not None:
        with contextlib.suppress(asyncio.TimeoutError, Exception):
            await asyncio.wait_for(asyncio.shield(asyncio.wrap_future(probe)), PROBE_WAIT_S)
    planner_info = state.describe()
    fault = state.fault()
    status = "starting" if state.planner is None else "degraded" if fault else "ok"
    if fault:
        planner_info["degraded_because"] = fault
    return {"status": status,
            "version": package_version(),
            "kernels_warm": len(rep.warm) if rep else 0,
            "kernels_cold": list(rep.cold) if rep else [],
            "warmup_seconds": rep.seconds if rep else None,
            "planner": planner_info}
