"""The outermost ASGI layer of the service: every answer is JSON, no exception escapes.

* An error answer that is not JSON (Starlette's 413 from the body limit, the allowed-host
  check's 400, both ``text/plain``) is rewritten as the JSON error body the OpenAPI
  description promises: ``{"detail": [{"loc", "type", "msg"}]}``.
* An exception no handler took (a bug) is answered 500 ``internal_error`` as JSON and
  logged; it is not re-raised, so uvicorn keeps the keep-alive connection open instead of
  resetting it.  A client gone while its body was read (``ClientDisconnect``: it hung up,
  or :mod:`api.connections` cut it off) is not an error and gets no answer.
"""

from __future__ import annotations

import json
import logging
from typing import Any

from fastapi import FastAPI
from fastapi._body_limit import get_body_limit_error
from starlette.exceptions import HTTPException
from starlette.requests import ClientDisconnect
from starlette.types import ASGIApp, Message, Receive, Scope, Send

log = logging.getLogger("thermogel.service")

TOO_LARGE = {"detail": [{"loc": ["body"], "type": "body_too_large",
                         "msg": "the request body is over the service's limit "
                                "(thermogel serve --max-body-bytes)"}]}
INTERNAL = {"detail": [{"loc": [], "type": "internal_error",
                        "msg": "internal server error: the service failed on this request "
                               "(logged); please report it"}]}
# the error kind of a non-JSON error answer rewritten as JSON
KINDS = {400: "bad_request", 401: "unauthorized", 403: "forbidden", 404: "not_found",
         405: "method_not_allowed", 408: "request_timeout", 429: "too_many_requests",
         500: "internal_error", 503: "unavailable"}
PLAIN_CHARS = 200  # the plain-text message kept


def json_error(status: int, text: bytes) -> bytes:
    """The JSON error body standing in for a plain-text error answer."""
    if status == 413:
        return json.dumps(TOO_LARGE).encode()
    msg = text[:PLAIN_CHARS].decode("utf-8", "replace").strip() or "error"
    loc = ["header", "host"] if msg.lower() == "invalid host header" else []
    return json.dumps({"detail": [{"loc": loc, "type": KINDS.get(status, "http_error"),
                                   "msg": msg}]}).encode()


def _json_start(status: int, body: bytes, headers: list[tuple[bytes, bytes]] | None = None
                ) -> Message:
    keep = [(k, v) for k, v in headers or []
            if k.lower() not in (b"content-type", b"content-length")]
    return {"type": "http.response.start", "status": status,
            "headers": [*keep, (b"content-type", b"application/json"),
                        (b"content-length", str(len(body)).encode())]}


class JsonGuard:
    """ASGI middleware: non-JSON error answers as JSON (``json_errors``), uncaught
    exceptions as a JSON 500 (``catch``)."""

    def __init__(self, app: ASGIApp, json_errors: bool = True, catch: bool = True) -> None:
        self.app = app
        self.json_errors = json_errors
        self.catch = catch

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] != "http":
            await self.app(scope, receive, send)
            return
        started = False
        rewrite: Message | None = None  # the start of a plain error answer being rewritten
        text = b""

        async def guarded_send(message: Message) -> None:
            nonlocal started, rewrite, text
            if message["type"] == "http.response.start":
                started = True
                ctype = dict(message.get("headers", [])).get(b"content-type", b"")
                if self.json_errors and message["status"] >= 400 \
                        and not ctype.startswith(b"application/json"):
                    rewrite = message
                    return
            elif rewrite is not None:  # collect the plain body, answer when it is whole
                if len(text) < PLAIN_CHARS:
                    text += message.get("body", b"")
                if not message.get("more_body", False):
                    body = json_error(rewrite["status"], text)
                    await send(_json_start(rewrite["status"], body, rewrite.get("headers")))
                    await send({"type": "http.response.body", "body": body})
                return
            await send(message)

        try:
            await self.app(scope, receive, guarded_send)
        except ClientDisconnect:
            return  # the client is gone: nobody to answer
        except Exception as exc:
            if not self.catch or isinstance(exc, HTTPException) \
                    or get_body_limit_error(exc) is not None:
                raise  # the body limit's own signal, or not ours to catch
            log.exception("unhandled exception on %s %s", scope.get("method"),
                          scope.get("path"))
            if started:
                raise  # too late to answer: uvicorn closes the connection
            body = json.dumps(INTERNAL).encode()
            await send(_json_start(500, body))
            await send({"type": "http.response.body", "body": body})


class GuardedFastAPI(FastAPI):
    """FastAPI with :class:`JsonGuard` twice: outermost (the body limit's 413 and the host
    check's 400, plain text, become JSON) and inside Starlette's ServerErrorMiddleware (an
    uncaught exception becomes a JSON 500 without closing the connection)."""

    def openapi(self) -> dict[str, Any]:
        """The OpenAPI description, completed (:func:`api.openapi_spec.complete`)."""
        if self.openapi_schema is None:
            from .openapi_spec import complete

            self.openapi_schema = complete(super().openapi())
        return self.openapi_schema

    def build_middleware_stack(self) -> ASGIApp:
        return JsonGuard(super().build_middleware_stack(), json_errors=True, catch=False)


def add(app: Any) -> None:
    """Install the inner :class:`JsonGuard` (a user middleware: inside ServerErrorMiddleware,
    outside the routes and their exception handlers)."""
    app.add_middleware(JsonGuard, json_errors=False, catch=True)
