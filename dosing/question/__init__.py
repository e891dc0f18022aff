"""One request, one answer: the planner as one pipeline over payload x population x heating
x question (issue 35; docs/architecture.md).  E.g. ``plan(Request("ANB", 302, Jump(308),
Dose(0.8), population=Batch({"cv": 0.2}), dry_radius_um=50)).seconds``: the batch's own time.
:func:`plan` answers blocking; :func:`answer` without waiting on a new full-solver run (a
result, a ``Pending`` validation, or None: the request needs a job, which :func:`plan` then
is).  Which code answers a cell: ``dosing.question.cells.CELLS``."""

from __future__ import annotations

from concurrent.futures import Executor
from typing import Any

from ..answers import Pending
from .axes import Batch, Dose, Drug, Fluid, Heating, Jump, OneBead, Schedule
from .request import Request
from .result import DoseResult, ScheduleResult

Result = DoseResult | ScheduleResult


def answer(planner: Any, request: Request) -> Result | Pending | None:
    """The answer if no new full-solver run is needed; a ``Pending`` validation queued on
    the planner; or None when the request needs a blocking job (:func:`run`)."""
    out = request.cell.now(planner, request)
    if out is not None and not isinstance(out, Pending):
        _finish(planner, request, out)
    return out


def _finish(planner: Any, request: Request, out: Result, blocking: bool = False) -> None:
    """The answer's echo of its request, its payload's tags and its envelope."""
    from .envelope import envelope

    out.request, out.tags = request.to_dict(), {**out.tags, **request.payload.tags}
    out.envelope = envelope(planner, request, out, blocking)


def run(planner: Any, request: Request) -> Result:
    """The answer, blocking (full-solver runs on the planner, cached)."""
    out = request.cell.run(planner, request)
    _finish(planner, request, out, blocking=True)
    return out


def plan(request: Request, planner: Any = None, cache_path: str | None = None,
         executor: Executor | None = None) -> Result:
    """The answer, blocking, on ``planner`` or a throw-away one on the cache."""
    if planner is not None:
        return run(planner, request)
    from .. import planner as planner_module

    p = planner_module.one_shot(cache_path, executor)
    try:
        return run(p, request)
    finally:
        p.close()
        if executor is None:
            p.jobs.executor.shutdown(wait=True)


__all__ = ["Batch", "Dose", "DoseResult", "Drug", "Fluid", "Heating", "Jump", "OneBead",
           "Pending", "Request", "Result", "Schedule", "ScheduleResult", "answer", "plan",
           "run"]
