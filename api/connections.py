"""Per-connection guards under uvicorn: a read deadline and caps on open connections.

uvicorn (h11) times out only idle keep-alive connections: a client that opens a connection
and sends its request line, headers or body slowly (or never) holds it open indefinitely,
and nothing caps how many connections one client address holds.
:class:`GuardedH11Protocol` (uvicorn's ``http=`` protocol class) adds:

* a read deadline: a request must be read whole (request line, headers and body) within
  ``read_timeout`` seconds of its first byte (of the connection's opening, for the first
  request); past it the service answers 408 as JSON, unless an answer was started, and
  closes the connection;
* a cap of ``per_client`` open connections per client address: a connection beyond it has
  its request answered 429 as JSON with Retry-After, and is closed;
* a cap of ``total`` open connections: beyond it, 503 as JSON with Retry-After, then closed
  (uvicorn's own ``limit_concurrency`` answers in plain text, so it is left off).

The limits are defined once in :mod:`api.connection_limits`; ``thermogel serve`` passes
them to every worker process through the environment.  Counts are per worker process.
"""

from __future__ import annotations

import asyncio
import json
import os
from collections import Counter
from typing import Any

import h11
from uvicorn.protocols.http.h11_impl import H11Protocol

from .connection_limits import RETRY_AFTER_S, ConnectionLimits

MAX_DRAIN_BYTES = 1 << 20  # a refused request's body read (then dropped) before answering
_READ = (h11.DONE, h11.MUST_CLOSE, h11.CLOSED)  # the peer's states once a request is read


def error_body(loc: list[str], kind: str, msg: str) -> bytes:
    """The service's JSON error body (api.schemas.ErrorResponse)."""
    return json.dumps({"detail": [{"loc": loc, "type": kind, "msg": msg}]}).encode()


def _head(body: bytes, retry: bool) -> list[tuple[bytes, bytes]]:
    head = [(b"content-type", b"application/json"),
            (b"content-length", str(len(body)).encode()), (b"connection", b"close")]
    if retry:
        head.append((b"retry-after", str(RETRY_AFTER_S).encode()))
    return head


def refusal(status: int, kind: str, msg: str) -> Any:
    """An ASGI app answering every request ``status`` as JSON (Retry-After, connection
    closed), after reading and dropping its body (so that the close loses no answer)."""
    body = error_body(["connection"], kind, msg)

    async def app(scope: Any, receive: Any, send: Any) -> None:
        if scope["type"] != "http":
            return
        more, read = True, 0
        while more and read <= MAX_DRAIN_BYTES:
            message = await receive()
            if message["type"] != "http.request":
                return  # the client is gone
            read += len(message.get("body", b""))
            more = message.get("more_body", False)
        await send({"type": "http.response.start", "status": status,
                    "headers": _head(body, retry=True)})
        await send({"type": "http.response.body", "body": body})

    return app


TOO_MANY = ("too_many_connections", "this client address has too many open connections "
            "(thermogel serve --max-connections-per-client); close some and retry")
BUSY = ("server_busy", "the service has too many open connections "
        "(thermogel serve --limit-concurrency); retry shortly")
TIMEOUT_MSG = ("the request was not received in time (thermogel serve --read-timeout); "
               "the connection is closed")

_OPEN: Counter[str] = Counter()  # open connections per client address (the loop's thread)


class GuardedH11Protocol(H11Protocol):
    """uvicorn's h11 protocol with the read deadline and connection caps (module doc)."""

    limits: ConnectionLimits | None = None  # set on the class to override the environment

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        self.guard = type(self).limits or ConnectionLimits.from_env()
        self._deadline: asyncio.TimerHandle | None = None
        self._peer: str | None = None

    def connection_made(self, transport: asyncio.Transport) -> None:  # type: ignore[override]
        """Count the connection; beyond a cap, its requests are refused; start the clock."""
        super().connection_made(transport)
        self._peer = self.client[0] if self.client else None
        if self._peer is not None:
            _OPEN[self._peer] += 1
        if len(self.connections) > self.guard.total:
            self.app = refusal(503, *BUSY)
        elif self._peer is not None and _OPEN[self._peer] > self.guard.per_client:
            self.app = refusal(429, *TOO_MANY)
        self._arm()

    def connection_lost(self, exc: Exception | None) -> None:
        """Stop the clock and uncount the connection."""
        self._disarm()
        if self._peer is not None:
            _OPEN[self._peer] -= 1
            if _OPEN[self._peer] <= 0:
                del _OPEN[self._peer]
            self._peer = None
        super().connection_lost(exc)

    def data_received(self, data: bytes) -> None:
        """A request's first byte starts the clock; its last stops it."""
        if self._deadline is None and self.conn.their_state not in _READ:
            self._arm()
        super().data_received(data)
        if self.conn.their_state in _READ:
            self._disarm()

    def _arm(self) -> None:
        self._disarm()
        self._deadline = self.loop.call_later(self.guard.read_timeout, self._expired)

    def _disarm(self) -> None:
        if self._deadline is not None:
            self._deadline.cancel()
            self._deadline = None

    def _expired(self) -> None:
        """The request was not read in time: 408 as JSON if no answer was started, then
        close (the route, if one waits for the body, sees a disconnect)."""
        self._deadline = None
        transport = self.transport
        if transport is None or transport.is_closing() or self.conn.their_state in _READ:
            return
        cycle = self.cycle if self.conn.their_state is h11.SEND_BODY else None
        if cycle is None or not cycle.response_started:
            body = error_body(["connection"], "request_timeout", TIMEOUT_MSG)
            head = b"".join(k + b": " + v + b"\r\n"
                            for k, v in _head(body, retry=False))
            transport.write(b"HTTP/1.1 408 Request Timeout\r\n" + head + b"\r\n" + body)
        if cycle is not None:
            cycle.disconnected = True
            cycle.message_event.set()
        transport.close()


def uvicorn_options(limits: ConnectionLimits | None = None) -> dict[str, Any]:
    """uvicorn.run keywords for the guarded protocol (the limits through the environment
    when given, so that worker processes have them too)."""
    if limits is not None:
        os.environ.update(limits.to_env())
    return {"http": "api.connections:GuardedH11Protocol", "limit_concurrency": None}
