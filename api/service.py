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
    DoseRequest,
    JobRunner,
    Pending,
    Planner,
    QueueFullError,
    ScheduleRequest,
    SolverSettings,
    UnknownValidationError,
)
from dosing.drug import DrugModel, carried_by_fluid
from dosing.drug_dose import DrugDoseRequest, drug_dose_now, plan_drug_dose
from dosing.drug_schedule import DrugScheduleRequest, plan_drug_schedule
from dosing.jobs import DEFAULT_LEASE_SECONDS
from dosing.request import resolve_gel
from solver.equilibrium import equilibria, folds
from solver.errors import NotApplicableError, ParameterError, SolverError
from solver.gel import PRESETS, Gel
from solver.phase import classify_jump

from . import schemas as s
from . import stored_jobs
from .errors import CacheFault, InternalError, ServiceUnavailable
from .warmup import WarmupReport, warm_up

log = logging.getLogger("thermogel.service")

JOB_QUEUE = 8  # stored jobs (schedules, fits) queued or running before 429
# threads running stored jobs: a long fit (minutes at the schema's limits) holds one, and
# schedule checks and drug doses go on beside it (their runs go to the planner's pool)
JOB_THREADS = 2
FAULT_SECONDS = 120.0  # /health is 'degraded' this long after a cache fault


# ----------------------------------------------------------------------------- physics

def to_gel(spec: str | s.GelParameters) -> Gel:
    """The solver gel a request names: a preset or stored gel, or one with parameters
    replaced (``dosing.request.resolve_gel``: one rule for HTTP, CLI and Python)."""
    if isinstance(spec, str):
        return resolve_gel(spec)
    return resolve_gel(spec.model_dump(include=set(s.GelParameters.model_fields),
                                       exclude_none=True))


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
        """Why the service is degraded (a recent cache fault, a failed cache probe), or None."""
        if self._fault is not None and time.monotonic() - self._fault[0] < FAULT_SECONDS:
            return f"the validation cache failed: {self._fault[1]}"
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


# ----------------------------------------------------------------------------- dosing

def _constants(c: s.ConstantsIn | None) -> dict[str, Any] | None:
    return None if c is None else c.model_dump(exclude_none=True)


def _protocol(body: s.DoseTimeRequest) -> Any:
    """The request's heating protocol (no file paths over HTTP), or None."""
    if body.protocol is None:
        return None
    from dosing.heating import Protocol

    if body.t_end is not None:
        raise ParameterError("t_end", body.t_end, "absent when a protocol is given (the "
                             "protocol's steps set the heating)")
    return Protocol(body.t_start, body.protocol, files=False)


def _case(body: s.DoseTimeRequest | s.ScheduleRequest) -> dict[str, Any]:
    """The :class:`dosing.request.Case` fields every request body shares (t_end aside)."""
    return {"gel": to_gel(body.gel), "t_start": body.t_start,
            "dry_radius_um": body.dry_radius_um, "swollen_radius_um": body.swollen_radius_um,
            "constants": _constants(body.constants), "branch": body.branch,
            "settings": SolverSettings(interfacial_length=body.interfacial_length,
                                       method=body.validation_method)}


def to_dose_request(body: s.DoseTimeRequest) -> DoseRequest:
    """The planner's request (it checks the dose against the stored fluid: ParameterError)."""
    protocol = _protocol(body)
    return DoseRequest(
        **_case(body), t_end=None if protocol is not None else body.t_end,
        protocol=protocol, dose_fraction=body.dose_fraction,
        dose_volume_ul=body.dose_volume_ul, drug_mass_ug=body.drug_mass_ug,
        concentration_ug_per_ul=body.concentration_ug_per_ul,
        size_distribution=None if body.size_distribution is None
        else body.size_distribution.model_dump(exclude_none=True))


def to_schedule_request(body: s.ScheduleRequest) -> ScheduleRequest | DrugScheduleRequest:
    """The planner's schedule request: of fluid, or of drug with a ``drug``."""
    fields = dict(_case(body), t_end=body.t_end, rests=body.rests,
                  rests_seconds=body.rests_seconds, check_protocol=body.check_protocol,
                  correct=body.correct, tolerance=body.tolerance)
    if body.drug is None:
        return ScheduleRequest(**fields, doses=tuple(body.doses))
    return DrugScheduleRequest(**fields, doses=tuple(body.doses), **_drug(body))


def _drug(body: s.DoseTimeRequest | s.ScheduleRequest) -> dict[str, Any]:
    """The :class:`dosing.drug_dose.DrugCase` fields of a body with a ``drug``."""
    return {"drug": DrugModel(**body.drug.model_kwargs()), "wait": body.drug.wait,
            "wait_seconds": body.drug.wait_seconds}


def to_drug_dose_request(body: s.DoseTimeRequest) -> DrugDoseRequest:
    """The planner's drug dose request (ParameterError names a bad field)."""
    for name in ("dose_volume_ul", "concentration_ug_per_ul"):
        if getattr(body, name) is not None:
            raise ParameterError(name, getattr(body, name), "null with a drug (give "
                                 "dose_fraction of the load or drug_mass_ug)")
    protocol = _protocol(body)
    return DrugDoseRequest(**_case(body), t_end=None if protocol is not None else body.t_end,
                           protocol=protocol, **_drug(body),
                           dose_fraction=body.dose_fraction, drug_mass_ug=body.drug_mass_ug)


DOSE_PENDING_NOTE = (
    "This scenario needs the full solver (no front model applies and no run is cached yet). "
    "Poll validation_url; once it is done, send the same request again: it is then answered "
    "at once from the cache.")
SCHEDULE_PENDING_NOTE = (
    "The schedule's protocol check and correction need the full solver; poll validation_url "
    "for the result.  `hold`, when present, is the hold reading (the paper's assumption: one "
    "continuous heating, doses read off cumulatively): a rough reading only, since the gel "
    "takes up fluid while it rests and later doses then come out larger.")
PROTOCOL_PENDING_NOTE = (
    "A dose under a heating protocol is a full-solver answer and its runs are not cached "
    "yet. Poll validation_url; once it is done, send the same request again (a protocol "
    "with until-steps may take one more round per until-step).")


DRUG_PENDING_NOTE = (
    "This drug dose needs full-solver drug runs that are not cached yet: it is queued as a "
    "job. Poll validation_url; once done, its result is the answer (asking again is then "
    "answered at once from the cache).")


def _drug_answer(ans: Any) -> dict[str, Any]:
    return {"status": "answered", "drug": True, **ans.to_dict()}


def _drug_dose_job(planner: Planner, body: s.DoseTimeRequest) -> dict[str, Any]:
    """A stored drug-dose job's run: the answer, computing its drug runs (blocking); a
    batch's (a size_distribution) from dosing.batch_drug."""
    req = to_drug_dose_request(body)
    if body.size_distribution is not None:
        from dosing.batch_drug import drug_batch_dose

        ans = drug_batch_dose(req, body.size_distribution.model_dump(exclude_none=True),
                              body.medium_volume_ml, body.bead_count)
        return {"status": "answered", "drug": True, "batch": ans.to_dict()}
    return _drug_answer(plan_drug_dose(planner, req, validate=body.validate_full))


def dose_time(planner: Planner, body: s.DoseTimeRequest,
              state: ServiceState | None = None) -> dict[str, Any] | Accepted:
    """The answer (front model or cache; 200), or :class:`Accepted` with a validation id;
    one planner call (:meth:`dosing.Planner.answer`).  A dose with a drug is answered at
    once when its runs are cached (:func:`dosing.drug_dose.drug_dose_now`), else (given
    ``state``) as a stored 'drug-dose' job, so that no HTTP worker thread waits on a run."""
    from dosing.batch_drug import check_batch_body

    check_batch_body(body)
    if body.drug is not None and body.size_distribution is not None:  # issue 26
        if state is None:
            return _drug_dose_job(planner, body)
        return Accepted(stored_jobs.submit(state, "drug-dose", body), DRUG_PENDING_NOTE)
    if body.drug is not None:  # under a protocol too (dosing.drug_protocol): always a job
        if state is None:
            return _drug_dose_job(planner, body)
        now = drug_dose_now(planner, to_drug_dose_request(body), validate=body.validate_full)
        if now is not None:
            return _drug_answer(now)
        return Accepted(stored_jobs.submit(state, "drug-dose", body), DRUG_PENDING_NOTE)
    req = to_dose_request(body)
    out = planner.answer(req, validate=body.validate_full)
    if isinstance(out, Pending):
        return Accepted(out.validation_id, DOSE_PENDING_NOTE if body.protocol is None
                        else PROTOCOL_PENDING_NOTE)
    answer = {"status": "answered", **out.answer.to_dict()}
    if req.size_distribution is not None:  # a batch (issue 26), under a protocol (24)
        from dosing.batch import batch_answer
        from dosing.batch_protocol import batch_protocol_answer

        answer["batch"] = (batch_answer(req) if req.heating is None else
                           batch_protocol_answer(req, validate=body.validate_full)).to_dict()
    if out.validation_id is not None:
        answer.update(validation_id=out.validation_id,
                      validation_url=validation_url(out.validation_id))
    return answer


def _schedule_result(planner: Planner, body: s.ScheduleRequest) -> dict[str, Any]:
    """The whole schedule (blocking): fluid, or drug with a ``drug``."""
    req = to_schedule_request(body)
    if isinstance(req, DrugScheduleRequest):
        return {"drug": True, **plan_drug_schedule(planner, req).to_dict()}
    return planner.schedule(req).to_dict()


def _schedule_now(planner: Planner, body: s.ScheduleRequest) -> dict[str, Any] | None:
    """The schedule when nothing in it needs a new full-solver run (one planner call for a
    fluid schedule: :meth:`dosing.Planner.schedule_now`), else None."""
    req = to_schedule_request(body)
    if isinstance(req, DrugScheduleRequest):  # the hold reading of a drug the fluid carries
        quick = not (req.check_protocol or req.correct) and carried_by_fluid(req.solute)
        return {"drug": True, **plan_drug_schedule(planner, req).to_dict()} if quick else None
    now = planner.schedule_now(req)
    return None if now is None else now.to_dict()


def schedule(state: ServiceState, body: s.ScheduleRequest) -> dict[str, Any] | Accepted:
    """The hold schedule (200) when nothing needs a new full-solver run, else a stored job
    (:class:`Accepted`)."""
    now = _schedule_now(state.planner, body)
    if now is not None:
        return {"status": "answered", **now}
    job = stored_jobs.submit(state, "schedule", body)
    rough = None
    if body.drug is None and (body.check_protocol or body.correct):
        hold = _schedule_now(state.planner, body.model_copy(
            update={"check_protocol": False, "correct": False}))
        rough = None if hold is None else hold["hold"]
    return Accepted(job, SCHEDULE_PENDING_NOTE, hold=rough)


stored_jobs.register(stored_jobs.JobKind("schedule", s.ScheduleRequest, _schedule_result))
stored_jobs.register(stored_jobs.JobKind("drug-dose", s.DoseTimeRequest, _drug_dose_job))


def validation(state: ServiceState, vid: str) -> dict[str, Any]:
    """A dose validation from the planner, or a stored job (both persistent)."""
    if stored_jobs.is_job(vid):
        return stored_jobs.status(state, vid)
    return {"kind": "dose", **state.planner.validation(vid).to_dict()}
