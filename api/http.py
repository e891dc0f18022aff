"""The HTTP planner service: the FastAPI app factory over ``dosing`` and ``solver``.

Routes live in :mod:`api.routers` (one module per area), reach the planner through the
dependencies of :mod:`api.deps`, and do their work in :mod:`api.service`; every blocking
call runs in the threadpool, never on the event loop.  Errors map to statuses through one
table (:mod:`api.errors`): input errors are 422 naming the field (pydantic's own checks,
strict and finite, and the solver's ``ParameterError`` / ``NotApplicableError``); a
numerical failure (``SolverError``) is a 422 saying so; a full queue is 429 with
Retry-After; an unknown validation id is 404; a body over the limit is 413, refused
before it is parsed.
"""

from __future__ import annotations

import os
from contextlib import asynccontextmanager
from typing import Any

from fastapi import APIRouter, FastAPI
from fastapi.concurrency import run_in_threadpool
from fastapi.routing import APIRoute

from dosing.runs.jobs import exit_with_parent

from . import docs_pages, errors, guard, openapi_spec
from .auth import HostCheck, TokenAuth
from .memory import ReleaseAfterLarge
from .routers import (
    analysis,
    design,
    dosing,
    fit,
    jobs,
    page,
    physics,
    service,
    sweep,
    validations,
)
from .routers import sensitivity as sensitivity_routes
from .service import ServiceState
from .version import package_version

DEFAULT_MAX_BODY = 1 << 20  # bytes: the largest valid request is a few kB
SUPERVISOR_ENV = "THERMOGEL_SUPERVISOR_PID"


def create_app(planner: Any = None, *, cache_path: str | None = None, warm: bool = True,
               max_pending: int | None = None, executor: Any = None,
               max_body_bytes: int = DEFAULT_MAX_BODY,
               lease_seconds: float | None = None, api_token: str | None = None,
               allowed_hosts: list[str] | None = None) -> FastAPI:
    """The planner service.

    ``planner``: a ``dosing.Planner`` to serve (the caller closes it); by default one is
    created at start-up on ``cache_path`` (the embedded SQLite cache) with ``executor``,
    ``max_pending`` (validations queued or running) and ``lease_seconds`` (how long a
    crashed server's claim on a run outlives it) and closed at shutdown, its process pool
    stopped.  ``warm``: warm every numba kernel first.  ``max_body_bytes``: larger request
    bodies are refused with 413 before they are read.  ``api_token``: every route but
    /health needs ``Authorization: Bearer <token>`` (:mod:`api.auth`).  ``allowed_hosts``:
    Host headers accepted (:class:`api.auth.HostCheck`: a name with any port, or
    ``name:port``; default any; ``thermogel serve`` on loopback defaults to
    ``api.auth.LOOPBACK_HOSTS``).
    """
    options: dict[str, Any] = {"cache_path": cache_path}
    if executor is not None:
        options["executor"] = executor
    if max_pending is not None:
        options["max_pending"] = max_pending
    if lease_seconds is not None:
        options["lease_seconds"] = lease_seconds
    state = ServiceState(planner=planner, options=options)

    @asynccontextmanager
    async def lifespan(_: FastAPI):
        unwatch = errors.watch_faults(state)  # /health degraded on a logged cache failure
        await run_in_threadpool(state.start, warm)
        try:
            yield
        finally:
            await run_in_threadpool(state.stop)
            unwatch()

    app = guard.GuardedFastAPI(
        title="thermogel planner", version=package_version(), lifespan=lifespan,
        max_body_size=max_body_bytes,
        description="Plan drug release from thermo-responsive gel beads (Butler & "
                    "Montenegro-Johnson). Temperatures in K; dimensionless lengths in dry "
                    "radii and times in units of tau (eq. timescale).",
        responses=openapi_spec.APP_RESPONSES, **docs_pages.offline_kwargs())
    docs_pages.install(app)  # /docs and /redoc with their assets from this server
    app.state.service = state
    errors.install(app)
    guard.add(app)
    if api_token:
        app.add_middleware(TokenAuth, token=api_token)
    if allowed_hosts:
        app.add_middleware(HostCheck, allowed=allowed_hosts)
    app.add_middleware(ReleaseAfterLarge)  # a large body's memory back to the system (R7)
    for router in (service.router, physics.router, dosing.router, validations.router,
                   fit.router, sweep.router, page.router, sensitivity_routes.router,
                   design.router, jobs.router, analysis.router):
        add_routes(app, router)
    return app


def add_routes(app: FastAPI, router: APIRouter) -> None:
    """Register ``router``'s routes on the app's own router, one by one (as FastAPI's
    ``include_router`` did before 0.116).  ``include_router`` now keeps each router as one
    route that matches its routes on every request, twice, under a body limit of its own:
    with nine routers that cost about 0.1 ms of a dose request's 1 ms (benchmarks/speed.py
    ``load``).  The routes, their OpenAPI description and the app's responses, dependency
    overrides and body limit are the same (tests/test_api_routes_flat.py)."""
    for r in router.routes:
        if not isinstance(r, APIRoute):
            raise TypeError(f"{r!r}: only API routes are registered route by route")
        app.router.add_api_route(
            r.path, r.endpoint, response_model=r.response_model, status_code=r.status_code,
            tags=r.tags, dependencies=r.dependencies, summary=r.summary,
            description=r.description, response_description=r.response_description,
            responses=r.responses, deprecated=r.deprecated, methods=r.methods,
            operation_id=r.operation_id, response_model_include=r.response_model_include,
            response_model_exclude=r.response_model_exclude,
            response_model_by_alias=r.response_model_by_alias,
            response_model_exclude_unset=r.response_model_exclude_unset,
            response_model_exclude_defaults=r.response_model_exclude_defaults,
            response_model_exclude_none=r.response_model_exclude_none,
            include_in_schema=r.include_in_schema, response_class=r.response_class,
            name=r.name, route_class_override=type(r), callbacks=r.callbacks,
            openapi_extra=r.openapi_extra,
            generate_unique_id_function=r.generate_unique_id_function)


def app_from_env() -> FastAPI:
    """App factory for ``uvicorn --factory`` (``thermogel serve``): options from the environment
    (read once, through :func:`dosing.settings.settings`).

    THERMOGEL_CACHE (cache file), THERMOGEL_MAX_PENDING (validations queued or running),
    THERMOGEL_MAX_BODY (bytes), THERMOGEL_LEASE_SECONDS, THERMOGEL_WARMUP ('0' skips the
    warm-up), THERMOGEL_API_TOKEN (the bearer token), THERMOGEL_ALLOWED_HOSTS (comma-
    separated Host names), THERMOGEL_RUN_SECONDS (the wall-clock budget of one full-solver run,
    read by dosing.runs.scenario.run_budget; default 600).  A uvicorn worker process
    (``--workers`` > 1) ends itself when the supervisor it was started by is gone.
    """
    from dosing.settings import settings

    env = settings()  # THERMOGEL_* (dosing.settings: one Settings object)
    supervisor = env.supervisor_pid
    if supervisor and supervisor != os.getpid():
        exit_with_parent(supervisor)
    return create_app(cache_path=str(env.cache) if env.cache else None,
                      max_pending=env.max_pending or None,
                      max_body_bytes=env.max_body or DEFAULT_MAX_BODY,
                      lease_seconds=env.lease_seconds or None,
                      warm=env.warmup, api_token=env.api_token or None,
                      allowed_hosts=env.hosts)
