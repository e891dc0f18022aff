"""An optional API token: ``Authorization: Bearer <token>`` on every route but /health.

Off when no token is configured (the loopback default); ``thermogel serve`` requires one
when it binds beyond loopback (``--token`` or ``$THERMOGEL_API_TOKEN``), e.g. in the Docker
image.  /health stays open for the container's health check.  A wrong or missing token is
a 401 JSON error; the comparison is constant-time.
"""

from __future__ import annotations

import hmac
import json

from starlette.types import ASGIApp, Receive, Scope, Send

OPEN_PATHS = ("/health",)
LOOPBACK = ("127.0.0.1", "::1", "localhost")
UNAUTHORIZED = json.dumps({"detail": [{
    "loc": ["header", "authorization"], "type": "unauthorized",
    "msg": "this service needs 'Authorization: Bearer <token>' (thermogel serve --token)"}]
}).encode()


def is_loopback(host: str) -> bool:
    """True for an interface only this machine reaches."""
    return host in LOOPBACK or host.startswith("127.")


class TokenAuth:
    """ASGI middleware checking the bearer token (module doc)."""

    def __init__(self, app: ASGIApp, token: str) -> None:
        self.app = app
        self.expected = f"Bearer {token}".encode()

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] != "http" or scope.get("path") in OPEN_PATHS:
            await self.app(scope, receive, send)
            return
        given = dict(scope.get("headers") or []).get(b"authorization", b"")
        if hmac.compare_digest(given, self.expected):
            await self.app(scope, receive, send)
            return
        await send({"type": "http.response.start", "status": 401,
                    "headers": [(b"content-type", b"application/json"),
                                (b"content-length", str(len(UNAUTHORIZED)).encode()),
                                (b"www-authenticate", b"Bearer")]})
        await send({"type": "http.response.body", "body": UNAUTHORIZED})
