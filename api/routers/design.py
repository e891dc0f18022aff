"""``POST /v1/design/heating`` and ``/v1/design/experiment`` (issue 39): stored jobs (202 +
poll at ``/v1/design/jobs/{id}`` or ``/v1/jobs/{id}``), bounded like the fit jobs (a 429
when the job queue is full) and kept in the cache, so they survive a restart; ``GET
/design`` a small page over them."""

from __future__ import annotations

from importlib.resources import files
from typing import Any

from fastapi import APIRouter
from fastapi.responses import HTMLResponse, JSONResponse

from dosing import UnknownValidationError
from solver.json_safe import json_safe

from .. import stored_jobs
from ..deps import StateDep
from ..design_schemas import DesignJobResponse, ExperimentDesignRequest, HeatingDesignRequest
from ..safe_route import SafeRoute
from ..service import to_gel
from .compute import compute

router = APIRouter(tags=["design"], route_class=SafeRoute)
KINDS = {"heating": "design-heating", "experiment": "design-experiment"}


def _constants(body: Any) -> dict[str, Any] | None:
    return None if body is None else body.model_dump(exclude_none=True)


def heating_target(body: HeatingDesignRequest) -> Any:
    """The request as a ``dosing.design.HeatingTarget`` (a ParameterError names the field)."""
    from dosing.design import HeatingTarget

    return HeatingTarget(to_gel(body.gel), body.t_start, body.at_seconds,
                         fraction=body.fraction, dose_ug=body.dose_ug,
                         concentration_ug_per_ul=body.concentration_ug_per_ul,
                         dry_radius_um=body.dry_radius_um, size_cv=body.size_cv,
                         mode=body.mode, t_end=body.t_end,
                         time_constant_s=body.time_constant_s,
                         bounds=None if body.bounds is None else tuple(body.bounds),
                         validate=body.validate_full, confidence=body.confidence,
                         full=body.full, constants=_constants(body.constants))


def experiment_ask(body: ExperimentDesignRequest) -> Any:
    """The request as a ``dosing.design.ExperimentAsk``."""
    from dosing.design import ExperimentAsk

    return ExperimentAsk(to_gel(body.gel), body.t_start, body.t_end, body.fraction,
                         body.dry_radius_um, size_noise=body.size_noise,
                         max_duration_s=body.max_duration_s, n_points=body.n_points,
                         min_interval_s=body.min_interval_s,
                         sizes_um=None if body.sizes_um is None else tuple(body.sizes_um),
                         jumps=None if body.jumps is None else tuple(body.jumps),
                         criterion=body.criterion, simulate=body.simulate,
                         constants=_constants(body.constants))


def _heating(planner: Any, body: HeatingDesignRequest) -> dict[str, Any]:
    from dosing.design import design_heating

    return json_safe(design_heating(heating_target(body), planner).to_dict())


def _experiment(planner: Any, body: ExperimentDesignRequest) -> dict[str, Any]:
    from dosing.design import design_experiment

    out = design_experiment(experiment_ask(body), planner)
    return json_safe({**out.to_dict(), "csv": out.csv()})


stored_jobs.register(stored_jobs.JobKind(KINDS["heating"], HeatingDesignRequest, _heating))
stored_jobs.register(stored_jobs.JobKind(KINDS["experiment"], ExperimentDesignRequest,
                                         _experiment))


def _submit(state: Any, kind: str, body: Any) -> JSONResponse:
    # what can be refused at once is refused before the job (422 naming the field)
    (heating_target if kind == "heating" else experiment_ask)(body)
    jid = stored_jobs.submit(state, KINDS[kind], body)
    url = f"/v1/design/jobs/{jid}"
    return JSONResponse({"id": jid, "kind": KINDS[kind], "status": "pending",
                         "status_url": url}, status_code=202, headers={"Location": url})


_ACCEPTED = {202: {"model": DesignJobResponse},
             429: {"description": "too many jobs queued; retry later"}}


@router.post("/v1/design/heating", status_code=202, response_model=DesignJobResponse,
             responses=_ACCEPTED)
async def design_heating_route(body: HeatingDesignRequest, state: StateDep) -> Any:
    """The heating at which the dose is out at the asked time: a job, poll status_url."""
    return await compute(_submit, state, "heating", body)


@router.post("/v1/design/experiment", status_code=202, response_model=DesignJobResponse,
             responses=_ACCEPTED)
async def design_experiment_route(body: ExperimentDesignRequest, state: StateDep) -> Any:
    """The shrinking-curve experiment that best pins the answer: a job, poll status_url."""
    return await compute(_submit, state, "experiment", body)


def status(state: Any, job_id: str) -> dict[str, Any]:
    """A design job's state (kept in the cache across restarts)."""
    if not job_id.startswith(tuple(k + "-" for k in KINDS.values())):
        raise UnknownValidationError(job_id)
    return {**stored_jobs.status(state, job_id), "status_url": f"/v1/design/jobs/{job_id}"}


@router.get("/v1/design/jobs/{job_id}", response_model=DesignJobResponse,
            responses={404: {"description": "no such design job"}})
async def design_job(job_id: str, state: StateDep) -> Any:
    """A design job's state, with the result when done or the error when failed."""
    return await compute(status, state, job_id)


@router.get("/design", response_class=HTMLResponse, include_in_schema=False)
async def design_page() -> HTMLResponse:
    """A small page over the two design routes (api/static/design.html: plain HTML and JS,
    no network): the heating's form and the experiment's, the jobs polled, the sampling
    table and its CSV."""
    return HTMLResponse((files("api") / "static" / "design.html").read_text(encoding="utf-8"))
