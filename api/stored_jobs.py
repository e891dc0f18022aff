"""Jobs kept in the planner's cache: schedules, drug doses, fits, sweeps (HTTP 202 + poll).

A job is a request body of a registered kind, stored in the cache's ``jobs`` table under an
id made of the kind and the body's hash; it runs on the service's job runner (leased on the
cache, so one server runs it) and its outcome is stored beside it.  A job that is pending
when polled and runs nowhere here (a restart, a crashed server) is queued again: jobs
survive kill -9.  Adding a kind is one :func:`register` call with the request model (the
stored body is validated with it again before it runs) and a blocking ``run(planner,
body) -> dict``; a kind may run on a runner of its own (``runner(state)``: sweeps keep
their one thread and queue), else on the service's job threads.
"""

from __future__ import annotations

import hashlib
import logging
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from pydantic import BaseModel

from dosing import QueueFullError, UnknownValidationError

log = logging.getLogger("thermogel.service")


@dataclass(frozen=True)
class JobKind:
    """A kind of stored job: its name (the id's prefix), request model and runner."""

    name: str
    request: type[BaseModel]
    run: Callable[[Any, Any], dict[str, Any]]
    runner: Callable[[Any], Any] | None = None  # state -> its JobRunner (default state.jobs)

    def runner_of(self, state: Any) -> Any:
        """The JobRunner this kind's jobs run on."""
        return state.jobs if self.runner is None else self.runner(state)


KINDS: dict[str, JobKind] = {}


def register(kind: JobKind) -> None:
    """Make a kind of job available to :func:`submit` and :func:`status`."""
    KINDS[kind.name] = kind


def job_id(kind: str, body: BaseModel) -> str:
    """The id of a job: ``<kind>-<hash of the body>`` (the same request, the same job)."""
    return f"{kind}-" + hashlib.sha256(body.model_dump_json().encode()).hexdigest()[:24]


def _kind_of(jid: str) -> JobKind | None:
    return next((k for name, k in KINDS.items() if jid.startswith(name + "-")), None)


def is_job(jid: str) -> bool:
    """True if ``jid`` names a stored job of a registered kind (not a dose validation)."""
    return _kind_of(jid) is not None


def _run(state: Any, jid: str, kind: JobKind, stored: dict[str, Any]) -> dict[str, Any]:
    """Run a stored job and store its outcome (in the job thread)."""
    cache = state.planner.cache
    try:
        result = kind.run(state.planner, kind.request.model_validate(stored))
    except Exception as exc:
        import sqlite3

        if isinstance(exc, sqlite3.Error) and hasattr(state, "record_fault"):
            state.record_fault(str(exc))  # /health: degraded
        cache.finish_job(jid, "failed", error=plain_error(exc))
        raise
    cache.finish_job(jid, "done", result=result)
    return result


def plain_error(exc: Exception) -> str:
    """Why a job failed, in plain words for its poll: the field and its valid range for an
    input error, the solver's reason for a numerical failure; never a Python exception's
    class name (the traceback goes to the log)."""
    from solver.errors import NotApplicableError, ParameterError, SolverError

    if isinstance(exc, ParameterError):
        return f"the input {exc.field} is not usable: {exc}"
    if isinstance(exc, NotApplicableError):
        return f"the model does not apply: {exc}"
    if isinstance(exc, SolverError):
        return f"the solver could not answer: {exc}"
    if isinstance(exc, QueueFullError):
        return str(exc)
    import sqlite3

    if isinstance(exc, sqlite3.Error) or type(exc).__name__ == "CacheFault":
        return f"the validation cache failed: {str(exc)[:300]}"
    log.error("job failed", exc_info=exc)
    text = str(exc).strip()
    if isinstance(exc, (ValueError, ArithmeticError)) and text:
        return f"the computation failed on these data: {text[:300]}"
    return "the job failed on an internal error (logged); please report it"


def _start(state: Any, jid: str, kind: JobKind, stored: dict[str, Any]) -> None:
    """Queue a stored job here, unless it is queued or running already."""
    runner = kind.runner_of(state)
    if runner.state(jid) in ("pending", "running"):
        return

    def finished_elsewhere() -> dict[str, Any] | None:  # a lease waiter's fetch
        row = state.planner.cache.get_job(jid)
        return row if row is not None and row["status"] != "pending" else None

    runner.submit(jid, _run, state, jid, kind, stored, fetch=finished_elsewhere)


def submit(state: Any, kind: str, body: BaseModel) -> str:
    """Store and queue a job (again, if it failed before); its id.  A full runner raises
    QueueFullError before anything is stored."""
    k = KINDS[kind]
    jid = job_id(kind, body)
    cache = state.planner.cache
    stored = body.model_dump(mode="json", by_alias=True)
    row = cache.get_job(jid)
    if row is None or row["status"] == "failed":  # new, or asked again after a failure
        if row is None:
            cache.put_job(jid, kind, stored)
        else:
            cache.finish_job(jid, "pending")
        try:
            _start(state, jid, k, stored)
        except QueueFullError:  # not admitted: asking again queues it
            cache.finish_job(jid, "failed", error="not admitted: the job queue was full")
            raise
    elif row["status"] == "pending":
        _start(state, jid, k, row["request"])
    return jid


def status(state: Any, jid: str) -> dict[str, Any]:
    """``{id, kind, status, result | error}`` of a stored job; an unfinished job nobody
    here runs is queued again.  Unknown ids raise UnknownValidationError (404)."""
    kind = _kind_of(jid)
    row = None if kind is None else state.planner.cache.get_job(jid)
    if row is None or kind is None:
        raise UnknownValidationError(jid)
    out: dict[str, Any] = {"id": jid, "kind": row["kind"], "status": row["status"]}
    if row["status"] == "pending":
        _start(state, jid, kind, row["request"])
        out["status"] = kind.runner_of(state).state(jid) or "pending"
        if out["status"] in ("done", "failed"):  # finished just now
            row = state.planner.cache.get_job(jid) or row
            out["status"] = row["status"]
    if out["status"] == "done":
        out["result"] = row["result"]
    elif out["status"] == "failed":
        out["error"] = row["error"] or "failed"
    return out
