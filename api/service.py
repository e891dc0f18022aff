"""The service layer under the HTTP routes: request models to planner calls, and back.

Blocking, FastAPI-free functions (the routes run them in the threadpool): conversions from
the API's pydantic models (:mod:`api.schemas`) to ``solver`` and ``dosing`` objects, the
mapping of the planner's one answer per request to an answer dict (200) or
:class:`Accepted` (202: the validation or job id to poll), schedule jobs (stored in the
cache, so they survive a restart and run once across servers), and the state the routes
share.  No physics here.
"""

from __future__ import annotations

import logging
import sqlite3
import threading
import time
from collections.abc import Iterator
from concurrent.futures import ThreadPoolExecutor
from contextlib import contextmanager
from dataclasses import dataclass, field
from functools import lru_cache
from typing import Any

from dosing import (
    JobRunner,
    Pending,
    Planner,
    QueueFullError,
    UnknownValidationError,
    question,
)
from dosing.runs.jobs import DEFAULT_LEASE_SECONDS
from solver.equilibrium import equilibria, folds
from solver.errors import NotApplicableError, ParameterError, SolverError
from solver.gel import PRESETS, Gel
from solver.phase import classify_jump

from . import schemas as s
from . import stored_jobs
from .errors import CacheFault, InternalError, ServiceUnavailable
from .requests import to_gel, to_request
from .warmup import WarmupReport, warm_up

log = logging.getLogger("thermogel.service")

JOB_QUEUE = 8  # stored jobs (schedules, fits) queued or running before 429
# threads running stored jobs: a long fit (minutes at the schema's limits) holds one, and
# schedule checks and drug doses go on beside it (their runs go to the planner's pool)
JOB_THREADS = 2
FAULT_SECONDS = 120.0  # /health is 'degraded' this long after a cache fault


# ----------------------------------------------------------------------------- physics


def _folds(gel: Gel) -> list[dict[str, Any]]:
    return [f.to_dict() for f in folds(gel)]


@lru_cache(maxsize=1)
def presets_answer() -> dict[str, Any]:
    """Every preset with its parameters and folds (computed once)."""
    return {"gels": [{"gel": g.to_dict(), "folds": _folds(g)} for g in PRESETS.values()]}


def equilibrium_answer(req: s.EquilibriumRequest) -> dict[str, Any]:
    """All equilibria at T and the folds (blocking)."""
    gel = to_gel(req.gel)
    return {"gel": gel.to_dict(), "temperature": req.temperature,
            "equilibria": [e.to_dict() for e in equilibria(gel, req.temperature)],
            "folds": _folds(gel)}


def classify_answer(req: s.ClassifyRequest) -> dict[str, Any]:
    """The jump's class (blocking)."""
    return classify_jump(to_gel(req.gel), req.t_start, req.t_end, req.branch).to_dict()


@contextmanager
def solver_guard() -> Iterator[None]:
    """Let input and solver errors through; a failure of the cache file (SQLite) becomes a
    CacheFault (503 naming the cache), any other exception an InternalError (500, logged
    with its traceback): server faults are not input errors."""
    try:
        yield
    except (ParameterError, NotApplicableError, SolverError, QueueFullError,
            UnknownValidationError, CacheFault, InternalError, ServiceUnavailable):
        raise
    except sqlite3.Error as exc:
        log.exception("validation cache failure on a request")
        raise CacheFault(str(exc) or type(exc).__name__) from exc
    except Exception as exc:
        log.exception("internal failure on a request")
        raise InternalError(type(exc).__name__) from exc


# ----------------------------------------------------------------------------- state

def _unfinished(runner: JobRunner) -> int | None:
    """Unfinished groups of a job runner, from a copy of its table (dict.copy is atomic):
    no lock, so /health never waits on the compute threads."""
    try:
        entries = runner._jobs.copy()
        return len({e.group for e in entries.values() if not e.outer.done()})
    except Exception:  # a stand-in runner: unknown
        return None


def validation_url(vid: str) -> str:
    """The path to poll a validation or stored job."""
    return f"/v1/validations/{vid}"


@dataclass
class Accepted:
    """A request queued as full-solver work: HTTP 202 with the id to poll."""

    validation_id: str
    note: str
    hold: list[dict[str, Any]] | None = None  # a schedule's rough hold reading, if at hand

    @property
    def validation_url(self) -> str:
        """Path to poll."""
        return validation_url(self.validation_id)

    def to_dict(self) -> dict[str, Any]:
        """The 202 body (schemas.PendingResponse)."""
        out: dict[str, Any] = {"status": "pending", "validation_id": self.validation_id,
                               "validation_url": self.validation_url, "note": self.note}
        if self.hold is not None:
            out["hold"] = self.hold
        return out


@dataclass
class ServiceState:
    """What the routes share: the planner (owned or lent), the warm-up report."""

    planner: Planner | None = None
    owns_planner: bool = False
    warmup: WarmupReport | None = None
    options: dict[str, Any] = field(default_factory=dict)
    _jobs: JobRunner | None = None
    _job_pool: ThreadPoolExecutor | None = None
    _fault: tuple[float, str] | None = None
    _probed: int | None = None
    _probe: Any = None
    _health_pool: ThreadPoolExecutor | None = None
    _probe_lock: threading.Lock = field(default_factory=threading.Lock)

    @property
    def jobs(self) -> JobRunner:
        """Stored jobs (schedules, drug doses, fits; :mod:`api.stored_jobs`): JOB_THREADS
        threads (their full-solver runs go to the planner's executor), leased on the
        planner's cache so that one server runs each job."""
        if self._jobs is None:
            self._job_pool = ThreadPoolExecutor(JOB_THREADS, thread_name_prefix="job")
            lease = float(self.options.get("lease_seconds") or DEFAULT_LEASE_SECONDS)
            self._jobs = JobRunner(self._job_pool, max_pending=JOB_QUEUE,
                                   leases=self.planner.cache,
                                   lease_seconds=lease, what="schedule and fit jobs")
        return self._jobs

    def start(self, warm: bool) -> None:
        """Create the planner if none was given, then warm the kernels (blocking)."""
        if self.planner is None:
            self.planner = Planner(**self.options)
            self.owns_planner = True
        if warm:
            self.warmup = warm_up(self.planner)

    def record_fault(self, reason: str) -> None:
        """Remember a server fault (a failed cache): /health is 'degraded' for
        ``FAULT_SECONDS`` after the last one, and says why."""
        self._fault = (time.monotonic(), reason)

    def fault(self) -> str | None:
        """Why the service is degraded (a recent cache fault, a failed cache probe, a broken
        full-solver pool not replaced yet), or None."""
        if self._fault is not None and time.monotonic() - self._fault[0] < FAULT_SECONDS:
            return f"the validation cache failed: {self._fault[1]}"
        pool = _pool_status(self.planner)
        if pool.get("status") == "degraded":
            return f"the full-solver pool is broken: {pool.get('broken_because')}"
        return None

    def describe(self) -> dict[str, Any]:
        """Queue state for /health, read without any lock the compute threads take and
        without the cache file (the cached count comes from :meth:`probe`)."""
        p = self.planner
        if p is None or not hasattr(p, "jobs") or not hasattr(p, "cache"):
            return {}
        out: dict[str, Any] = {"cache": p.cache.path.name,
                               "cached_trajectories": self._probed,
                               "validations_unfinished": _unfinished(p.jobs),
                               "max_pending": p.jobs.max_pending}
        out["jobs_unfinished"] = 0 if self._jobs is None else _unfinished(self._jobs)
        out["pool"] = _pool_status(p)
        return out

    def probe(self) -> Any:
        """Start a look at the cache file on the health thread (never the compute threads'
        pool) unless one is under way; a concurrent.futures.Future, or None."""
        p = self.planner
        if p is None or not hasattr(p, "cache"):
            return None
        with self._probe_lock:  # only the health route takes it
            if self._probe is not None and not self._probe.done():
                return self._probe
            if self._health_pool is None:
                self._health_pool = ThreadPoolExecutor(1, thread_name_prefix="health")
            self._probe = self._health_pool.submit(self._look, p.cache)
            return self._probe

    def _look(self, cache: Any) -> None:
        try:
            self._probed = len(cache)
        except sqlite3.Error as exc:
            self.record_fault(str(exc))

    def stop(self, wait: bool = False) -> None:
        """Drop queued stored jobs (``wait``: join the running one; they stay in the cache
        and run again when polled); close the planner if this service created it."""
        if self._jobs is not None:
            self._jobs.shutdown(wait=False)
            if self._job_pool is not None:
                self._job_pool.shutdown(wait=wait, cancel_futures=True)
            self._jobs = self._job_pool = None
        if self._health_pool is not None:
            self._health_pool.shutdown(wait=False, cancel_futures=True)
            self._health_pool = None
        if self.owns_planner and self.planner is not None:
            self.planner.close()
            self.planner = None


def _pool_status(planner: Any) -> dict[str, Any]:
    """The full-solver pool's health (dosing.runs.jobs.JobRunner.pool_status), {} without one."""
    status = getattr(getattr(planner, "jobs", None), "pool_status", None)
    return status() if callable(status) else {}


# ----------------------------------------------------------------------------- dosing

PENDING_NOTE = (
    "{cell} needs full-solver runs that are not cached yet; they are queued. Poll "
    "validation_url; once it is done, send the same request again: it is then answered at "
    "once from the cache (a protocol with until-steps may take one more round per "
    "until-step).")
JOB_NOTE = (
    "{cell} needs full-solver runs that are not cached yet: it is queued as a job. Poll "
    "validation_url; once done, its result is the answer (asking again is then answered at "
    "once from the cache).")

HOLD_NOTE = (
    " `hold` is the hold reading (the paper's assumption: one continuous heating, doses read "
    "off cumulatively): a rough reading only, since the gel takes up fluid while it rests "
    "and later doses then come out larger.")


def _answered(result: Any) -> dict[str, Any]:
    out = {"status": "answered", **result.to_dict()}
    if getattr(result, "validation_id", None) is not None:
        out["validation_url"] = validation_url(result.validation_id)
    return out


def _job_result(planner: Planner, body: s.DoseTimeRequest | s.ScheduleRequest
                ) -> dict[str, Any]:
    """A stored job's run: the request planned, blocking (dosing.question.run)."""
    return _answered(question.run(planner, to_request(body)))


def _plan(state: ServiceState | None, planner: Planner, body: Any, kind: str,
          hold: Any = None) -> dict[str, Any] | Accepted:
    """One adapter: body -> request -> planner -> one answer (200), a queued validation or
    a stored job (202)."""
    request = to_request(body)
    if state is None:
        return _job_result(planner, body)
    out = question.answer(planner, request)
    if isinstance(out, Pending):
        return Accepted(out.validation_id, PENDING_NOTE.format(cell=request.cell_name))
    if out is None:
        job = stored_jobs.submit(state, kind, body)
        rough = None if hold is None else hold(planner, body)
        return Accepted(job, JOB_NOTE.format(cell=request.cell_name)
                        + ("" if rough is None else HOLD_NOTE), hold=rough)
    return _answered(out)


def dose_time(planner: Planner, body: s.DoseTimeRequest,
              state: ServiceState | None = None) -> dict[str, Any] | Accepted:
    """A dose, whatever its cell (:func:`_plan`): answered now (front or reduced model, or
    cached runs), else a queued validation or a stored 'dose' job (202)."""
    return _plan(state, planner, body, "dose")


def _rough_hold(planner: Planner, body: s.ScheduleRequest) -> list[dict[str, Any]] | None:
    """A schedule's hold reading while its job runs, when it is at hand without runs: the
    cell's own reading (``cell.now``), not ``question.answer``, whose envelope (a lattice run
    in the request's thread) the 202 would wait on and then drop."""
    try:
        request = to_request(body.model_copy(update={"check_protocol": False,
                                                     "correct": False}))
        quick = request.cell.now(planner, request)
    except ParameterError:
        return None
    return None if quick is None or isinstance(quick, Pending) else quick.to_dict()["hold"]


def schedule(state: ServiceState, body: s.ScheduleRequest) -> dict[str, Any] | Accepted:
    """A schedule, whatever its cell: answered now (the hold reading asked alone), else a
    stored 'schedule' job (202, with the rough hold reading when at hand)."""
    return _plan(state, state.planner, body, "schedule", _rough_hold)


# the job kinds; 'drug-dose' and 'batch-schedule' (round three) still poll their stored ids
for _kind, _body in (("dose", s.DoseTimeRequest), ("drug-dose", s.DoseTimeRequest),
                     ("schedule", s.ScheduleRequest), ("batch-schedule", s.ScheduleRequest)):
    stored_jobs.register(stored_jobs.JobKind(_kind, _body, _job_result))


def validation(state: ServiceState, vid: str) -> dict[str, Any]:
    """A dose validation from the planner, or a stored job (both persistent)."""
    if stored_jobs.is_job(vid):
        return stored_jobs.status(state, vid)
    return {"kind": "dose", **state.planner.validation(vid).to_dict()}
