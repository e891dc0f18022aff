"""FastAPI dependencies: the service state and its planner, injected into the routes.

Routes declare ``planner: PlannerDep`` or ``state: StateDep`` instead of reaching into
``request.app.state``; a test can swap either with ``app.dependency_overrides``.  Both are
``async`` so that FastAPI never needs a threadpool thread to resolve them (/health answers
while every thread computes).
"""

from __future__ import annotations

from typing import Annotated, Any

from fastapi import Depends, Request

from .errors import ServiceUnavailable
from .service import ServiceState


async def get_state(request: Request) -> ServiceState:
    """The app's shared :class:`ServiceState`."""
    return request.app.state.service


async def get_planner(state: Annotated[ServiceState, Depends(get_state)]) -> Any:
    """The planner (503 until start-up has created it)."""
    if state.planner is None:
        raise ServiceUnavailable("the planner is starting or has shut down: retry shortly")
    return state.planner


StateDep = Annotated[ServiceState, Depends(get_state)]
PlannerDep = Annotated[Any, Depends(get_planner)]
