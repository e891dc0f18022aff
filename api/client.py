"""Python client of the planner service (httpx): ``Client`` (sync) and ``AsyncClient``.

One method per route of the service, written once over the route table :data:`ROUTES`
(``tests/test_api_client_routes.py`` compares it with ``/openapi.json``): a route with a
body takes its request model (or a dict, or keyword fields), a route with path parameters
takes them positionally, a GET with a query takes keyword parameters.  A JSON answer is
returned as the pydantic model the server documents (:mod:`api.schemas` and the areas'
schema modules); a 202 (work queued) as the route's accepted model (a dose or schedule:
:class:`~api.schemas.PendingResponse` with the id to poll); CSV as ``str``, SVG as
``bytes``.  A 429 or 503 with ``Retry-After`` (a full queue, the connection caps, a
starting server) is asked again after the seconds it names, at most ``retries`` times and
``max_retry_wait`` seconds in all; any other error answer (404, 422, ...) raises
:class:`ApiError` with the status, the detail (422: a list naming the fields) and the
Retry-After seconds::

    from api.client import Client
    with Client("http://127.0.0.1:8000") as c:
        ans = c.dose_time(gel="ANB", t_start=302, t_end=308, dose_fraction=0.8,
                          dry_radius_um=50)
        print(ans.model, ans.time, ans.seconds)
"""

from __future__ import annotations

import asyncio
import importlib
import re
import time
from dataclasses import dataclass
from typing import Any, TypeVar
from urllib.parse import quote

import httpx
from pydantic import BaseModel, ConfigDict, TypeAdapter, ValidationError

from . import schemas as s

M = TypeVar("M", bound=BaseModel)
DEFAULT_URL = "http://127.0.0.1:8000"
FINISHED = ("done", "failed")
RETRY_STATUSES = (429, 503)
RETRIES = 3  # asks again after a 429 / 503 with Retry-After, at most this many times
MAX_RETRY_WAIT = 60.0  # ... and at most this many seconds of waiting in all


class ApiError(RuntimeError):
    """An error answer from the service."""

    def __init__(self, status: int, detail: Any, retry_after: float | None = None) -> None:
        self.status = status
        self.detail = detail
        self.retry_after = retry_after
        super().__init__(f"HTTP {status}: {detail}")

    @property
    def fields(self) -> list[str]:
        """The fields a 422 names (dotted, without the leading 'body')."""
        if not isinstance(self.detail, list):
            return []
        out = []
        for item in self.detail:
            loc = [str(x) for x in item.get("loc", []) if x not in ("body", "custom", "preset")]
            out.append(".".join(loc))
        return out


@dataclass(frozen=True)
class Route:
    """One route of the service as the client calls it: the method's ``name``, the HTTP
    ``method`` and ``path`` (``{name}``: a positional parameter), ``body`` (the request
    model, 'module:Name') or ``query`` (keyword parameters), and the answer: ``answers``
    (models tried in order, 'module:Name'), ``accepted`` (the 202's model), or ``media``
    ('text' for CSV, 'bytes' for SVG)."""

    name: str
    method: str
    path: str
    answers: tuple[str, ...] = ()
    body: str | None = None
    query: bool = False
    accepted: str | None = None
    media: str | None = None
    doc: str = ""

    @property
    def params(self) -> list[str]:
        """The path parameters, in order."""
        return re.findall(r"{(\w+)}", self.path)


S, F, J, SW, P, SE = ("api.schemas", "api.fit_schemas", "api.routers.jobs", "api.routers.sweep",
                      "api.routers.page", "api.sensitivity_schemas")
A = "api.analysis_schemas"
PENDING = f"{S}:PendingResponse"
ROUTES: tuple[Route, ...] = (
    Route("health", "GET", "/health", (f"{S}:HealthResponse",),
          doc="liveness, the warm-up report and queue state"),
    Route("gels", "GET", "/v1/gels", (f"{S}:GelsResponse",),
          doc="preset gels with parameters and folds"),
    Route("equilibrium", "POST", "/v1/equilibrium", (f"{S}:EquilibriumResponse",),
          body=f"{S}:EquilibriumRequest", doc="every equilibrium at a temperature"),
    Route("classify", "POST", "/v1/classify", (f"{S}:ClassifyResponse",),
          body=f"{S}:ClassifyRequest", doc="what a jump does"),
    Route("dose_time", "POST", "/v1/dose-time",
          (f"{S}:DoseTimeResponse", f"{S}:DrugDoseResponse", f"{S}:ProtocolDoseResponse"),
          body=f"{S}:DoseTimeRequest", accepted=PENDING,
          doc="actuation time for a dose (202: PendingResponse)"),
    Route("schedule", "POST", "/v1/schedule",
          (f"{S}:ScheduleResponse", f"{S}:DrugScheduleResponse"),
          body=f"{S}:ScheduleRequest", accepted=PENDING,
          doc="a multi-dose schedule (202: a job, PendingResponse)"),
    Route("validation", "GET", "/v1/validations/{validation_id}", (f"{S}:ValidationResponse",),
          doc="a validation's state and result"),
    Route("fit_swelling", "POST", "/v1/fit/swelling", body=f"{F}:SwellingFitRequest",
          accepted=f"{F}:FitJobResponse", doc="fit a swelling curve (a job)"),
    Route("fit_kinetics", "POST", "/v1/fit/kinetics", body=f"{F}:KineticsFitRequest",
          accepted=f"{F}:FitJobResponse", doc="fit a shrinking curve (a job)"),
    Route("fit_release", "POST", "/v1/fit/release", body=f"{F}:ReleaseFitRequest",
          accepted=f"{F}:ReleaseFitJobResponse", doc="fit a drug's D0 to a release curve"),
    Route("fit_empirical", "POST", "/v1/fit/empirical", body=f"{A}:EmpiricalFitRequest",
          accepted=f"{A}:EmpiricalFitJobResponse",
          doc="fit the empirical release models (DDSolver's zoo) to a profile (a job)"),
    Route("compare", "POST", "/v1/compare", (f"{A}:CompareResponse",),
          body=f"{A}:CompareRequest", doc="f1 and f2 of two release profiles (FDA rules, "
          "bootstrap)"),
    Route("fit_job", "GET", "/v1/fit/jobs/{job_id}",
          (f"{F}:ReleaseFitJobResponse", f"{F}:FitJobResponse"), doc="a fit job's state"),
    Route("sweep", "POST", "/v1/sweep", body=f"{SW}:SweepRequest",
          accepted=f"{SW}:SweepAccepted", doc="queue a design map (a job)"),
    Route("sweep_status", "GET", "/v1/sweeps/{sweep_id}", (f"{SW}:SweepStatus",),
          doc="a design map's progress and table"),
    Route("sweep_table_csv", "GET", "/v1/sweeps/{sweep_id}/table.csv", media="text",
          doc="a finished design map as CSV (str)"),
    Route("sweep_plot_svg", "GET", "/v1/sweeps/{sweep_id}/plot.svg", query=True,
          media="bytes", doc="a design map's heat maps as SVG (bytes)"),
    Route("front_curve", "POST", "/v1/front-curve", (f"{P}:FrontCurveResponse",),
          body=f"{P}:FrontCurveRequest", doc="the front model's a(t) and R_f(t)"),
    Route("phase_map_svg", "GET", "/v1/phase-map.svg", query=True, media="bytes",
          doc="a gel's phase map as SVG (bytes)"),
    Route("sensitivity", "POST", "/v1/sensitivity", (f"{SE}:SensitivityResponse",),
          body=f"{SE}:SensitivityRequest", doc="Sobol or Morris indices of the dose time"),
    Route("job", "GET", "/v1/jobs/{job_id}", (f"{J}:JobResponse",),
          doc="any job's state (validation, schedule, drug dose, fit, sweep)"),
)


def _model(ref: str) -> Any:
    """The model (a pydantic class, or a union of them) 'module:Name' names."""
    module, _, name = ref.partition(":")
    return getattr(importlib.import_module(module), name)


_OPEN: dict[type, type] = {}


def _open(model: type[BaseModel]) -> type[BaseModel]:
    """``model``, or a subclass of it that keeps the fields it does not declare (every
    answer's ``request`` and ``version``, api/stamp.py) when it would drop them."""
    if model.model_config.get("extra") == "allow":
        return model
    if model not in _OPEN:
        _OPEN[model] = type(model.__name__, (model,), {
            "__module__": model.__module__, "__doc__": model.__doc__,
            "model_config": ConfigDict(**{**model.model_config, "extra": "allow"})})
    return _OPEN[model]


def _validate(model: Any, data: Any) -> Any:
    if isinstance(model, type) and issubclass(model, BaseModel):
        return _open(model).model_validate(data)
    got = TypeAdapter(model).validate_python(data)  # a union (the jobs' poll route)
    return _open(type(got)).model_validate(data) if isinstance(got, BaseModel) else got


def _body(req: BaseModel | dict[str, Any] | None, fields: dict[str, Any]) -> dict:
    """The JSON body: a request model, or a dict and keyword fields sent as they are (the
    server validates them; ``None`` values mean "not given")."""
    if isinstance(req, BaseModel):
        return req.model_dump(mode="json", by_alias=True, exclude_none=True)
    merged = {**(req or {}), **fields}
    return {k: v for k, v in merged.items() if v is not None}


def _error(resp: httpx.Response) -> ApiError:
    try:
        data = resp.json()
        detail = data.get("detail", resp.text) if isinstance(data, dict) else data
    except ValueError:
        detail = resp.text
    return ApiError(resp.status_code, detail, _retry_after(resp))


def _retry_after(resp: httpx.Response) -> float | None:
    raw = resp.headers.get("Retry-After")
    try:
        return None if raw is None else max(0.0, float(raw))
    except ValueError:
        return None


def _typed(data: Any, refs: tuple[str, ...]) -> Any:
    """``data`` as the first of the models ``refs`` that takes it (the drug answers first
    when the answer says drug; the last model's error when none does)."""
    models = [_model(r) for r in refs]
    if isinstance(data, dict) and data.get("drug") is True:
        models.sort(key=lambda m: "Drug" not in getattr(m, "__name__", ""))
    for i, model in enumerate(models):
        try:
            return _validate(model, data)
        except ValidationError:
            if i == len(models) - 1:
                raise
    return data


def _answer(resp: httpx.Response, route: Route) -> Any:
    """A 2xx answer as the route's model (or text / bytes); an error raises ApiError."""
    if resp.status_code >= 400:
        raise _error(resp)
    if route.media == "text":
        return resp.text
    if route.media == "bytes":
        return resp.content
    if resp.status_code == 202:
        return _typed(resp.json(), (route.accepted or PENDING,))
    if not route.answers:
        return _typed(resp.json(), (route.accepted,)) if route.accepted else resp.json()
    return _typed(resp.json(), route.answers)


def _request(route: Route, args: tuple[Any, ...], req: Any, fields: dict[str, Any]
             ) -> tuple[str, dict | None, dict | None]:
    """(path, JSON body, query) of a call of ``route``."""
    names = route.params
    if len(args) != len(names):
        raise TypeError(f"{route.name}() takes {len(names)} positional argument(s) "
                        f"({', '.join(names) or 'none'}), {len(args)} given")
    path = route.path
    for name, value in zip(names, args, strict=True):
        path = path.replace("{" + name + "}", quote(str(value), safe=""))
    if route.body is not None:
        return path, _body(req, fields), None
    if route.query:
        query = _body(req, fields)
        return path, None, {k: (str(v).lower() if isinstance(v, bool) else v)
                            for k, v in query.items()}
    if req is not None or fields:
        raise TypeError(f"{route.name}() takes no body or query")
    return path, None, None


def _method(route: Route) -> Any:
    def call(self: _Routes, *args: Any, req: Any = None, **fields: Any) -> Any:
        if route.body is not None and args and len(args) == len(route.params) + 1:
            *args, req = args  # the request model or dict, positionally after the ids
        path, body, query = _request(route, tuple(args), req, fields)
        return self._call(route, path, body, query)

    call.__name__ = call.__qualname__ = route.name
    shape = ", ".join(route.params + (["req | **fields"] if route.body else [])
                      + (["**query"] if route.query else []))
    answer = route.media or " | ".join(r.partition(":")[2] for r in route.answers) or \
        (route.accepted or "").partition(":")[2]
    call.__doc__ = (f"{route.method} {route.path} ({shape}) -> {answer}"
                    + (f", or {route.accepted.partition(':')[2]} (202)"
                       if route.accepted and route.answers else "") + f": {route.doc}.")
    return call


class _Routes:
    """The route table's methods shared by both clients (one per :data:`ROUTES` entry);
    ``_call`` is sync or async in the subclass."""

    retries: int = RETRIES
    max_retry_wait: float = MAX_RETRY_WAIT

    def _call(self, route: Route, path: str, body: dict | None, query: dict | None) -> Any:
        raise NotImplementedError

    def _retry_delay(self, resp: httpx.Response, attempt: int, waited: float) -> float | None:
        """Seconds to wait before asking again (a 429 / 503 with Retry-After, within the
        bounds), or None: answer now."""
        if resp.status_code not in RETRY_STATUSES or attempt >= self.retries:
            return None
        delay = _retry_after(resp)
        if delay is None or waited + delay > self.max_retry_wait:
            return None
        return delay


for _route in ROUTES:
    setattr(_Routes, _route.name, _method(_route))


class Client(_Routes):
    """Synchronous client; use as a context manager or call :meth:`close`."""

    def __init__(self, base_url: str = DEFAULT_URL, timeout: float = 30.0,
                 transport: httpx.BaseTransport | None = None, retries: int = RETRIES,
                 max_retry_wait: float = MAX_RETRY_WAIT) -> None:
        self._http = httpx.Client(base_url=base_url, timeout=timeout, transport=transport)
        self.retries, self.max_retry_wait = retries, max_retry_wait

    def _call(self, route: Route, path: str, body: dict | None, query: dict | None) -> Any:
        waited, attempt = 0.0, 0
        while True:
            resp = self._http.request(route.method, path, json=body, params=query)
            delay = self._retry_delay(resp, attempt, waited)
            if delay is None:
                return _answer(resp, route)
            time.sleep(delay)
            waited, attempt = waited + delay, attempt + 1

    def wait_validation(self, validation_id: str, timeout: float = 600.0,
                        interval: float = 0.5) -> s.ValidationResponse:
        """Poll until the validation is done or failed; TimeoutError after ``timeout`` s."""
        deadline = time.monotonic() + timeout
        while True:
            v = self.validation(validation_id)
            if v.status in FINISHED:
                return v
            if time.monotonic() > deadline:
                raise TimeoutError(f"validation {validation_id} still {v.status}")
            time.sleep(interval)

    def close(self) -> None:
        """Close the connection pool."""
        self._http.close()

    def __enter__(self) -> Client:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


class AsyncClient(_Routes):
    """Asynchronous client (every route method is a coroutine); ``async with`` it."""

    def __init__(self, base_url: str = DEFAULT_URL, timeout: float = 30.0,
                 transport: httpx.AsyncBaseTransport | None = None, retries: int = RETRIES,
                 max_retry_wait: float = MAX_RETRY_WAIT) -> None:
        self._http = httpx.AsyncClient(base_url=base_url, timeout=timeout, transport=transport)
        self.retries, self.max_retry_wait = retries, max_retry_wait

    async def _call(self, route: Route, path: str, body: dict | None,  # type: ignore[override]
                    query: dict | None) -> Any:
        waited, attempt = 0.0, 0
        while True:
            resp = await self._http.request(route.method, path, json=body, params=query)
            delay = self._retry_delay(resp, attempt, waited)
            if delay is None:
                return _answer(resp, route)
            await asyncio.sleep(delay)
            waited, attempt = waited + delay, attempt + 1

    async def wait_validation(self, validation_id: str, timeout: float = 600.0,
                              interval: float = 0.5) -> s.ValidationResponse:
        """Poll until the validation is done or failed; TimeoutError after ``timeout`` s."""
        deadline = time.monotonic() + timeout
        while True:
            v = await self.validation(validation_id)
            if v.status in FINISHED:
                return v
            if time.monotonic() > deadline:
                raise TimeoutError(f"validation {validation_id} still {v.status}")
            await asyncio.sleep(interval)

    async def aclose(self) -> None:
        """Close the connection pool."""
        await self._http.aclose()

    async def __aenter__(self) -> AsyncClient:
        return self

    async def __aexit__(self, *exc: object) -> None:
        await self.aclose()
