"""Release analysis over HTTP (issue 38): ``POST /v1/fit/empirical`` fits the empirical
release models as a stored job (202 + poll at ``/v1/fit/jobs/{id}`` or ``/v1/jobs/{id}``);
``POST /v1/compare`` answers f1/f2 with the FDA rules and Shah's bootstrap at once (a few
milliseconds: vectorised).  Bad data are a 422 naming the field and index.  ``GET /analysis``
is a small page over both: CSV files uploaded, results as tables and plots."""

from __future__ import annotations

from typing import Any

from fastapi import APIRouter
from fastapi.responses import FileResponse, HTMLResponse, JSONResponse

from solver.json_safe import json_safe

from .. import stored_jobs
from ..analysis_schemas import (
    CompareRequest,
    CompareResponse,
    EmpiricalFitJobResponse,
    EmpiricalFitRequest,
)
from ..deps import StateDep
from ..safe_route import SafeRoute
from .compute import compute
from .fit import KINDS
from .page import STATIC

router = APIRouter(tags=["fit"], route_class=SafeRoute)


def _empirical(_: Any, body: EmpiricalFitRequest) -> dict[str, Any]:
    """The empirical models' report (a stored job's run)."""
    from dosing.analysis import fit_empirical

    res = fit_empirical(body.profile(), body.models, lag=body.lag, kp_window=body.kp_window)
    return json_safe(res.report())


stored_jobs.register(stored_jobs.JobKind(KINDS["empirical"], EmpiricalFitRequest,
                                         _empirical))


def _submit(state: Any, body: EmpiricalFitRequest) -> JSONResponse:
    body.profile()  # bad data: a 422 before the job
    jid = stored_jobs.submit(state, KINDS["empirical"], body)
    url = f"/v1/fit/jobs/{jid}"
    return JSONResponse({"id": jid, "kind": "empirical", "status": "pending",
                         "status_url": url}, status_code=202, headers={"Location": url})


@router.post("/v1/fit/empirical", status_code=202, response_model=EmpiricalFitJobResponse,
             responses={202: {"model": EmpiricalFitJobResponse},
                        429: {"description": "too many jobs queued; retry later"}})
async def fit_empirical_route(body: EmpiricalFitRequest, state: StateDep) -> Any:
    """Fit the empirical release models (zero-order, first-order, Higuchi, Korsmeyer-Peppas,
    Hixson-Crowell, Weibull, Peppas-Sahlin) to a profile: a job, poll status_url."""
    return await compute(_submit, state, body)


def _compare(body: CompareRequest) -> dict[str, Any]:
    from dosing.analysis.similarity import compare

    c = compare(body.reference.profile("reference"), body.test.profile("test"),
                n_boot=body.n_boot, seed=body.seed, confidence=body.confidence)
    return json_safe(c.to_dict())


@router.post("/v1/compare", response_model=CompareResponse)
async def compare_route(body: CompareRequest) -> Any:
    """f1 and f2 of two release profiles with the FDA rules (points used, the 85 % and CV
    rules, the outcome in the guidance's words) and Shah et al.'s bootstrap f2 (90 % BCa)
    when replicate units are given."""
    return await compute(_compare, body)


@router.get("/analysis", response_class=HTMLResponse, include_in_schema=False)
async def analysis_page() -> HTMLResponse:
    """The release-analysis page: CSV uploads to the two routes above."""
    return HTMLResponse((STATIC / "analysis.html").read_text(encoding="utf-8"))


@router.get("/analysis.js", include_in_schema=False)
async def analysis_script() -> FileResponse:
    """Its script."""
    return FileResponse(str(STATIC / "analysis.js"), media_type="text/javascript")
