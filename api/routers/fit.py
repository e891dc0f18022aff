"""``POST /v1/fit/swelling``, ``/v1/fit/kinetics`` and ``/v1/fit/release``: fits as stored
jobs (202 + poll at ``/v1/fit/jobs/{id}`` or ``/v1/jobs/{id}``).

The data are checked at once (a bad column, NaN, a negative size or too few points is a 422
naming it); the fit runs as a stored job (:mod:`api.stored_jobs`: kept in the cache, so it
survives a restart) and is polled at ``GET /v1/fit/jobs/{id}``; a fit that fails on the data
(e.g. all points on one side of the transition) ends ``failed`` with the message.
"""

from __future__ import annotations

from typing import Any

from fastapi import APIRouter
from fastapi.responses import JSONResponse

from dosing import PhysicalConstants, SolverSettings, UnknownValidationError
from dosing.fits.gel import (
    data_dict,
    fit_swelling,
    kinetics_data,
    kinetics_report,
    swelling_data,
)
from dosing.fits.gel_store import GelStore, check_name
from solver.errors import ParameterError
from solver.fit import fit_gel
from solver.gel import Gel
from solver.json_safe import json_safe
from solver.limits import DRY_RADIUS_UM_RANGE, SIZE_UM_RANGE

from .. import stored_jobs
from ..analysis_schemas import EmpiricalFitJobResponse
from ..deps import StateDep
from ..fit_schemas import (
    FitJobResponse,
    KineticsFitRequest,
    ReleaseFitJobResponse,
    ReleaseFitRequest,
    SwellingFitRequest,
)
from ..requests import http_protocol
from ..safe_route import SafeRoute
from ..service import to_gel
from .compute import compute

router = APIRouter(tags=["fit"], route_class=SafeRoute)
KINDS = {"swelling": "fit-swelling", "kinetics": "fit-kinetics", "release": "fit-release",
         "empirical": "fit-empirical"}  # empirical: api/routers/analysis.py


def _swelling_data(body: SwellingFitRequest) -> Any:
    data = swelling_data(body.temperature_K, body.size, body.size_kind, body.weight)
    if len(data) <= 6 - len(body.fixed or {}):
        raise ParameterError("temperature_K", f"{len(data)} points", "more points than "
                             "fitted parameters")
    return data


def _swelling(_: Any, body: SwellingFitRequest) -> dict[str, Any]:
    """The swelling fit's report (a stored job's run; eq. EqlEqn)."""
    data = _swelling_data(body)
    res = fit_swelling(data, sigma_t=body.sigma_t, size_rel_sigma=body.size_rel_sigma,
                       fixed=body.fixed, n_starts=body.n_starts,
                       objective=body.objective, dry_size=body.dry_size)
    report = json_safe(res.to_dict())
    if body.dose_jump:
        from dosing.fits.gel import dose_under_objectives

        report["dose_time_by_objective"] = json_safe(dose_under_objectives(
            data, body.dose_jump[0], body.dose_jump[1], body.dose_fraction,
            sigma_t=body.sigma_t, size_rel_sigma=body.size_rel_sigma, fixed=body.fixed,
            fits={body.objective: res}, n_starts=body.n_starts))
    if body.save:
        GelStore().save(body.save, fit_gel(res, body.save),
                        swelling={"data": data_dict(data), "fit": report})
        report["saved"] = body.save
    return report


def _kinetics(planner: Any, body: KineticsFitRequest) -> dict[str, Any]:
    """The kinetics fit's report (a stored job's run; eq. timescale)."""
    data = kinetics_data(body.time_s, body.size, body.size_kind, body.weight)
    settings = SolverSettings() if body.interfacial_length is None else SolverSettings(
        interfacial_length=body.interfacial_length)
    _, report = kinetics_report(
        data, to_gel(body.gel), body.t_start, body.t_end, compare_laws=body.compare_laws,
        branch=body.branch, dry_radius_um=body.dry_radius_um,
        swollen_radius_um=body.swollen_radius_um,
        constants=PhysicalConstants(body.viscosity_pa_s, body.polymer_volume_m3),
        fit_beta=body.fit_beta, beta=body.beta, model=body.model, settings=settings,
        size_rel_sigma=body.size_rel_sigma, planner=planner)
    report = json_safe(report)
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


def _release_data(body: ReleaseFitRequest) -> tuple[Any, Any]:
    from dosing.fits.release import release_data

    return release_data(body.time_s, body.released, body.released_unit, body.loaded_ug)


def _release_settings(body: ReleaseFitRequest) -> SolverSettings | None:
    if body.solver_n is None and body.solver_rtol is None:
        return None
    return SolverSettings(n=body.solver_n, rtol=body.solver_rtol)


def _release(_: Any, body: ReleaseFitRequest) -> dict[str, Any]:
    """The release fit's report (a stored job's run; dosing.fits.release, f2)."""
    from dosing.fits.release import fit_release

    t, y = _release_data(body)
    prot = None if body.protocol is None else http_protocol(body.t_start, body.protocol)
    return json_safe(fit_release(
        t, y, to_gel(body.gel), body.t_start, body.t_end, body.dry_radius_um,
        protocol=prot, hindrance=body.hindrance, mesh_size_nm=body.mesh_size_nm,
        fiber_radius_nm=body.fiber_radius_nm, settings=_release_settings(body)))


stored_jobs.register(stored_jobs.JobKind(KINDS["swelling"], SwellingFitRequest, _swelling))
stored_jobs.register(stored_jobs.JobKind(KINDS["release"], ReleaseFitRequest, _release))
stored_jobs.register(stored_jobs.JobKind(KINDS["kinetics"], KineticsFitRequest, _kinetics))


def _check(body: SwellingFitRequest | KineticsFitRequest | ReleaseFitRequest) -> None:
    """What can be refused before the job (422 naming the field, never a failed job): the
    name, the data (enough points for the parameters fitted), the gel, the bead size."""
    first = "temperature_K" if isinstance(body, SwellingFitRequest) else "time_s"
    try:
        _check_body(body)
    except ParameterError as exc:
        if exc.field != "data":
            raise
        raise ParameterError(first, exc.value, exc.valid) from None


def _enough(body: KineticsFitRequest | ReleaseFitRequest, least: int) -> None:
    n = len(body.time_s)
    if n < least:
        raise ParameterError("time_s", f"{n} points", f"at least {least} points (more than "
                             "the parameters fitted)")


def _bead(name: str, value: float | None) -> None:
    lo, hi = DRY_RADIUS_UM_RANGE if name == "dry_radius_um" else SIZE_UM_RANGE
    if value is not None and not lo <= value <= hi:
        raise ParameterError(name, value, f"{lo:g}-{hi:g} um")


def _check_body(body: SwellingFitRequest | KineticsFitRequest | ReleaseFitRequest) -> None:
    if isinstance(body, ReleaseFitRequest):
        _enough(body, 3)
        _bead("dry_radius_um", body.dry_radius_um)
        _release_data(body)
        _release_settings(body)
        to_gel(body.gel)
        if body.protocol is not None:
            from dosing.fits.release_steps import parse_protocol

            if body.t_end is not None:
                raise ParameterError("t_end", body.t_end, "null when a protocol is given")
            parse_protocol(body.t_start, http_protocol(body.t_start, body.protocol))
        elif body.t_end is not None and body.t_end != body.t_start:
            raise ParameterError("t_end", body.t_end, f"equal to t_start = {body.t_start:g} "
                                 "K (isothermal), or give a protocol")
        return
    if body.save:
        check_name(body.save)
    if isinstance(body, SwellingFitRequest):
        _swelling_data(body)
    else:
        _enough(body, 3 if body.fit_beta else 2)
        _bead("dry_radius_um", body.dry_radius_um)
        _bead("swollen_radius_um", body.swollen_radius_um)
        kinetics_data(body.time_s, body.size, body.size_kind, body.weight)
        to_gel(body.gel)


def _submit(state: Any, kind: str, body: Any) -> JSONResponse:
    _check(body)
    jid = stored_jobs.submit(state, KINDS[kind], body)
    url = f"/v1/fit/jobs/{jid}"
    return JSONResponse({"id": jid, "kind": kind, "status": "pending", "status_url": url},
                        status_code=202, headers={"Location": url})


_ACCEPTED = {202: {"model": FitJobResponse},
             429: {"description": "too many jobs queued; retry later"}}


@router.post("/v1/fit/swelling", status_code=202, response_model=FitJobResponse,
             responses=_ACCEPTED)
async def fit_swelling_route(body: SwellingFitRequest, state: StateDep) -> Any:
    """Fit a gel to an equilibrium swelling curve (eq. EqlEqn): a job, poll status_url."""
    return await compute(_submit, state, "swelling", body)


@router.post("/v1/fit/kinetics", status_code=202, response_model=FitJobResponse,
             responses=_ACCEPTED)
async def fit_kinetics_route(body: KineticsFitRequest, state: StateDep) -> Any:
    """Fit tau (hence k0) to a shrinking curve after a jump: a job, poll status_url."""
    return await compute(_submit, state, "kinetics", body)


@router.post("/v1/fit/release", status_code=202, response_model=ReleaseFitJobResponse,
             responses={202: {"model": ReleaseFitJobResponse},
                        429: {"description": "too many jobs queued; retry later"}})
async def fit_release_route(body: ReleaseFitRequest, state: StateDep) -> Any:
    """Fit a drug's free diffusivity D0 to a cumulative release curve, isothermal or under a
    heating protocol, with f2 (dosing.fits.release): a job, poll status_url."""
    return await compute(_submit, state, "release", body)


def _status(state: Any, job_id: str) -> dict[str, Any]:
    if not job_id.startswith(tuple(k + "-" for k in KINDS.values())):
        raise UnknownValidationError(job_id)
    out = stored_jobs.status(state, job_id)
    kind = out["kind"].removeprefix("fit-")
    return {**out, "kind": kind, "status_url": f"/v1/fit/jobs/{job_id}"}


@router.get("/v1/fit/jobs/{job_id}",
            response_model=ReleaseFitJobResponse | EmpiricalFitJobResponse | FitJobResponse,
            responses={404: {"description": "no such fit job"}})
async def fit_job(job_id: str, state: StateDep) -> Any:
    """A fit job's state, with the report when done or the error when failed (kept in the
    cache across restarts)."""
    return await compute(_status, state, job_id)
