"""Python client of the planner service (httpx): ``Client`` (sync) and ``AsyncClient``.

One method per route, each taking the request model (or a dict, or keyword fields) and
returning the same pydantic models the server uses (:mod:`api.schemas`); a 202 (work
queued) is a :class:`~api.schemas.PendingResponse` with the id to poll.  An error answer
(404, 422, 429, 5xx) raises :class:`ApiError` with the status, the detail (422: a list
naming the fields) and, for 429, the Retry-After seconds::

    from api.client import Client
    with Client("http://127.0.0.1:8000") as c:
        ans = c.dose_time(gel="ANB", t_start=302, t_end=308, dose_fraction=0.8,
                          dry_radius_um=50)
        print(ans.model, ans.time, ans.seconds)
"""

from __future__ import annotations

import asyncio
import time
from typing import Any, TypeVar
from urllib.parse import quote

import httpx
from pydantic import BaseModel

from . import schemas as s

M = TypeVar("M", bound=BaseModel)
DEFAULT_URL = "http://127.0.0.1:8000"
FINISHED = ("done", "failed")


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


def _body(req: BaseModel | dict[str, Any] | None, fields: dict[str, Any]) -> dict:
    """The JSON body: a request model, or a dict and keyword fields sent as they are (the
    server validates them; ``None`` values mean "not given")."""
    if isinstance(req, BaseModel):
        return req.model_dump(mode="json", by_alias=True, exclude_none=True)
    merged = {**(req or {}), **fields}
    return {k: v for k, v in merged.items() if v is not None}


_DRUG_ANSWERS: dict[type, type] = {s.DoseTimeResponse: s.DrugDoseResponse,
                                   s.ScheduleResponse: s.DrugScheduleResponse}


def _answer(resp: httpx.Response, model: type[M]) -> M:
    """Parse a 200 answer into ``model`` (a 202 into PendingResponse); raise
    :class:`ApiError` for an error answer."""
    if resp.status_code >= 400:
        try:
            detail = resp.json().get("detail", resp.text)
        except ValueError:
            detail = resp.text
        retry = resp.headers.get("Retry-After")
        raise ApiError(resp.status_code, detail, float(retry) if retry else None)
    if resp.status_code == 202:
        return s.PendingResponse.model_validate(resp.json())  # type: ignore[return-value]
    data = resp.json()
    if isinstance(data, dict) and data.get("drug") is True:  # a drug answer (api.schemas.DrugOut)
        model = _DRUG_ANSWERS.get(model, model)  # type: ignore[assignment]
    return model.model_validate(data)


class _Routes:
    """The route table shared by both clients; ``_call`` is sync or async in the subclass."""

    def _call(self, method: str, path: str, body: dict | None, model: type[M]) -> Any:
        raise NotImplementedError

    def health(self) -> Any:
        """GET /health -> HealthResponse."""
        return self._call("GET", "/health", None, s.HealthResponse)

    def gels(self) -> Any:
        """GET /v1/gels -> GelsResponse (presets with parameters and folds)."""
        return self._call("GET", "/v1/gels", None, s.GelsResponse)

    def equilibrium(self, req: s.EquilibriumRequest | dict | None = None, **fields: Any) -> Any:
        """POST /v1/equilibrium -> EquilibriumResponse."""
        body = _body(req, fields)
        return self._call("POST", "/v1/equilibrium", body, s.EquilibriumResponse)

    def classify(self, req: s.ClassifyRequest | dict | None = None, **fields: Any) -> Any:
        """POST /v1/classify -> ClassifyResponse."""
        body = _body(req, fields)
        return self._call("POST", "/v1/classify", body, s.ClassifyResponse)

    def dose_time(self, req: s.DoseTimeRequest | dict | None = None, **fields: Any) -> Any:
        """POST /v1/dose-time -> DoseTimeResponse, or PendingResponse (202)."""
        body = _body(req, fields)
        return self._call("POST", "/v1/dose-time", body, s.DoseTimeResponse)

    def schedule(self, req: s.ScheduleRequest | dict | None = None, **fields: Any) -> Any:
        """POST /v1/schedule -> ScheduleResponse, or PendingResponse (202: a job)."""
        body = _body(req, fields)
        return self._call("POST", "/v1/schedule", body, s.ScheduleResponse)

    def validation(self, validation_id: str) -> Any:
        """GET /v1/validations/{id} -> ValidationResponse."""
        path = f"/v1/validations/{quote(str(validation_id), safe='')}"
        return self._call("GET", path, None, s.ValidationResponse)


class Client(_Routes):
    """Synchronous client; use as a context manager or call :meth:`close`."""

    def __init__(self, base_url: str = DEFAULT_URL, timeout: float = 30.0,
                 transport: httpx.BaseTransport | None = None) -> None:
        self._http = httpx.Client(base_url=base_url, timeout=timeout, transport=transport)

    def _call(self, method: str, path: str, body: dict | None, model: type[M]) -> M:
        return _answer(self._http.request(method, path, json=body), model)

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
                 transport: httpx.AsyncBaseTransport | None = None) -> None:
        self._http = httpx.AsyncClient(base_url=base_url, timeout=timeout, transport=transport)

    async def _call(self, method: str, path: str, body: dict | None, model: type[M]) -> M:
        return _answer(await self._http.request(method, path, json=body), model)

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
