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


def service_state(request: Request) -> ServiceState:
    """The app's shared :class:`ServiceState` (what :func:`get_state` injects), for a route
    that already has a dependency and needs the state only on some requests."""
    return request.app.state.service


async def get_state(request: Request) -> ServiceState:
    """The app's shared :class:`ServiceState`."""
    return service_state(request)


async def get_planner(request: Request) -> Any:
    """The planner (503 until start-up has created it).  It reads the state itself rather
    than depending on :func:`get_state`: each dependency FastAPI solves costs a request
    about 0.03 ms (docs/speed.md sec. 6.1)."""
    planner = service_state(request).planner
    if planner is None:
        raise ServiceUnavailable("the planner is starting or has shut down: retry shortly")
    return planner


StateDep = Annotated[ServiceState, Depends(get_state)]
PlannerDep = Annotated[Any, Depends(get_planner)]
