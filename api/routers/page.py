"""The planner page and the two small routes it draws from.

``GET /`` is a single page (``api/static``: plain HTML, JS and CSS shipped in the package,
no network, no build step) over the JSON routes; it reads every input's bounds from
``/openapi.json``.  ``POST /v1/front-curve`` gives the front model's trajectory (radius and
front against time, eqs. SphereEvolve_Dimless and FrontEvolve) for the plot;
``GET /v1/phase-map.svg`` draws the gel's phase map (paper fig. 3) with the jump on it.
"""

from __future__ import annotations

import functools
import io
from importlib.resources import files
from typing import Annotated, Any, Literal

from fastapi import APIRouter, HTTPException, Query
from fastapi.responses import FileResponse, HTMLResponse, Response
from pydantic import BaseModel, ConfigDict, Field, field_validator

from dosing.model_choice import choose_model, front_model_name, front_run
from dosing.request import resolve_jump
from dosing.runs.scenario import SolverSettings
from solver.errors import NotApplicableError

from ..safe_route import SafeRoute
from ..schemas import (
    T_MAX,
    T_MIN,
    Branch,
    ErrorResponse,
    GelParameters,
    GelSpec,
    RequestModel,
    check_interfacial_length,
    interfacial_length_field,
    temperature_field,
)
from ..service import to_gel
from .compute import RENDER, compute

router = APIRouter(route_class=SafeRoute)
STATIC = files("api") / "static"
ASSETS = {"app.js": "text/javascript", "app.css": "text/css"}


class FrontCurveRequest(RequestModel):
    """The jump whose front-model trajectory to draw."""

    model_config = ConfigDict(extra="forbid", json_schema_extra={
        "examples": [{"gel": "ANB", "t_start": 302.0, "t_end": 308.0}]})

    gel: GelSpec = "ANB"
    t_start: float = temperature_field("start (loading) temperature", 302.0)
    t_end: float = temperature_field("end (actuation) temperature", 308.0)
    branch: Branch | None = Field(None, description="start branch (default swollen)")
    interfacial_length: float | None = interfacial_length_field()
    n: int = Field(201, ge=11, le=2001, description="samples, 11-2001")

    _ell = field_validator("interfacial_length")(check_interfacial_length)


class FrontCurveResponse(BaseModel):
    """The front model's trajectory: samples of a(t) and R_f(t), dimensionless."""

    model_config = ConfigDict(extra="allow")

    model: Literal["front-sharp", "front"] = Field(
        description="'front-sharp' (regularized truth) or 'front' (the paper's model)")
    t: list[float] = Field(description="times, units of tau")
    radius: list[float] = Field(description="bead radius a(t), dry radii")
    front: list[float] = Field(description="front radius R_f(t), dry radii")
    start_radius: float = Field(description="a(0), the equilibrium at T_start, dry radii")
    final_radius: float = Field(description="equilibrium radius at T_end, dry radii")
    t_stop: float = Field(description="when the front reaches the centre, units of tau")


def _asset(name: str) -> Any:
    return STATIC / name


@router.get("/", response_class=HTMLResponse, include_in_schema=False)
async def page() -> HTMLResponse:
    """The planner page."""
    return HTMLResponse(_asset("index.html").read_text(encoding="utf-8"))


@router.get("/static/{name}", include_in_schema=False)
async def asset(name: str) -> Response:
    """The page's script and style sheet (nothing else is served from the package)."""
    if name not in ASSETS:
        raise HTTPException(404, f"no asset {name!r}")
    return FileResponse(str(_asset(name)), media_type=ASSETS[name])


def front_curve_answer(body: FrontCurveRequest) -> dict[str, Any]:
    """The trajectory the planner's front model follows for this jump (blocking)."""
    gel = to_gel(body.gel)
    jump = resolve_jump(gel, body.t_start, body.t_end, body.branch)
    model, why = choose_model(gel, jump.t_start, jump.t_end, jump.branch)
    if model != "front":
        exc = NotApplicableError(f"no front-model curve for this jump: {why}; the full "
                                 "solver answers it (validate a dose)")
        exc.field = "t_end"  # type: ignore[attr-defined]
        raise exc
    settings = SolverSettings(interfacial_length=body.interfacial_length)
    fr = front_run(gel, jump.t_start, jump.t_end, jump.branch, settings.regularized)
    t, r, f = fr.t.tolist(), fr.radius.tolist(), fr.front.tolist()
    if body.n != len(t):
        import numpy as np

        tt = np.linspace(fr.t[0], fr.t_stop, body.n)
        states = [fr.state_at(x) for x in tt]
        t, r, f = tt.tolist(), [s[0] for s in states], [s[1] for s in states]
    return {"model": front_model_name(settings), "t": t, "radius": r, "front": f,
            "start_radius": jump.start_radius, "final_radius": jump.final_radius,
            "t_stop": float(fr.t_stop)}


@router.post("/v1/front-curve", response_model=FrontCurveResponse, tags=["physics"],
             responses={422: {"model": ErrorResponse, "description": "bad input, or no front "
                                                                     "on this jump"}})
async def front_curve(body: FrontCurveRequest) -> dict[str, Any]:
    """Radius and front against time from the front model (what the dose answers read)."""

    return await compute(front_curve_answer, body)


class PhaseMapQuery(GelParameters):
    """A gel (a preset, ``base``, with any parameter replaced) and the jump to draw."""

    # query strings are text: parse numbers from them (still finite, still bounded)
    model_config = ConfigDict(strict=False)

    t_start: float = Field(302.0, ge=T_MIN, le=T_MAX, description="start temperature in K")
    t_end: float = Field(308.0, ge=T_MIN, le=T_MAX, description="end temperature in K")
    branch: Branch | None = Field(None, description="start branch (default swollen)")


@functools.lru_cache(maxsize=32)
def phase_map_svg(query_json: str) -> bytes:
    """The phase map of the query's gel with its jump drawn (blocking; memoised)."""
    from ..plots.phase_map import draw_phase_map  # matplotlib: only where a map is drawn

    q = PhaseMapQuery.model_validate_json(query_json)
    gel = to_gel(q)
    jump = resolve_jump(gel, q.t_start, q.t_end, q.branch)
    buf = io.BytesIO()
    draw_phase_map(gel, buf, jump=(jump.t_start, jump.start_radius, jump.t_end,
                                   jump.final_radius), fmt="svg", size=(6.0, 4.2))
    return buf.getvalue()


@router.get("/v1/phase-map.svg", response_class=Response, tags=["physics"],
            responses={200: {"content": {"image/svg+xml": {}}},
                       422: {"model": ErrorResponse, "description": "bad input"}})
async def phase_map(query: Annotated[PhaseMapQuery, Query()]) -> Response:
    """The gel's phase map (paper fig. 3) with the jump T_start -> T_end drawn on it."""

    svg = await RENDER.run(phase_map_svg, query.model_dump_json())
    return Response(svg, media_type="image/svg+xml")
