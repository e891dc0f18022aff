"""Every JSON answer of the service carries ``request`` and ``version`` (dosing.provenance).

:class:`api.safe_route.SafeRoute` (every route of the service) passes each answer through
:func:`stamp_response`: a JSON object answer (200, 201, 202) gets ``request``, the request as
the route resolved it (a body: its model with every default filled; path and query
parameters; the route), with the unit of each physical field in ``request["units"]``, and
``version`` (package, code and solver versions).  An answer that carries the planner's own
resolved request (dosing.question's ``Request.to_dict()``) keeps it, with its units added.
Error answers (4xx, 5xx), files (CSV,
SVG, HTML) and answers that already carry the fields are passed through unchanged.
"""

from __future__ import annotations

import json
from typing import Any

from fastapi import Request, Response
from pydantic import TypeAdapter, ValidationError

from dosing.provenance import resolved, version_info


def _adapter(route: Any) -> TypeAdapter | None:
    cached = getattr(route, "_stamp_adapter", False)
    if cached is not False:
        return cached
    field = getattr(route, "body_field", None)
    adapter = None
    if field is not None:
        try:
            adapter = TypeAdapter(field.field_info.annotation)
        except Exception:  # an annotation pydantic cannot adapt alone: the raw body serves
            adapter = None
    route._stamp_adapter = adapter
    return adapter


async def request_record(route: Any, request: Request) -> dict[str, Any]:
    """The request as the route resolved it: the body's model dumped with its defaults
    (the raw JSON when it is not a model), path and query parameters, and the route."""
    out: dict[str, Any] = {}
    if request.method in ("POST", "PUT", "PATCH"):
        raw = await request.body()
        try:
            body = json.loads(raw) if raw else None
        except ValueError:
            body = None
        adapter = _adapter(route)
        if adapter is not None and body is not None:
            try:
                model = adapter.validate_python(body)
                body = (model.model_dump(mode="json") if hasattr(model, "model_dump")
                        else adapter.dump_python(model, mode="json"))
            except ValidationError:
                pass
        if isinstance(body, dict):
            out.update(body)
        elif body is not None:
            out["body"] = body
    out.update({k: v for k, v in request.path_params.items() if k not in out})
    out.update({k: v for k, v in request.query_params.items() if k not in out})
    out["route"] = f"{request.method} {route.path}"
    return resolved(out)


async def stamp_response(route: Any, request: Request, response: Response) -> Response:
    """``response`` with ``request`` and ``version`` added when it is a JSON object answer
    (2xx) without them; anything else unchanged."""
    if not (200 <= response.status_code < 300) or "json" not in (
            response.headers.get("content-type") or ""):
        return response
    body = getattr(response, "body", b"")
    if not body or not body.lstrip().startswith(b"{"):
        return response
    try:
        answer = json.loads(body)
    except ValueError:
        return response
    if not isinstance(answer, dict):
        return response
    own = answer.get("request")
    if isinstance(own, dict) and "units" in own and "version" in answer:
        return response
    if isinstance(own, dict):  # the planner's resolved request (dosing.question): its units
        answer["request"] = resolved(own)
    else:
        answer["request"] = await request_record(route, request)
    answer.setdefault("version", version_info())
    headers = {k: v for k, v in response.headers.items()
               if k.lower() not in ("content-length", "content-type")}
    content = json.dumps(answer, ensure_ascii=False, allow_nan=False,
                         separators=(",", ":")).encode("utf-8")
    return Response(content, status_code=response.status_code, headers=headers,
                    media_type="application/json", background=response.background)
