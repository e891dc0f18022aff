"""Exceptions to HTTP answers: one table, one handler.

Every error answer has the shape ``{"detail": [{"loc", "msg", "type", ...}]}`` (a 429 and
a 413 carry a message string): ``loc`` names the field (``['body', 'doses', 1]``) or the
path parameter.  Validation errors echo at most a short excerpt of the offending input,
never the input itself: an excerpt is always strict JSON (NaN and Infinity as text), so a
non-finite number cannot turn a 422 into a 500.
"""

from __future__ import annotations

import logging
import math
import re
import sqlite3
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from fastapi import FastAPI, Request
from fastapi.exceptions import RequestValidationError
from fastapi.responses import JSONResponse

from dosing import QueueFullError, UnknownValidationError
from solver.errors import NotApplicableError, ParameterError, SolverError

from .safe_route import printable

RETRY_AFTER_SECONDS = 5
# the path parameter of each kind's own poll route (a 404 names the id where it was given)
_ID_PARAM = {"sweep": "sweep_id", "fit": "job_id", "design": "job_id", "schedule": "validation_id",
             "drug-dose": "validation_id", "batch-schedule": "validation_id",
             "dose": "validation_id", "validation": "validation_id"}


def job_kind(job_id: Any) -> str:
    """The kind of job an id names (its prefix; a dose validation has none)."""
    for kind in ("sweep", "fit", "design", "schedule", "drug-dose", "batch-schedule", "dose"):
        if str(job_id).startswith(kind + "-"):
            return kind
    return "validation"
MAX_ERRORS = 20  # validation errors reported per answer
EXCERPT_CHARS = 80
MSG_CHARS = 400


class ServiceUnavailable(RuntimeError):
    """The planner is not ready (start-up not finished, or shut down)."""


class CacheFault(RuntimeError):
    """The validation cache failed (SQLite: disk full, a malformed page, an I/O error): a
    server fault, HTTP 503 naming the cache; /health says 'degraded' for a while."""

    def __init__(self, reason: str) -> None:
        super().__init__(f"the validation cache failed: {reason}; the service is degraded "
                         "(an operator must free disk space or repair the cache file)")
        self.reason = reason


class InternalError(RuntimeError):
    """An unexpected exception in the service: HTTP 500 with the stable code
    'internal_error' (the traceback goes to the log, not to the client)."""


def loc_of(name: str | None, root: str = "body") -> list[str | int]:
    """[root, ...] from a dotted field name with indices: 'doses[1]' -> body, doses, 1."""
    out: list[str | int] = [root]
    for part in re.findall(r"[^.\[\]]+", name or ""):
        out.append(int(part) if part.isdigit() else part)
    return out


def excerpt(value: Any) -> str | float | int | bool | None:
    """A short, strict-JSON stand-in for an input value."""
    if value is None or isinstance(value, (bool, int)):
        return value if not isinstance(value, int) or abs(value) < 10**15 else str(value)[:24]
    if isinstance(value, float):
        return value if math.isfinite(value) else str(value)
    if isinstance(value, str):
        return printable(value, EXCERPT_CHARS)
    if isinstance(value, (list, tuple)):
        return f"a list of {len(value)} items"
    if isinstance(value, dict):
        keys = ", ".join(printable(str(k), 20) for k in list(value)[:8])
        return printable(f"an object with keys {keys}" + (", ..." if len(value) > 8 else ""),
                         EXCERPT_CHARS)
    return type(value).__name__


def _item(loc: list[str | int], msg: str, kind: str, **extra: Any) -> dict[str, Any]:
    """One error item, UTF-8 safe and short: a 100 kB unknown key is echoed as 80 chars."""
    loc = [p if isinstance(p, int) else printable(str(p), EXCERPT_CHARS) for p in loc]
    return {"loc": loc, "msg": printable(msg, MSG_CHARS), "type": printable(kind, 40),
            **extra}


@dataclass(frozen=True)
class Rule:
    """How one exception class answers: status, error kind, where and what."""

    status: int
    kind: str
    loc: Callable[[Exception], list[str | int]] = lambda e: ["body"]
    msg: Callable[[Exception], str] = str
    extra: Callable[[Exception], dict[str, Any]] = lambda e: {}
    headers: Callable[[Exception], dict[str, str]] = lambda e: {}
    plain: bool = False  # detail is the message string, not a list of items


def _retry(exc: Exception) -> dict[str, str]:
    seconds = getattr(exc, "retry_after", RETRY_AFTER_SECONDS)
    return {"Retry-After": str(max(1, math.ceil(seconds)))}


# the table (a subclass such as BudgetExceeded finds its base: the MRO is walked)
ERRORS: dict[type[Exception], Rule] = {
    ParameterError: Rule(422, "parameter_error", loc=lambda e: loc_of(e.field),
                         extra=lambda e: {"valid": e.valid}),
    NotApplicableError: Rule(422, "not_applicable",
                             loc=lambda e: loc_of(getattr(e, "field", None))),
    SolverError: Rule(422, "solver_error",
                      msg=lambda e: f"the solver could not answer this scenario: {e}"),
    QueueFullError: Rule(429, "queue_full", headers=_retry, plain=True),
    UnknownValidationError: Rule(
        404, "not_found", loc=lambda e: ["path", e.args[1] if len(e.args) > 1
                                         else _ID_PARAM[job_kind(e.args[0])]],
        msg=lambda e: (f"no {job_kind(e.args[0])} job with id {e.args[0]!r}"
                       if job_kind(e.args[0]) != "validation"
                       else f"no validation with id {e.args[0]!r}")
        + (f" here: {e.args[2]}" if len(e.args) > 2 else "")),
    ServiceUnavailable: Rule(503, "unavailable", plain=True,
                             headers=lambda e: {"Retry-After": str(RETRY_AFTER_SECONDS)}),
    CacheFault: Rule(503, "cache_unavailable", loc=lambda e: ["cache"],
                     headers=lambda e: {"Retry-After": str(6 * RETRY_AFTER_SECONDS)}),
    InternalError: Rule(500, "internal_error",
                        msg=lambda e: "internal server error: the service failed on this "
                                      "request (logged); please report it"),
}


def rule_for(exc: Exception) -> Rule | None:
    """The table's rule for ``exc`` (its class or nearest base), or None."""
    for cls in type(exc).__mro__:
        if cls in ERRORS:
            return ERRORS[cls]
    return None


def error_response(exc: Exception, model: Any = None, body: Any = None) -> JSONResponse:
    """The answer to a table exception (``model``: the route's body model, whose fields a
    ``loc`` under 'body' must name: :func:`known_loc`; ``body``: the request's JSON, where
    a derived value's field must be given, not null or absent)."""
    rule = rule_for(exc)
    assert rule is not None, type(exc)
    loc = rule.loc(exc)
    if model is not None and loc[:1] == ["body"]:
        loc = known_loc(loc, model)
    if (isinstance(body, dict) and len(loc) > 1 and loc[0] == "body"
            and body.get(loc[1]) is None and getattr(exc, "value", None) is not None):
        loc = ["body"]  # a value the planner derived (a batch's mean) for a field not given
    detail: Any = (rule.msg(exc) if rule.plain else
                   [_item(loc, rule.msg(exc), rule.kind, **rule.extra(exc))])
    return JSONResponse({"detail": detail}, status_code=rule.status, headers=rule.headers(exc))


def _fields(model: Any) -> dict[str, Any]:
    """A pydantic model's fields by name and by alias."""
    fields = getattr(model, "model_fields", None) or {}
    out = dict(fields)
    out.update({f.alias: f for f in fields.values() if getattr(f, "alias", None)})
    return out


def _model_in(annotation: Any) -> Any:
    """The pydantic model inside an annotation (``X | None``, ``list[X]``), or None."""
    if isinstance(annotation, type) and hasattr(annotation, "model_fields"):
        return annotation
    for arg in getattr(annotation, "__args__", ()) or ():
        found = _model_in(arg)
        if found is not None:
            return found
    return None


def known_loc(loc: list[str | int], model: Any) -> list[str | int]:
    """``loc`` cut at its first part the request's model does not have: an error found deep
    in the planner (a solver's 'targets', a derived 'data') points at the body, or at the
    deepest field the request has, never at a field it lacks (issue 40, R10)."""
    out: list[str | int] = [loc[0]]
    current = model
    for part in loc[1:]:
        if isinstance(part, int):  # an index into a list field: kept
            out.append(part)
            continue
        fields = _fields(current) if current is not None else {}
        if part not in fields:
            if current is None and len(out) > 1:  # a free-form value (a protocol step)
                out.append(part)
                continue
            break
        out.append(part)
        current = _model_in(fields[part].annotation)
    return out


def _route_model(request: Request) -> Any:
    route = request.scope.get("route")
    body = getattr(route, "body_field", None)
    info = getattr(body, "field_info", None)
    return _model_in(getattr(body, "type_", None) or getattr(body, "annotation", None)
                     or getattr(info, "annotation", None))


async def _table_handler(request: Request, exc: Exception) -> JSONResponse:
    if isinstance(exc, CacheFault):  # /health reports it
        state = getattr(request.app.state, "service", None)
        if state is not None and hasattr(state, "record_fault"):
            state.record_fault(exc.reason)
    return error_response(exc, _route_model(request), _json_body(request))


def _json_body(request: Request) -> Any:
    """The request's JSON body as the route read it (kept on the request), or None."""
    raw = getattr(request, "_body", None)
    if not raw or len(raw) > (4 << 20):
        return None
    try:
        import json

        return json.loads(raw)
    except ValueError:
        return None


async def _validation_handler(_: Request, exc: Exception) -> JSONResponse:
    """422 for pydantic's errors: loc, msg, type and an excerpt of the input (no echo)."""
    errors = list(exc.errors())  # type: ignore[attr-defined]
    items = [_item(list(e.get("loc", ["body"])), str(e.get("msg", "invalid")),
                   str(e.get("type", "value_error")), input=excerpt(e.get("input")))
             for e in errors[:MAX_ERRORS]]
    if len(errors) > MAX_ERRORS:
        items.append(_item(["body"], f"{len(errors) - MAX_ERRORS} more errors not shown",
                           "truncated"))
    return JSONResponse({"detail": items}, status_code=422)


def install(app: FastAPI) -> None:
    """Register the table's handler for each of its classes, and the 422 handler."""
    for cls in ERRORS:
        app.add_exception_handler(cls, _table_handler)
    app.add_exception_handler(RequestValidationError, _validation_handler)


class FaultWatch(logging.Handler):
    """A log handler on the 'thermogel' loggers: a cache failure logged anywhere in the
    process (a job thread, a validation, the health probe; a request's is recorded by
    :func:`_table_handler`) makes /health 'degraded' (issue 40, R10: it said 'ok' on a
    cache the log already called malformed)."""

    WORDS = ("malformed", "disk is full", "disk i/o error", "not a database")

    def __init__(self, record_fault: Callable[[str], None]) -> None:
        super().__init__(logging.WARNING)
        self.record_fault = record_fault

    def emit(self, record: logging.LogRecord) -> None:
        try:
            exc = record.exc_info[1] if record.exc_info else None
            text = str(exc) if isinstance(exc, sqlite3.Error) else None
            if text is None:
                msg = record.getMessage().lower()
                if any(w in msg for w in self.WORDS):
                    text = record.getMessage()
            if text:
                self.record_fault(text[:300])
        except Exception:  # a log handler never raises
            pass


def watch_faults(state: Any) -> Callable[[], None]:
    """Install a :class:`FaultWatch` for ``state`` (its ``record_fault``); the remover."""
    handler = FaultWatch(state.record_fault)
    logger = logging.getLogger("thermogel")
    logger.addHandler(handler)
    return lambda: logger.removeHandler(handler)
