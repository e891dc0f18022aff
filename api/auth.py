"""An optional API token: ``Authorization: Bearer <token>`` on every route but /health, and
the Host check (DNS rebinding).

Off when no token is configured (the loopback default); ``thermogel serve`` requires one
when it binds beyond loopback (``--token`` or ``$THERMOGEL_API_TOKEN``), e.g. in the Docker
image.  /health stays open for the container's health check.  A wrong or missing token is
a 401 JSON error; the comparison is constant-time.

:class:`HostCheck` accepts only the Host headers listed (``--allowed-hosts``): a name alone
matches it with any port (``localhost`` takes ``localhost:8000``), a name with a port that
port only (``example.org:8443``), ``*.example.org`` its subdomains, ``*`` anything; IPv6
literals in brackets (``[::1]``).  A loopback server checks by default (``LOOPBACK_HOSTS``):
a page from elsewhere that rebinds its DNS name to 127.0.0.1 sends its own name as the Host
and is refused (400 as JSON naming the header).
"""

from __future__ import annotations

import hmac
import json

from starlette.types import ASGIApp, Receive, Scope, Send

OPEN_PATHS = ("/health",)
LOOPBACK = ("127.0.0.1", "::1", "localhost")
LOOPBACK_HOSTS = ("localhost", "127.0.0.1", "[::1]")  # a loopback server's default Hosts
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


BAD_HOST = json.dumps({"detail": [{
    "loc": ["header", "host"], "type": "bad_request",
    "msg": "invalid host header: this service answers only the Host names it was started "
           "for (thermogel serve --allowed-hosts)"}]}).encode()


def split_host(value: str) -> tuple[str, str | None]:
    """(name in lower case, port or None) of a Host header or an allowed-hosts entry:
    'localhost:8000' -> ('localhost', '8000'), '[::1]:80' -> ('[::1]', '80'), '::1' ->
    ('[::1]', None)."""
    v = value.strip().lower()
    if v.startswith("["):
        end = v.find("]")
        if end < 0:
            return v, None
        rest = v[end + 1:]
        return v[:end + 1], rest[1:] if rest.startswith(":") else None
    if v.count(":") > 1:  # a bare IPv6 literal
        return f"[{v}]", None
    name, _, port = v.partition(":")
    return name, port or None


class HostCheck:
    """ASGI middleware: refuse a Host header outside ``allowed`` (module doc)."""

    def __init__(self, app: ASGIApp, allowed: list[str]) -> None:
        self.app = app
        self.any = "*" in allowed
        self.allowed = [split_host(a) for a in allowed if a.strip() and a.strip() != "*"]

    def accepts(self, host: str) -> bool:
        """Whether a Host header's value is allowed."""
        if self.any:
            return True
        name, port = split_host(host)
        if not name:
            return False
        for a_name, a_port in self.allowed:
            if a_port is not None and a_port != port:
                continue
            if a_name == name or (a_name.startswith("*.") and name.endswith(a_name[1:])):
                return True
        return False

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] not in ("http", "websocket"):
            await self.app(scope, receive, send)
            return
        host = dict(scope.get("headers") or []).get(b"host", b"").decode("latin-1")
        if self.accepts(host):
            await self.app(scope, receive, send)
            return
        await send({"type": "http.response.start", "status": 400,
                    "headers": [(b"content-type", b"application/json"),
                                (b"content-length", str(len(BAD_HOST)).encode())]})
        await send({"type": "http.response.body", "body": BAD_HOST})
