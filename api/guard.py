"""The outermost ASGI layer of the service: every answer is JSON, no exception escapes.

* A 413 from the body limit (Starlette answers it as ``text/plain``) is rewritten as the
  JSON error body the OpenAPI description promises: ``{"detail": "..."}``.
* An exception no handler took (a bug) is answered 500 ``internal_error`` as JSON and
  logged; it is not re-raised, so uvicorn keeps the keep-alive connection open instead of
  resetting it.
"""

from __future__ import annotations

import json
import logging
from typing import Any

from fastapi import FastAPI
from fastapi._body_limit import get_body_limit_error
from starlette.exceptions import HTTPException
from starlette.types import ASGIApp, Message, Receive, Scope, Send

log = logging.getLogger("thermogel.service")

TOO_LARGE = {"detail": [{"loc": ["body"], "type": "body_too_large",
                         "msg": "the request body is over the service's limit "
                                "(thermogel serve --max-body-bytes)"}]}
INTERNAL = {"detail": [{"loc": [], "type": "internal_error",
                        "msg": "internal server error: the service failed on this request "
                               "(logged); please report it"}]}


def _json_start(status: int, body: bytes, headers: list[tuple[bytes, bytes]] | None = None
                ) -> Message:
    keep = [(k, v) for k, v in headers or []
            if k.lower() not in (b"content-type", b"content-length")]
    return {"type": "http.response.start", "status": status,
            "headers": [*keep, (b"content-type", b"application/json"),
                        (b"content-length", str(len(body)).encode())]}


class JsonGuard:
    """ASGI middleware: 413 as JSON (``json_413``), uncaught exceptions as a JSON 500
    (``catch``)."""

    def __init__(self, app: ASGIApp, json_413: bool = True, catch: bool = True) -> None:
        self.app = app
        self.json_413 = json_413
        self.catch = catch

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] != "http":
            await self.app(scope, receive, send)
            return
        started = False
        rewrite = False

        async def guarded_send(message: Message) -> None:
            nonlocal started, rewrite
            if message["type"] == "http.response.start":
                started = True
                ctype = dict(message.get("headers", [])).get(b"content-type", b"")
                if self.json_413 and message["status"] == 413 \
                        and not ctype.startswith(b"application/json"):
                    rewrite = True
                    body = json.dumps(TOO_LARGE).encode()
                    await send(_json_start(413, body, message.get("headers")))
                    await send({"type": "http.response.body", "body": body})
                    return
            elif rewrite:
                return  # the plain-text body is replaced
            await send(message)

        try:
            await self.app(scope, receive, guarded_send)
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
    """FastAPI with :class:`JsonGuard` twice: outermost (the body limit's 413, sent outside
    every user middleware, becomes JSON) and inside Starlette's ServerErrorMiddleware (an
    uncaught exception becomes a JSON 500 without closing the connection)."""

    def build_middleware_stack(self) -> ASGIApp:
        return JsonGuard(super().build_middleware_stack(), json_413=True, catch=False)


def add(app: Any) -> None:
    """Install the inner :class:`JsonGuard` (a user middleware: inside ServerErrorMiddleware,
    outside the routes and their exception handlers)."""
    app.add_middleware(JsonGuard, json_413=False, catch=True)
