"""Memory a large request leaves behind, handed back to the system (issue 40, R7).

CPython frees a request's objects at once, but glibc's allocator keeps the freed pages of a
large body (a 100,000-row trace is ~1 MB of JSON and ~10x that as objects) in its arenas, so
the process's RSS only grows.  After a request whose body is larger than ``LARGE_BODY``, this
middleware asks glibc to return free memory (``malloc_trim(0)``), and the service's threads
share two arenas (``mallopt(M_ARENA_MAX, 2)``); elsewhere it does nothing.
"""

from __future__ import annotations

import ctypes
import ctypes.util
import functools
from typing import Any

LARGE_BODY = 256 * 1024  # bytes: a request this large is followed by a trim


@functools.cache
def _trim() -> Any:
    """glibc's malloc_trim, or None (another C library)."""
    name = ctypes.util.find_library("c")
    try:
        fn = ctypes.CDLL(name).malloc_trim if name else None
    except (OSError, AttributeError):
        return None
    if fn is not None:
        fn.argtypes, fn.restype = [ctypes.c_size_t], ctypes.c_int
    return fn


M_ARENA_MAX = -8  # glibc's mallopt parameter
ARENAS = 2  # the service's threads share two arenas: freed pages are found again


def limit_arenas() -> None:
    """Let the service's many threads share ``ARENAS`` malloc arenas (glibc's default is
    8 per core, each keeping its own freed pages), else nothing."""
    name = ctypes.util.find_library("c")
    try:
        fn = ctypes.CDLL(name).mallopt if name else None
    except (OSError, AttributeError):
        return
    if fn is not None:
        fn.argtypes, fn.restype = [ctypes.c_int, ctypes.c_int], ctypes.c_int
        fn(M_ARENA_MAX, ARENAS)


def release() -> None:
    """Hand the allocator's free memory back to the system (glibc), else nothing."""
    fn = _trim()
    if fn is not None:
        fn(0)


class ReleaseAfterLarge:
    """ASGI middleware: after a request with a body over ``LARGE_BODY`` bytes, release."""

    def __init__(self, app: Any) -> None:
        self.app = app
        limit_arenas()

    async def __call__(self, scope: dict, receive: Any, send: Any) -> None:
        if scope.get("type") != "http":
            await self.app(scope, receive, send)
            return
        length = dict(scope.get("headers") or []).get(b"content-length", b"0")
        try:
            large = int(length) > LARGE_BODY
        except ValueError:
            large = False
        try:
            await self.app(scope, receive, send)
        finally:
            if large:
                import gc

                from starlette.concurrency import run_in_threadpool

                gc.collect()
                await run_in_threadpool(release)
