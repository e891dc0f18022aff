"""``POST /v1/fit/swelling`` and ``/v1/fit/kinetics``: fits run as jobs (202 + poll).

The data are checked at once (a bad column, NaN, a negative size or too few points is a 422
naming it); the fit runs on a one-thread job runner of this app and is polled at
``GET /v1/fit/jobs/{id}``; a fit that fails on the data (e.g. all points on one side of the
transition) ends ``failed`` with the message.
"""

from __future__ import annotations

import hashlib
from concurrent.futures import ThreadPoolExecutor
from typing import Any

import fastapi
from fastapi import Request
from fastapi.responses import JSONResponse

from api.fit_schemas import FitJobResponse, KineticsFitRequest, SwellingFitRequest

from ..service import to_gel
from .compute import compute

router = fastapi.APIRouter(tags=["fit"])
FIT_QUEUE = 8


def _jobs(request: Request) -> Any:
    """This app's fit job runner (created on first use)."""
    from dosing.jobs import JobRunner

    st = request.app.state
    if getattr(st, "fit_jobs", None) is None:
        st.fit_jobs = JobRunner(ThreadPoolExecutor(1, thread_name_prefix="fit"), FIT_QUEUE)
    return st.fit_jobs


def _key(kind: str, body: Any) -> str:
    return kind + "-" + hashlib.sha256(body.model_dump_json().encode()).hexdigest()[:24]


def _accepted(kind: str, key: str) -> JSONResponse:
    url = f"/v1/fit/jobs/{key}"
    return JSONResponse({"id": key, "kind": kind, "status": "pending", "status_url": url},
                        status_code=202, headers={"Location": url})


def _swelling(body: SwellingFitRequest, data: Any) -> dict[str, Any]:
    from dosing.fit import data_dict, fit_swelling
    from dosing.gel_store import GelStore
    from solver.fit import fit_gel

    res = fit_swelling(data, sigma_t=body.sigma_t, size_rel_sigma=body.size_rel_sigma,
                       fixed=body.fixed, n_starts=body.n_starts)
    report = res.to_dict()
    if body.save:
        GelStore().save(body.save, fit_gel(res, body.save),
                        swelling={"data": data_dict(data), "fit": report})
        report["saved"] = body.save
    return report


def _kinetics(body: KineticsFitRequest, data: Any, planner: Any) -> dict[str, Any]:
    from dosing import PhysicalConstants, SolverSettings
    from dosing.fit import data_dict, fit_shrinking
    from dosing.gel_store import GelStore
    from solver.gel import Gel

    settings = SolverSettings() if body.interfacial_length is None else SolverSettings(
        interfacial_length=body.interfacial_length)
    res = fit_shrinking(data, to_gel(body.gel), body.t_start, body.t_end, branch=body.branch,
                        dry_radius_um=body.dry_radius_um,
                        swollen_radius_um=body.swollen_radius_um,
                        constants=PhysicalConstants(body.viscosity_pa_s,
                                                    body.polymer_volume_m3),
                        fit_beta=body.fit_beta, beta=body.beta, model=body.model,
                        settings=settings, size_rel_sigma=body.size_rel_sigma,
                        planner=planner)
    report = res.to_dict()
    if body.save:
        store = GelStore()
        g = Gel.from_dict({**report["gel"], "name": body.save})
        if report.get("beta") is not None:
            g = g.with_permeability("power", report["beta"])
        src = body.gel if isinstance(body.gel, str) and body.gel in store.names() else None
        swelling = store.load_record(src).get("swelling") if src else None
        store.save(body.save, g, swelling=swelling, kinetics={"data": data_dict(data),
                                                             "fit": report})
        report["saved"] = body.save
    return report


@router.post("/v1/fit/swelling", status_code=202, response_model=FitJobResponse,
             responses={202: {"model": FitJobResponse}, 429: {"description": "too many fit "
                                                                "jobs queued; retry later"}})
async def fit_swelling_route(body: SwellingFitRequest, request: Request) -> Any:
    """Fit a gel to an equilibrium swelling curve (eq. EqlEqn): a job, poll status_url."""
    from dosing.fit import swelling_data
    from dosing.gel_store import check_name

    if body.save:
        check_name(body.save)
    data = swelling_data(body.temperature_K, body.size, body.size_kind, body.weight)
    if len(data) <= 6 - len(body.fixed or {}):
        from solver.errors import ParameterError

        raise ParameterError("temperature_K", f"{len(data)} points", "more points than "
                             "fitted parameters")
    key = _key("swelling", body)
    _jobs(request).submit(key, _swelling, body, data)
    return _accepted("swelling", key)


@router.post("/v1/fit/kinetics", status_code=202, response_model=FitJobResponse,
             responses={202: {"model": FitJobResponse}, 429: {"description": "too many fit "
                                                                "jobs queued; retry later"}})
async def fit_kinetics_route(body: KineticsFitRequest, request: Request) -> Any:
    """Fit tau (hence k0) to a shrinking curve after a jump: a job, poll status_url."""
    from dosing.fit import kinetics_data
    from dosing.gel_store import check_name
    if body.save:
        check_name(body.save)
    data = kinetics_data(body.time_s, body.size, body.size_kind, body.weight)
    await compute(to_gel, body.gel)  # an unknown gel is a 422 now
    planner = getattr(getattr(request.app.state, "service", None), "planner", None)
    key = _key("kinetics", body)
    _jobs(request).submit(key, _kinetics, body, data, planner)
    return _accepted("kinetics", key)


@router.get("/v1/fit/jobs/{job_id}", response_model=FitJobResponse,
            responses={404: {"description": "no such fit job"}})
async def fit_job(job_id: str, request: Request) -> Any:
    """A fit job's state, with the report when done or the error when failed."""
    runner = _jobs(request)
    state = runner.state(job_id)
    if state is None:
        return JSONResponse({"detail": [{"loc": ["path", "job_id"], "type": "not_found",
                                         "msg": f"no fit job {job_id!r} (jobs are kept in "
                                                "memory and end with a restart)"}]},
                            status_code=404)
    out: dict[str, Any] = {"id": job_id, "kind": job_id.split("-")[0], "status": state,
                           "status_url": f"/v1/fit/jobs/{job_id}"}
    fut = runner.get(job_id)
    if state == "done":
        from api.commands.common import _clean

        out["result"] = _clean(fut.result())
    elif state == "failed":
        out["error"] = str(fut.exception())
    return out
