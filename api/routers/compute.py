"""Running blocking physics and planner calls from a route: in worker threads, guarded.

The calls share a pool of ``COMPUTE_THREADS`` threads per event loop (not anyio's default
40): the rest wait in the pool's queue, costing nothing, so that a burst of requests
cannot starve the loop of the GIL and /health (answered on the loop, no thread) stays
prompt.  The pool is a ``concurrent.futures.ThreadPoolExecutor``: a thread that finishes
a call takes the next queued one at once, where a limiter on the loop (anyio's
``CapacityLimiter``, used before) woke a waiting task on the loop and then a sleeping
thread for each call; with 16 concurrent dose requests that saved about a quarter of a
request's CPU in process (docs/speed.md sec. 6.1).  A queued call whose request is gone
(its task cancelled) is dropped; a running one finishes and its result is dropped.

Work that is not a millisecond answer never runs on those threads (issue 40, R4/R5): it
goes to a :class:`Bounded` executor of its own, one thread each, a few calls queued before
a 429 with Retry-After: ``ANALYSIS`` (POST /v1/sensitivity: seconds of front-model
samples) and ``RENDER`` (figures and big tables: a sweep's SVG, its table as JSON or CSV the
first time, the phase map).  However many such requests arrive, the compute threads stay
free for front doses and /health (answered on the loop) stays prompt.
"""

from __future__ import annotations

import asyncio
import contextvars
import weakref
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from functools import partial
from typing import Any

from dosing import QueueFullError

from ..service import solver_guard

COMPUTE_THREADS = 4
_POOLS: weakref.WeakKeyDictionary[asyncio.AbstractEventLoop, ThreadPoolExecutor] = \
    weakref.WeakKeyDictionary()


def _guarded(fn: Callable[..., Any], *args: Any) -> Any:
    with solver_guard():
        return fn(*args)


def pool() -> ThreadPoolExecutor:
    """The compute threads of the running event loop (one pool per loop, its threads
    stopped once the loop is gone)."""
    loop = asyncio.get_running_loop()
    ex = _POOLS.get(loop)
    if ex is None:
        ex = _POOLS[loop] = ThreadPoolExecutor(COMPUTE_THREADS,
                                               thread_name_prefix="thermogel-compute")
        weakref.finalize(loop, ex.shutdown, wait=False, cancel_futures=True)
    return ex


async def compute(fn: Callable[..., Any], *args: Any) -> Any:
    """Run a blocking physics or planner call in a compute thread (the caller's context
    variables copied to it), under :func:`solver_guard` (an input or solver error passes;
    a cache failure is a 503, any other failure a 500)."""
    ctx = contextvars.copy_context()
    return await asyncio.get_running_loop().run_in_executor(
        pool(), partial(ctx.run, _guarded, fn, *args))


class Bounded:
    """A named executor of ``threads`` threads (one pool per event loop, like
    :func:`pool`) admitting at most ``limit`` calls queued or running: one more raises
    ``QueueFullError`` (HTTP 429 naming ``what``, with Retry-After)."""

    def __init__(self, name: str, threads: int, limit: int, what: str,
                 retry_after: float = 5.0) -> None:
        self.name, self.threads, self.limit = name, threads, limit
        self.what, self.retry_after = what, retry_after
        self._pools: weakref.WeakKeyDictionary[asyncio.AbstractEventLoop, ThreadPoolExecutor] \
            = weakref.WeakKeyDictionary()
        self.pending = 0  # changed on the event loop only

    def _pool(self) -> ThreadPoolExecutor:
        loop = asyncio.get_running_loop()
        ex = self._pools.get(loop)
        if ex is None:
            ex = self._pools[loop] = ThreadPoolExecutor(
                self.threads, thread_name_prefix=f"thermogel-{self.name}")
            weakref.finalize(loop, ex.shutdown, wait=False, cancel_futures=True)
        return ex

    async def run(self, fn: Callable[..., Any], *args: Any) -> Any:
        """Run a blocking call here (as :func:`compute` does on the compute threads), or
        refuse it at once when ``limit`` calls are queued or running."""
        if self.pending >= self.limit:
            raise QueueFullError(self.pending, self.retry_after, self.what, self.limit)
        self.pending += 1
        try:
            ctx = contextvars.copy_context()
            return await asyncio.get_running_loop().run_in_executor(
                self._pool(), partial(ctx.run, _guarded, fn, *args))
        finally:
            self.pending -= 1


ANALYSIS = Bounded("analysis", 1, 8, "sensitivity analyses", retry_after=10.0)
RENDER = Bounded("render", 1, 8, "figure and table renders")
