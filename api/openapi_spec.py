"""The OpenAPI description completed in one place, so that a generated client handles every
answer of every route.

FastAPI documents what each route declares; the service's layers answer more: the body
limit (413), the token (401), the read timeout (408), the connection caps (429, 503), the
error table (422, 500, 503) and, on a route with a path parameter, an unknown id (404).
:func:`complete` adds each such status with the JSON error model (``ErrorResponse``) to
every operation, the Retry-After header to every 429 and 503, the Location header to every
202, and a schema to the CSV (text) and SVG (binary) bodies.  A route's own declaration of
a status is kept (its description), only filled in.
"""

from __future__ import annotations

from typing import Any

from .schemas import ErrorResponse

ERROR_REF = {"$ref": "#/components/schemas/ErrorResponse"}
RETRY_AFTER = {"Retry-After": {"description": "seconds to wait before asking again",
                               "schema": {"type": "integer"}}}
LOCATION = {"Location": {"description": "the path to poll (the body's url field)",
                         "schema": {"type": "string"}}}
# every operation can answer these (the service's layers, not the route)
EVERY = {
    "401": "the service has a token and the request lacks it (type 'unauthorized')",
    "408": "the request was not received within the read timeout (type "
           "'request_timeout'); the connection is closed",
    "413": "body over the limit (type 'body_too_large')",
    "422": "bad input; loc names the field",
    "429": "too many open connections from this client address (type "
           "'too_many_connections'), or a full job queue (the message says which)",
    "500": "internal error (type 'internal_error'; logged)",
    "503": "starting, the validation cache failed (type 'cache_unavailable'; /health says "
           "degraded), or too many open connections (type 'server_busy')",
}
WITH_BODY = {"400": "unreadable body (not JSON)"}
WITH_PATH = {"404": "unknown id (type 'not_found'; loc names the path parameter)"}
APP_RESPONSES = {int(code): {"model": ErrorResponse, "description": text}
                 for code, text in {**EVERY, **WITH_BODY}.items()}  # FastAPI(responses=...)
MEDIA_SCHEMA = {"text/csv": {"type": "string"},
                "image/svg+xml": {"type": "string", "format": "binary"}}


def _error_schemas(spec: dict[str, Any]) -> None:
    """ErrorResponse (and ErrorItem) in the components."""
    schemas = spec.setdefault("components", {}).setdefault("schemas", {})
    if "ErrorResponse" not in schemas:
        js = ErrorResponse.model_json_schema(ref_template="#/components/schemas/{model}")
        schemas.update(js.pop("$defs", {}))
        schemas["ErrorResponse"] = js


def _fill(code: str, response: dict[str, Any]) -> None:
    """A response's missing content (errors: JSON ErrorResponse) and headers."""
    content = response.setdefault("content", {})
    if code[0] in "45" and "application/json" not in content:
        content["application/json"] = {"schema": ERROR_REF}
    for media, schema in MEDIA_SCHEMA.items():
        if media in content and not content[media].get("schema"):
            content[media]["schema"] = schema
    if not content:
        del response["content"]
    if code in ("429", "503"):
        response.setdefault("headers", {}).update(RETRY_AFTER)
    if code == "202":
        response.setdefault("headers", {}).update(LOCATION)


# every JSON answer's provenance (api/stamp.py, dosing/provenance.py)
PROVENANCE = {
    "request": {"type": "object", "additionalProperties": True, "title": "Request",
                "description": "the request as the route resolved it (every default filled; "
                               "path and query parameters; 'route'), with 'units': the unit "
                               "of each physical field"},
    "version": {"$ref": "#/components/schemas/VersionOut"},
}
VERSION_SCHEMA = {
    "type": "object", "title": "VersionOut", "required": ["package", "code", "solver"],
    "description": "the versions that made an answer",
    "properties": {"package": {"type": "string", "description": "thermogel's version"},
                   "code": {"type": "string", "description": "the package version and the "
                            "checkout's git describe"},
                   "solver": {"type": "string", "description": "digest of the full solver's "
                              "sources (the validation cache's key)"}},
}


def _refs(schema: dict[str, Any]) -> list[str]:
    if "$ref" in schema:
        return [schema["$ref"].rsplit("/", 1)[-1]]
    return [r for key in ("anyOf", "oneOf") for sub in schema.get(key, []) for r in _refs(sub)]


def _provenance(spec: dict[str, Any]) -> None:
    """``request`` and ``version`` on every model a 2xx JSON answer is."""
    schemas = spec.setdefault("components", {}).setdefault("schemas", {})
    schemas.setdefault("VersionOut", VERSION_SCHEMA)
    for ops in spec.get("paths", {}).values():
        for op in ops.values():
            for code, response in op.get("responses", {}).items():
                js = response.get("content", {}).get("application/json", {}).get("schema")
                if not code.startswith("2") or not js:
                    continue
                for name in _refs(js):
                    props = schemas.get(name, {}).setdefault("properties", {})
                    for key, value in PROVENANCE.items():
                        props.setdefault(key, value)


def complete(spec: dict[str, Any]) -> dict[str, Any]:
    """Complete ``spec`` (FastAPI's OpenAPI dict) in place (module doc); return it."""
    _error_schemas(spec)
    _provenance(spec)
    for path, ops in spec.get("paths", {}).items():
        for op in ops.values():
            responses = op.setdefault("responses", {})
            wanted = dict(EVERY)
            if "requestBody" in op:
                wanted.update(WITH_BODY)
            if "{" in path:
                wanted.update(WITH_PATH)
            for code, text in wanted.items():
                responses.setdefault(code, {"description": text})
            for code, response in responses.items():
                _fill(code, response)
    return spec
