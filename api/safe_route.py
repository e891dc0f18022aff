"""Request bodies a route can read safely: no lone UTF-16 surrogate in any JSON string.

JSON allows ``"\\ud800"`` (an escape of half a surrogate pair), Python's ``json`` decodes it
into a ``str`` that cannot be encoded as UTF-8, and every later step (an error answer, a
cache key, a file name) would fail on it.  :class:`SafeRoute` reads the body before the
route does and refuses such a body with a 422 whose ``loc`` names the string (or the key)
holding it; every router of the service uses it (``APIRouter(route_class=SafeRoute)``).
"""

from __future__ import annotations

import json
import re
from collections.abc import Callable, Coroutine, Iterator
from typing import Any

from fastapi import Request, Response
from fastapi.exceptions import RequestValidationError
from fastapi.routing import APIRoute

from .stamp import stamp_response

_ESCAPE = re.compile(rb"\\u[dD][89abcdefABCDEF]")  # the escape of a surrogate half
_SURROGATE = re.compile("[\ud800-\udfff]")
MSG = "a lone UTF-16 surrogate (e.g. \\ud800) is not text: remove it"


def has_surrogate(text: str) -> bool:
    """True if ``text`` holds a lone surrogate code point (not encodable as UTF-8)."""
    return _SURROGATE.search(text) is not None


def printable(text: str, limit: int = 80) -> str:
    """``text`` cut to ``limit`` characters, surrogates written as escapes (UTF-8 safe)."""
    cut = text if len(text) <= limit else text[:limit] + "..."
    return cut.encode("utf-8", "backslashreplace").decode("utf-8")


def surrogate_locs(value: Any, loc: tuple[str | int, ...] = ("body",)) -> Iterator[
        tuple[str | int, ...]]:
    """Where ``value`` (decoded JSON) holds a lone surrogate: in a string, or in a key."""
    if isinstance(value, str):
        if has_surrogate(value):
            yield loc
    elif isinstance(value, list):
        for i, item in enumerate(value):
            yield from surrogate_locs(item, (*loc, i))
    elif isinstance(value, dict):
        for key, item in value.items():
            name = printable(str(key))
            if has_surrogate(str(key)):
                yield (*loc, name)
            yield from surrogate_locs(item, (*loc, name))


async def check_body(request: Request) -> None:
    """Raise RequestValidationError (422) if the JSON body holds a lone surrogate."""
    if request.method not in ("POST", "PUT", "PATCH"):
        return
    body = await request.body()  # kept on the request: the route reads it again for free
    if not body or _ESCAPE.search(body) is None:
        return
    try:
        parsed = json.loads(body)
    except ValueError:
        return  # the route's own parse reports it
    locs = list(surrogate_locs(parsed))
    if locs:
        raise RequestValidationError([
            {"loc": loc, "msg": MSG, "type": "string_unicode", "input": "\\ud800"}
            for loc in locs[:20]])


class SafeRoute(APIRoute):
    """An APIRoute whose JSON body is checked by :func:`check_body` first, and whose JSON
    answers carry ``request`` and ``version`` (:func:`api.stamp.stamp_response`)."""

    def get_route_handler(self) -> Callable[[Request], Coroutine[Any, Any, Response]]:
        handler = super().get_route_handler()

        async def safe_handler(request: Request) -> Response:
            await check_body(request)
            return await stamp_response(self, request, await handler(request))

        return safe_handler
