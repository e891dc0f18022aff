"""The HTTP planner service: a FastAPI app with versioned routes over ``dosing`` and ``solver``.

Routes, error mapping and the app factory; the work is in :mod:`api.service`.  Every
blocking call (planner, equilibria, classifier) runs in the threadpool, never on the event
loop.  Input errors are 422 naming the field: pydantic's own checks, and the solver's
``ParameterError`` / ``NotApplicableError`` mapped to the same shape; a numerical failure
(``SolverError``) is a 422 saying so, or a failed validation; a full queue is 429 with
Retry-After; an unknown validation id is 404.
"""

from __future__ import annotations

import math
import os
import re
from collections.abc import Callable
from contextlib import asynccontextmanager
from importlib.metadata import PackageNotFoundError, version
from typing import Any

from fastapi import FastAPI, Request
from fastapi.concurrency import run_in_threadpool
from fastapi.responses import JSONResponse

from dosing import QueueFullError, UnknownValidationError
from solver.errors import NotApplicableError, ParameterError, SolverError

from . import schemas as s
from .routers import fit as fit_routes
from .routers import page as page_routes
from .routers import sweep as sweep_routes
from .service import (
    ServiceState,
    classify_answer,
    dose_time,
    equilibrium_answer,
    presets_answer,
    schedule,
    solver_guard,
    validation,
)

RETRY_AFTER_SECONDS = 5


def _version() -> str:
    try:
        return version("thermogel")
    except PackageNotFoundError:
        return "unknown"


# ----------------------------------------------------------------------------- errors

def _guarded(fn: Callable[..., Any], *args: Any) -> Any:
    with solver_guard():
        return fn(*args)


async def compute(fn: Callable[..., Any], *args: Any) -> Any:
    """Run a blocking physics or planner call in the threadpool, under :func:`solver_guard`."""
    return await run_in_threadpool(_guarded, fn, *args)


def _loc(name: str | None) -> list[str | int]:
    """['body', ...] from a dotted field name with indices: 'doses[1]' -> body, doses, 1."""
    out: list[str | int] = ["body"]
    for part in re.findall(r"[^.\[\]]+", name or ""):
        out.append(int(part) if part.isdigit() else part)
    return out


def _error(status: int, loc: list[str | int], msg: str, kind: str, **extra: Any) -> JSONResponse:
    item = {"loc": loc, "msg": msg, "type": kind, **extra}
    return JSONResponse({"detail": [item]}, status_code=status)


def _install_error_handlers(app: FastAPI) -> None:
    @app.exception_handler(ParameterError)
    async def _parameter(_: Request, exc: ParameterError) -> JSONResponse:
        return _error(422, _loc(exc.field), str(exc), "parameter_error", valid=exc.valid)

    @app.exception_handler(NotApplicableError)
    async def _not_applicable(_: Request, exc: NotApplicableError) -> JSONResponse:
        return _error(422, _loc(getattr(exc, "field", None)), str(exc), "not_applicable")

    @app.exception_handler(SolverError)
    async def _solver(_: Request, exc: SolverError) -> JSONResponse:
        return _error(422, ["body"], f"the solver could not answer this scenario: {exc}",
                      "solver_error")

    @app.exception_handler(QueueFullError)
    async def _full(_: Request, exc: QueueFullError) -> JSONResponse:
        retry = max(1, math.ceil(getattr(exc, "retry_after", RETRY_AFTER_SECONDS)))
        return JSONResponse({"detail": str(exc)}, status_code=429,
                            headers={"Retry-After": str(retry)})

    @app.exception_handler(UnknownValidationError)
    async def _unknown(_: Request, exc: UnknownValidationError) -> JSONResponse:
        return _error(404, ["path", "validation_id"], f"no validation with id {exc.args[0]!r} "
                      "(schedule jobs are kept in memory and end with a restart)", "not_found")


def create_app(planner: Any = None, *, cache_path: str | None = None, warm: bool = True,
               max_pending: int | None = None, executor: Any = None) -> FastAPI:
    """The planner service.

    ``planner``: a ``dosing.Planner`` to serve (the caller closes it); by default one is
    created at start-up on ``cache_path`` (the embedded SQLite cache) with ``executor`` and
    ``max_pending`` and closed at shutdown.  ``warm``: warm every numba kernel first.
    """
    options: dict[str, Any] = {"cache_path": cache_path}
    if executor is not None:
        options["executor"] = executor
    if max_pending is not None:
        options["max_pending"] = max_pending
    state = ServiceState(planner=planner, options=options)

    @asynccontextmanager
    async def lifespan(_: FastAPI):  # noqa: ANN202
        await run_in_threadpool(state.start, warm)
        try:
            yield
        finally:
            await run_in_threadpool(state.stop)

    app = FastAPI(
        title="thermogel planner", version=_version(), lifespan=lifespan,
        description="Plan drug release from thermo-responsive gel beads (Butler & "
                    "Montenegro-Johnson). Temperatures in K; dimensionless lengths in dry "
                    "radii and times in units of tau (eq. timescale).",
        responses={400: {"model": s.ErrorResponse, "description": "unreadable body"},
                   422: {"model": s.ErrorResponse, "description": "bad input; loc names it"}})
    app.state.service = state
    _install_error_handlers(app)
    _physics_routes(app)
    _dosing_routes(app)
    app.include_router(sweep_routes.router)
    app.include_router(page_routes.router)
    app.include_router(fit_routes.router)
    return app


def app_from_env() -> FastAPI:
    """App factory for ``uvicorn --factory`` (``thermogel serve``): options from the environment.

    THERMOGEL_CACHE (cache file), THERMOGEL_MAX_PENDING (queue bound), THERMOGEL_WARMUP
    ('0' skips the warm-up).
    """
    pending = os.environ.get("THERMOGEL_MAX_PENDING")
    return create_app(cache_path=os.environ.get("THERMOGEL_CACHE") or None,
                      max_pending=int(pending) if pending else None,
                      warm=os.environ.get("THERMOGEL_WARMUP", "1") != "0")


def _physics_routes(app: FastAPI) -> None:
    @app.get("/health", response_model=s.HealthResponse, tags=["service"])
    async def health(request: Request) -> dict[str, Any]:
        """Liveness: 'ok' once the kernels are warm."""
        st: ServiceState = request.app.state.service
        rep = st.warmup
        planner_info = await run_in_threadpool(st.describe)
        return {"status": "ok" if st.planner is not None else "starting",
                "version": _version(),
                "kernels_warm": len(rep.warm) if rep else 0,
                "kernels_cold": list(rep.cold) if rep else [],
                "warmup_seconds": rep.seconds if rep else None,
                "planner": planner_info}

    @app.get("/v1/gels", response_model=s.GelsResponse, tags=["physics"])
    async def gels() -> dict[str, Any]:
        """The preset gels with their parameters and fold temperatures."""
        return await compute(presets_answer)

    @app.post("/v1/equilibrium", response_model=s.EquilibriumResponse, tags=["physics"])
    async def equilibrium(req: s.EquilibriumRequest) -> dict[str, Any]:
        """Every free-swelling equilibrium at a temperature (eq. EqlEqn), and the folds."""
        return await compute(equilibrium_answer, req)

    @app.post("/v1/classify", response_model=s.ClassifyResponse, tags=["physics"])
    async def classify(req: s.ClassifyRequest) -> dict[str, Any]:
        """What a temperature jump does: smooth, front, delayed front or spinodal."""
        return await compute(classify_answer, req)


def _maybe_pending(code: int, out: dict[str, Any]) -> dict[str, Any] | JSONResponse:
    """A 202 carries only the poll fields (and a Location header); a 200 the full model."""
    if code != 202:
        return out
    return JSONResponse(out, status_code=202, headers={"Location": out["validation_url"]})


def _dosing_routes(app: FastAPI) -> None:
    """Dose-time, schedule and validation routes."""

    @app.post("/v1/dose-time", response_model=s.DoseTimeResponse, tags=["dosing"],
              responses={202: {"model": s.DoseTimeResponse,
                               "description": "needs the full solver: poll validation_url"},
                         429: {"model": s.ErrorResponse, "description": "validation queue full"}})
    async def dose(body: s.DoseTimeRequest, request: Request) -> Any:
        """How long to heat a bead to release a dose (front model at once, or 202)."""
        st: ServiceState = request.app.state.service
        code, out = await compute(dose_time, st.planner, body)
        return _maybe_pending(code, out)

    @app.post("/v1/schedule", response_model=s.ScheduleResponse, tags=["dosing"],
              responses={202: {"model": s.ScheduleResponse,
                               "description": "queued as a job: poll validation_url"},
                         429: {"model": s.ErrorResponse, "description": "job queue full"}})
    async def schedule_route(body: s.ScheduleRequest, request: Request) -> Any:
        """A multi-dose schedule: hold times at once; protocol check and correction as a job."""
        code, out = await compute(schedule, request.app.state.service, body)
        return _maybe_pending(code, out)

    @app.get("/v1/validations/{validation_id}", response_model=s.ValidationResponse,
             tags=["dosing"],
             responses={404: {"model": s.ErrorResponse, "description": "unknown id"},
                        429: {"model": s.ErrorResponse,
                              "description": "resuming it needs a queue slot"}})
    async def validation_route(validation_id: str, request: Request) -> dict[str, Any]:
        """State of a full-solver job; when done, the full solver's answer."""
        return await compute(validation, request.app.state.service, validation_id)
