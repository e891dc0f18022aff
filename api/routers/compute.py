"""Running blocking physics and planner calls from a route: in worker threads, guarded.

The calls share a limiter of ``COMPUTE_THREADS`` threads (not anyio's default 40): the
rest wait on the event loop, costing nothing, so that a burst of requests cannot starve
the loop of the GIL and /health (answered on the loop, no thread) stays prompt.
"""

from __future__ import annotations

import asyncio
import weakref
from collections.abc import Callable
from functools import partial
from typing import Any

import anyio.to_thread

from ..service import solver_guard

COMPUTE_THREADS = 4
_LIMITERS: weakref.WeakKeyDictionary[Any, anyio.CapacityLimiter] = weakref.WeakKeyDictionary()


def _guarded(fn: Callable[..., Any], *args: Any) -> Any:
    with solver_guard():
        return fn(*args)


def limiter() -> anyio.CapacityLimiter:
    """The compute threads' limiter of the running event loop (one per loop: a limiter
    is bound to the loop it is first used in)."""
    loop = asyncio.get_running_loop()
    lim = _LIMITERS.get(loop)
    if lim is None:
        lim = _LIMITERS[loop] = anyio.CapacityLimiter(COMPUTE_THREADS)
    return lim


async def compute(fn: Callable[..., Any], *args: Any) -> Any:
    """Run a blocking physics or planner call in a compute thread, under
    :func:`solver_guard` (an input or solver error passes; a cache failure is a 503, any
    other failure a 500)."""
    return await anyio.to_thread.run_sync(partial(_guarded, fn, *args), limiter=limiter())
