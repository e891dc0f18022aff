"""Running blocking physics and planner calls from a route: in the threadpool, guarded."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from fastapi.concurrency import run_in_threadpool

from ..service import solver_guard


def _guarded(fn: Callable[..., Any], *args: Any) -> Any:
    with solver_guard():
        return fn(*args)


async def compute(fn: Callable[..., Any], *args: Any) -> Any:
    """Run a blocking physics or planner call in the threadpool, under :func:`solver_guard`
    (any failure that is not an input or solver error becomes a SolverError: a 422)."""
    return await run_in_threadpool(_guarded, fn, *args)
