"""FastAPI dependencies: the service state and its planner, injected into the routes.

Routes declare ``planner: PlannerDep`` or ``state: StateDep`` instead of reaching into
``request.app.state``; a test can swap either with ``app.dependency_overrides``.
"""

from __future__ import annotations

from typing import Annotated, Any

from fastapi import Depends, Request

from .errors import ServiceUnavailable
from .service import ServiceState


def get_state(request: Request) -> ServiceState:
    """The app's shared :class:`ServiceState`."""
    return request.app.state.service


def get_planner(state: Annotated[ServiceState, Depends(get_state)]) -> Any:
    """The planner (503 until start-up has created it)."""
    if state.planner is None:
        raise ServiceUnavailable("the planner is starting or has shut down: retry shortly")
    return state.planner


StateDep = Annotated[ServiceState, Depends(get_state)]
PlannerDep = Annotated[Any, Depends(get_planner)]
