"""Design-map routes: ``POST /v1/sweep`` queues a sweep as a job (202 + Location), ``GET
/v1/sweeps/{id}`` (or ``GET /v1/jobs/{id}``) polls it (progress, then the table as JSON, or
CSV with ``?format=csv``), ``GET /v1/sweeps/{id}/plot.svg`` draws its heat maps.

A sweep is a stored job (:mod:`api.stored_jobs`, kind 'sweep'): its body and, once done, its
table are kept in the planner's cache, so a finished sweep survives a restart and one
pending at a kill -9 is run again when polled.  It runs on a job thread of its own (one
thread, ``SWEEP_QUEUE`` queued before 429) and spreads its chunks over the planner's
executor, so a planner on a Dask cluster sweeps on the cluster.  Validations the request
selects are the planner's own (poll /v1/validations/{id}); each poll of the sweep fills
those done, and the table is stored again once they all are.  Only rendered bodies of
final tables are kept in memory (the last ``SWEEPS_KEPT``, ``RENDERED_BYTES`` at most).
"""

from __future__ import annotations

import json
import threading
from concurrent.futures import ThreadPoolExecutor
from typing import Annotated, Any, Literal

from fastapi import APIRouter, Query, Request
from fastapi.responses import JSONResponse, Response
from pydantic import BaseModel, ConfigDict, Field, create_model, field_validator, model_validator

from dosing import JobRunner, SolverSettings, UnknownValidationError
from dosing.runs.lru import ByteLRU
from dosing.studies.sweep import COLUMNS, SweepGrid, SweepResult, fill_validations, run_sweep
from solver.errors import ParameterError
from solver.json_safe import json_safe
from solver.limits import T_MAX, T_MIN

from .. import stored_jobs
from ..safe_route import SafeRoute
from ..schemas import (
    Branch,
    ConstantsIn,
    ErrorResponse,
    GelSpec,
    RequestModel,
    check_interfacial_length,
    interfacial_length_field,
    temperature_field,
)
from ..service import to_gel
from .compute import RENDER, compute

router = APIRouter(tags=["design maps"], route_class=SafeRoute)

MAX_SERVICE_POINTS = 20_000  # points in one sweep request (the CLI takes up to 100,000)
SWEEP_QUEUE = 4  # sweeps queued or running before 429
SWEEP_PREFIX = "sweep-"
SWEEPS_KEPT = 8  # final sweep tables kept rendered in memory (20,000 rows: tens of MB)
RENDERED_BYTES = 64e6  # ... and their bodies' bytes at most
Temperature = Annotated[float, Field(ge=T_MIN, le=T_MAX)]
Radius = Annotated[float, Field(ge=1.0e-3, le=1.0e5)]
Fraction = Annotated[float, Field(gt=0.0, le=1.0)]


class SweepRequest(RequestModel):
    """A design map: every combination of gels x T_end x dry radius x dose, answered with
    the front model; full-solver validations queued for the points ``validate`` selects.
    A point that fails on its own (a dose above what the gel can expel at that T_end) is a
    row with status 'error' and its message."""

    model_config = ConfigDict(extra="forbid", json_schema_extra={"examples": [
        {"gels": ["ANB"], "t_start": 302.0, "t_ends": [308.0, 309.0, 310.0],
         "dry_radii_um": [20.0, 50.0, 100.0], "doses": [0.3, 0.5, 0.8]}]})

    gels: list[GelSpec] = Field(["ANB"], min_length=1, max_length=8,
                                description="1-8 gels: preset names or custom parameters")
    t_start: float = temperature_field("start (loading) temperature", 302.0)
    t_ends: list[Temperature] = Field(
        min_length=1, max_length=200, examples=[[308.0, 309.0, 310.0]],
        description="1-200 end (actuation) temperatures in K, 273.15-373.15 each")
    dry_radii_um: list[Radius] = Field(
        min_length=1, max_length=200, examples=[[20.0, 50.0, 100.0]],
        description="1-200 dry bead radii in micrometres, 1e-3 <= r <= 1e5 each")
    doses: list[Fraction] = Field(
        min_length=1, max_length=100, examples=[[0.3, 0.5, 0.8]],
        description="1-100 doses, fractions of the stored fluid, 0 < f <= 1 each")
    branch: Branch | None = Field(None, description="start branch (default swollen)")
    constants: ConstantsIn | None = Field(None, description="timescale constants")
    interfacial_length: float | None = interfacial_length_field()
    validate_points: Literal["all", "needs-full"] | list[Annotated[int, Field(ge=0)]] = Field(
        [], alias="validate", description="points whose full-solver validation to queue: "
        "'needs-full' (those the front model cannot answer), 'all', or a list of indices")

    _ell = field_validator("interfacial_length")(check_interfacial_length)

    @model_validator(mode="after")
    def _size(self) -> SweepRequest:
        n = len(self.gels) * len(self.t_ends) * len(self.dry_radii_um) * len(self.doses)
        if n > MAX_SERVICE_POINTS:
            raise ValueError(f"at most {MAX_SERVICE_POINTS} points per sweep (this one has "
                             f"{n}): split it, or run 'thermogel sweep' on a cluster")
        return self


class SweepAccepted(BaseModel):
    """A queued sweep: poll ``sweep_url``."""

    status: Literal["pending"] = Field("pending", description="'pending': poll sweep_url")
    sweep_id: str = Field(description="id of the sweep job")
    sweep_url: str = Field(description="path to poll")
    points: int = Field(description="points in the grid")


class SweepColumn(BaseModel):
    """A column of the table."""

    name: str = Field(description="column name (a key of every row)")
    unit: str = Field(description="unit: K, um, s, uL, tau (dimensionless time), 1 "
                                  "(a fraction), '' for text")
    description: str = Field(description="what the column holds")


def _row_field(name: str, unit: str, description: str) -> tuple[Any, Any]:
    kind: Any = int if name in ("index", "gel_index") else str if unit == "" else float
    return kind | None, Field(None, description=f"{description} [{unit or 'text'}]")


# one row of the table: a field per column of dosing.studies.sweep.COLUMNS (the one definition)
SweepRow = create_model("SweepRow", __config__=ConfigDict(extra="allow"),
                        __doc__="One point of the sweep (a row of the table).",
                        **{name: _row_field(name, *spec) for name, spec in COLUMNS.items()})


class SweepTable(BaseModel):
    """The table: the grid's axes, the columns with units, one row per point."""

    model_config = ConfigDict(extra="allow")

    grid: dict[str, Any] = Field(description="the axes, with shape [gels, t_ends, radii, "
                                             "doses]")
    columns: list[SweepColumn] = Field(description="every column with its unit")
    rows: list[SweepRow] = Field(description="one object per point, keys as columns")  # type: ignore[valid-type]
    counts: dict[str, int] = Field(description="points per status")
    seconds: float = Field(description="wall time of the front-model sweep, s")


class SweepStatus(BaseModel):
    """A sweep job's state; ``result`` once done."""

    id: str = Field(description="sweep id")
    status: Literal["pending", "running", "done", "failed"] = Field(description="its state")
    points: int = Field(description="points in the grid")
    points_done: int = Field(description="points answered so far")
    validations_unfinished: int | None = Field(
        None, description="validations of this sweep still pending or running")
    result: SweepTable | None = Field(None, description="when done: the table")
    error: str | None = Field(None, description="when failed: why")


class _Sweeps:
    """The service's sweep runner (one thread, a bounded queue), progress of the sweeps
    running here, and the rendered bodies of the last ``SWEEPS_KEPT`` final tables."""

    def __init__(self) -> None:
        self.runner = JobRunner(ThreadPoolExecutor(1, thread_name_prefix="sweep"),
                                max_pending=SWEEP_QUEUE, what="sweeps")
        self.progress: dict[str, list[int]] = {}
        # JSON, CSV, SVG bodies: RENDERED_BYTES at most (dosing.runs.lru: bytes, not entries)
        self.rendered: ByteLRU = ByteLRU(RENDERED_BYTES, sizeof=len)
        self.lock = threading.Lock()

    def keep(self, key: tuple[str, str], body: bytes) -> None:
        """Keep a final table's rendered body, dropping those of the oldest sweeps beyond
        ``SWEEPS_KEPT`` (they are rendered again from the store when asked)."""
        with self.lock:
            self.rendered[key] = body
            self.rendered.move_to_end(key)
            while len({k[0] for k in self.rendered}) > SWEEPS_KEPT:
                self.rendered.popitem(last=False)

    def cached(self, key: tuple[str, str]) -> bytes | None:
        """A rendered body, or None."""
        with self.lock:
            return self.rendered.get(key)


_CREATE = threading.Lock()


def _sweeps_of(state: Any) -> _Sweeps:
    """The sweep runner of a service state (created on first use)."""
    with _CREATE:
        jobs = getattr(state, "sweeps", None)
        if jobs is None:
            jobs = state.sweeps = _Sweeps()
    return jobs


def _sweeps(request: Request) -> _Sweeps:
    jobs = _sweeps_of(request.app.state.service)
    request.app.state.sweeps = jobs
    return jobs


def to_grid(body: SweepRequest) -> SweepGrid:
    """The dosing grid of a request (gels as the service reads them)."""

    return SweepGrid(t_ends=body.t_ends, dry_radii_um=body.dry_radii_um, doses=body.doses,
                     gels=[to_gel(g) for g in body.gels], t_start=body.t_start,
                     branch=body.branch,
                     constants=None if body.constants is None
                     else body.constants.model_dump(exclude_none=True),
                     settings=SolverSettings(interfacial_length=body.interfacial_length))


def _run_job(planner: Any, body: SweepRequest) -> dict[str, Any]:
    """The stored job's run: the sweep on the planner's executor; its table (a dict)."""
    grid = to_grid(body)
    progress = _PROGRESS.setdefault(stored_jobs.job_id("sweep", body), [0, grid.size])
    progress[0] = 0
    jobs = getattr(planner, "jobs", None)

    def step(n: int) -> None:
        progress[0] += n

    return run_sweep(grid, executor=None if jobs is None else jobs.executor,
                     planner=planner, validate=body.validate_points, progress=step).to_dict()


_PROGRESS: dict[str, list[int]] = {}  # points done of the sweeps running in this process
stored_jobs.register(stored_jobs.JobKind("sweep", SweepRequest, _run_job,
                                         runner=lambda state: _sweeps_of(state).runner))


def _check_validate(body: SweepRequest, size: int) -> None:
    """A ``validate`` index past the grid is refused before the sweep runs (422)."""
    if isinstance(body.validate_points, list):
        for i, idx in enumerate(body.validate_points):
            if idx >= size:
                raise ParameterError(f"validate[{i}]", idx, f"a point index 0-{size - 1}")


def _submit(request: Request, body: SweepRequest) -> dict[str, Any]:
    grid = to_grid(body)  # ParameterError: 422 naming the field
    _check_validate(body, grid.size)
    state = request.app.state.service
    _sweeps(request)
    vid = stored_jobs.submit(state, "sweep", body)  # one job per body; a full queue: 429
    return {"status": "pending", "sweep_id": vid, "sweep_url": f"/v1/sweeps/{vid}",
            "points": grid.size}


def _status(request: Request, sweep_id: str) -> dict[str, Any]:
    """The sweep job's state from the store; when done, its table with the validations
    filled (stored again once none is unfinished)."""
    state = request.app.state.service
    _sweeps(request)
    if not sweep_id.startswith(SWEEP_PREFIX):
        raise UnknownValidationError(sweep_id)
    job = stored_jobs.status(state, sweep_id)
    if job["status"] == "done":
        total = done = len(job["result"]["rows"])
    else:  # the stored body (no table yet): its grid's size
        d = state.planner.cache.get_job(sweep_id)["request"]
        total = len(d["gels"]) * len(d["t_ends"]) * len(d["dry_radii_um"]) * len(d["doses"])
        done = _PROGRESS.get(sweep_id, [0])[0]
    out: dict[str, Any] = {"id": sweep_id, "status": job["status"], "points": total,
                           "points_done": done}
    if job["status"] == "done":
        table = job["result"]
        res = SweepResult(table["grid"], table["rows"], table["seconds"])
        open_before = sum(1 for r in res.rows if r.get("validation_id")
                          and r.get("validation_status") not in ("done", "failed"))
        out["validations_unfinished"] = fill_validations(res, state.planner)
        out["result"] = res.to_dict()
        if open_before and not out["validations_unfinished"]:  # settled: store it so
            state.planner.cache.finish_job(sweep_id, "done", result=out["result"])
        _PROGRESS.pop(sweep_id, None)
    elif job["status"] == "failed":
        out["error"] = job.get("error") or "failed"
    return out


@router.post("/v1/sweep", status_code=202, response_model=SweepAccepted,
             responses={422: {"model": ErrorResponse, "description": "bad input; loc names it"},
                        429: {"model": ErrorResponse, "description": "sweep queue full"}})
async def sweep(body: SweepRequest, request: Request) -> JSONResponse:
    """Queue a design map (front model for every point at once; validations for a subset)."""
    out = await compute(_submit, request, body)
    return JSONResponse(out, status_code=202, headers={"Location": out["sweep_url"]})


@router.get("/v1/sweeps/{sweep_id}", response_model=SweepStatus,
            responses={404: {"model": ErrorResponse, "description": "unknown id"}})
async def sweep_status(
        sweep_id: str, request: Request,
        format: Annotated[Literal["json", "csv"], Query(include_in_schema=False)] = "json",
) -> Any:
    """A sweep's progress; when done, its table (JSON with units; as CSV at
    ``/v1/sweeps/{id}/table.csv``).  Serialised off the event loop; a final table (every
    validation settled) is serialised once.  (``?format=csv``, undocumented, is the CSV
    route's older spelling.)"""
    body, media = await render(request, sweep_id, format)
    return Response(body, media_type=media)


@router.get("/v1/sweeps/{sweep_id}/table.csv", response_class=Response, responses={
    200: {"content": {"text/csv": {"schema": {"type": "string"}}},
          "description": "the finished table as CSV (headers 'name [unit]')"},
    404: {"model": ErrorResponse, "description": "unknown id"},
    409: {"model": ErrorResponse, "description": "not done yet (poll the sweep)"}})
async def sweep_csv(sweep_id: str, request: Request) -> Response:
    """The finished sweep's table as CSV, one row per point (a 409 while it runs)."""
    body, media = await render(request, sweep_id, "csv")
    if media != _MEDIA["csv"]:
        state = json.loads(body).get("status")
        return JSONResponse({"detail": [{"loc": ["path", "sweep_id"], "type": "not_done",
                                         "msg": f"sweep {sweep_id} is {state}: poll "
                                                f"/v1/sweeps/{sweep_id}"}]}, status_code=409)
    return Response(body, media_type=media)


async def render(request: Request, sweep_id: str, fmt: str) -> tuple[bytes, str]:
    """A sweep poll's answer as bytes: a final table's from memory at once, else rendered
    on the render executor (a 20,000-row table is not serialised on the compute threads)."""
    hit = _sweeps(request).cached((sweep_id, fmt))
    if hit is not None:
        return hit, _MEDIA[fmt]
    return await RENDER.run(_render, request, sweep_id, fmt)


def _render(request: Request, sweep_id: str, fmt: str) -> tuple[bytes, str]:
    """The poll's answer as bytes (in a compute thread), from the cache when final."""
    jobs = _sweeps(request)
    hit = jobs.cached((sweep_id, fmt))
    if hit is not None:
        return hit, _MEDIA[fmt]
    out = _status(request, sweep_id)
    if fmt == "csv" and out["status"] == "done":
        res = SweepResult(out["result"]["grid"], out["result"]["rows"],
                          out["result"]["seconds"])
        body = res.to_csv().encode()
    else:
        fmt = "json"
        body = json.dumps(json_safe(out), separators=(",", ":"), allow_nan=False).encode()
    if out["status"] == "done" and not out.get("validations_unfinished"):
        jobs.keep((sweep_id, fmt), body)
    return body, _MEDIA[fmt]


_MEDIA = {"json": "application/json", "csv": "text/csv", "svg": "image/svg+xml"}


@router.get("/v1/sweeps/{sweep_id}/plot.svg", response_class=Response,
            responses={200: {"content": {"image/svg+xml": {"schema": {
                "type": "string", "format": "binary"}}}, "description": "the heat maps"},
                       404: {"model": ErrorResponse, "description": "unknown id"},
                       409: {"model": ErrorResponse, "description": "not done yet"}})
async def sweep_plot(
        sweep_id: str, request: Request,
        gel: Annotated[int, Query(ge=0, description="which gel of the grid")] = 0,
) -> Response:
    """Heat maps of the finished sweep: actuation time and its error over T_end x radius
    (drawn once per final table and gel, on the render executor: at most 8 doses drawn, so
    seconds; kept)."""
    hit = _sweeps(request).cached((sweep_id, f"svg{gel}"))
    if hit is not None:
        return Response(hit, media_type=_MEDIA["svg"])
    return await RENDER.run(_plot, request, sweep_id, gel)


def _plot(request: Request, sweep_id: str, gel: int) -> Response:
    jobs = _sweeps(request)
    hit = jobs.cached((sweep_id, f"svg{gel}"))
    if hit is not None:
        return Response(hit, media_type=_MEDIA["svg"])
    out = _status(request, sweep_id)
    if out["status"] != "done":
        return JSONResponse({"detail": [{"loc": ["path", "sweep_id"], "type": "not_done",
                                         "msg": f"sweep {sweep_id} is {out['status']}: poll "
                                                f"/v1/sweeps/{sweep_id}"}]}, status_code=409)
    if gel >= out["result"]["grid"]["shape"][0]:
        return JSONResponse({"detail": [{"loc": ["query", "gel"], "type": "value_error",
                                         "msg": "gel index beyond the grid's gels"}]},
                            status_code=422)
    svg = _svg(out["result"], gel)
    if not out.get("validations_unfinished"):
        jobs.keep((sweep_id, f"svg{gel}"), svg)
    return Response(svg, media_type=_MEDIA["svg"])


def _svg(table: dict[str, Any], gel: int) -> bytes:
    import io

    from ..plots.sweep import draw_sweep

    buf = io.BytesIO()
    draw_sweep(table, buf, gel_index=gel)
    return buf.getvalue()



__all__ = ["COLUMNS", "router"]
