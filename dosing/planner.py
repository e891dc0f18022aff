"""The dose planner: model choice, actuation times, validation against the full solver.

Sec. Application: a0 from eq. EqlEqn, the dose radius a^3 = a0^3 - f (a0^3 - 1) (eq.
FluidVolExpelled), the time a(t) falls to it, times tau (eq. timescale) for seconds.
:meth:`Planner.answer` is a request's one call (``Answered | Pending``), :meth:`Planner.dose`
the blocking form.  Models and truths: docs/architecture.md, docs/interfacial.md sec. 9."""

from __future__ import annotations

import functools
import hashlib
import json
import threading
import time
from collections import OrderedDict
from concurrent.futures import Executor, ThreadPoolExecutor
from dataclasses import fields
from typing import TYPE_CHECKING, Any, NamedTuple

from solver.errors import SolverError
from solver.gel import Gel

from .answers import (
    Answered,
    DoseAnswer,
    ModelChoice,
    Pending,
    ValidationReport,
    ValidationStatus,
    plain,
)
from .model_choice import build_answer, front_time, model_answer
from .request import DoseRequest, ScheduleRequest
from .runs.jobs import DEFAULT_LEASE_SECONDS
from .runs.scenario import Scenario, Solver, SolverSettings
from .runs.store import DEFAULT_HORIZON, RunStore
from .truth import delayed_settings, range_settings
from .validation import error_estimate, failure, validation_report

if TYPE_CHECKING:
    from .question.schedule import ScheduleAnswer

VERDICTS = 1024  # front-model verdicts remembered per planner (keyed by cache generation)


class UnknownValidationError(KeyError):
    """A validation id this planner's cache has never seen."""


def validation_scenarios(gel: Gel, t_start: float, t_end: float, branch: str,
                         settings: SolverSettings,
                         ell_range: tuple[float, float] | None = None) -> tuple[Scenario, ...]:
    """A jump's validation runs: the settings' rungs, then, for the direct truth, the
    interfacial-length runs at ``ell_range`` and the model-form runs (module ``truth``).

    Memoised per (jump, settings, range): the scenarios are immutable and their keys (a
    sha256 of canonical JSON) are computed once, so a warm answer builds neither."""
    return _validation_scenarios(gel, float(t_start), float(t_end), branch, settings,
                                 settings.auto_length,
                                 None if ell_range is None else tuple(ell_range))


@functools.lru_cache(maxsize=1024)
def _validation_scenarios(gel: Gel, t_start: float, t_end: float, branch: str,
                          settings: SolverSettings, auto_length: bool,
                          ell_range: tuple[float, float] | None) -> tuple[Scenario, ...]:
    # auto_length is not a field (settings equal without it): keyed apart all the same
    runs = [*settings.rungs(), *range_settings(settings, ell_range), *delayed_settings(settings)]
    scs = tuple(Scenario(gel, t_start, t_end, branch=branch, settings=s) for s in runs)
    for sc in scs:
        sc.key()  # computed once, here
    return scs


@functools.lru_cache(maxsize=1024)
def _truth_scenario(gel: Gel, t_start: float, t_end: float, branch: str,
                    settings: SolverSettings) -> Scenario:
    sc = Scenario(gel, t_start, t_end, branch=branch, settings=settings)
    sc.key()
    return sc


def truth_scenario(req: DoseRequest) -> Scenario:
    """The request's truth run: the first of :func:`request_scenarios` (every method's
    first rung is the settings themselves), without building the others."""
    return _truth_scenario(req.gel, float(req.t_start), float(req.t_end), req.branch,
                           req.settings)


def request_scenarios(req: DoseRequest | ScheduleRequest) -> tuple[Scenario, ...]:
    """The validation runs of a request (:func:`validation_scenarios`)."""
    return validation_scenarios(req.gel, req.t_start, req.t_end, req.branch, req.settings,
                                req.interfacial_range)




class Planner:
    """Plans doses and schedules; keeps full-solver validations in a persistent cache.
    ``executor``: any ``concurrent.futures.Executor`` (default a process pool); runs deduplicated by
    key across processes on one file (a lease lapses ``lease_seconds`` unrenewed); at most
    ``max_pending`` validations queued; ``solver`` (default ``solver.full.simulate``) pickles."""

    def __init__(self, cache_path: str | None = None, executor: Executor | None = None,
                 max_pending: int = 64, horizon: float = DEFAULT_HORIZON,
                 lease_seconds: float = DEFAULT_LEASE_SECONDS,
                 solver: Solver | None = None) -> None:
        # every full-solver run, stored or queued: dosing.runs.store (the planner's cache
        # file, jobs and solver are the store's)
        self.runs = RunStore(cache_path, executor, max_pending, horizon, lease_seconds, solver)
        self.cache = self.runs.cache
        self.jobs = self.runs.jobs
        # the store's run lookups, under the names the planner's callers use
        self.cached = self.runs.cached
        self.cached_many = self.runs.cached_many
        self.submit = self.runs.submit
        self.run_here = self.runs.run_here
        self.trajectory = self.runs.trajectory
        self._trajectories = self.runs.trajectories
        # a front-model dose's verdict from the stored runs (:meth:`_front_dose`): (request's
        # verdict key, cache generation) -> _Verdict, least recently used dropped
        self._verdicts: OrderedDict[tuple[Any, ...], _Verdict] = OrderedDict()
        self._mem_lock = threading.Lock()

    @property
    def solver(self) -> Solver:
        """What runs a scenario (the store's: default ``solver.full.simulate``)."""
        return self.runs.solver

    @property
    def horizon(self) -> float:
        """The first simulated time of a jump's run (the store's)."""
        return self.runs.horizon

    @property
    def restarts(self) -> int:
        """Protocol runs started from a stored prefix's state (the store's count)."""
        return self.runs.restarts

    # ------------------------------------------------------------------ trajectories
    def scenarios(self, req: DoseRequest | ScheduleRequest) -> list[Scenario]:
        """The jump's validation runs (``SolverSettings.rungs``): the ladder of interfacial
        lengths, or the paper's model on the truth grid and then the other grid."""
        return list(request_scenarios(req))

    # ------------------------------------------------------------------ doses
    def unvalidated(self, req: DoseRequest) -> bool:
        """True when the request's truth run (the first of its validation runs) is
        certainly not stored (:meth:`ValidationCache.stored_runs`): its validation is not
        complete, so a front answer needs neither the runs' keys nor a lookup."""
        runs = self.cache.stored_runs()
        return runs is not None and (req.t_start, req.t_end, req.branch,
                                     req.settings.interfacial_length) not in runs

    def front_time(self, req: DoseRequest, radius: float) -> float:
        """The front model's time to ``radius`` (raises where it does not apply)."""
        return front_time(req, radius)

    def model_answer(self, req: DoseRequest) -> ModelChoice:
        """The model that answers ``req`` (:func:`model_answer`)."""
        return model_answer(req)

    def answer(self, req: DoseRequest, validate: bool = False) -> Answered | Pending:
        """One dose, without waiting for the full solver: :class:`Answered` when the front
        model gives it or every validation run covering it is cached (its report then in
        the answer), else :class:`Pending` with the id of the validation queued for it.
        ``validate``: also queue the validation of an answered dose (its id in the answer).
        The one call the HTTP service makes per dose request."""
        return _DOSE_PATHS[req.heating_kind].answer(self, req, validate)

    def _jump_answer(self, req: DoseRequest, validate: bool) -> Answered | Pending:
        """:meth:`answer` for a jump to T_end (the planner's own models and runs)."""
        choice, scs, ans = self._now(req)
        if ans is None:
            return Pending(self._submit_validation(req, choice, scs))
        if not validate:
            return Answered(ans)
        return Answered(ans, self._submit_validation(req, choice, self.scenarios(req)))

    def answer_now(self, req: DoseRequest) -> DoseAnswer | None:
        """The dose's answer when it needs no new full-solver run (as :meth:`answer`), else
        None; queues nothing."""
        return self._now(req)[2]

    def _now(self, req: DoseRequest) -> tuple[ModelChoice, list[Scenario], DoseAnswer | None]:
        """(model choice, validation runs, the answer from the cache alone or None); for a
        front-model answer (:meth:`_front_dose`, never None) the runs are the truth's alone."""
        choice = self.model_answer(req)
        if not choice.needs_full:
            return choice, [truth_scenario(req)], self._front_dose(req, choice)
        scs = self.scenarios(req)
        trajs = self.cached_many(scs, choice.radius, choice.front_time or 0.0)
        complete = all(t is not None for t in trajs)
        if choice.needs_full and not complete:
            return choice, scs, None
        return choice, scs, self._dose(req, choice, scs, trajs if complete else [])

    def dose(self, req: DoseRequest, validate: bool = False) -> DoseAnswer:
        """The actuation time for one dose of the request's bead (front model, or the full
        solver where needed: blocking; ``validate`` runs the validation too and waits for
        it).  A batch's request is answered here for its number-weighted mean bead; the
        batch's own answer is the one request's (``dosing.plan_dose``,
        ``dosing.question.plan``), above the planner."""
        return _DOSE_PATHS[req.heating_kind].dose(self, req, validate)

    def _jump_dose(self, req: DoseRequest, validate: bool) -> DoseAnswer:
        """:meth:`dose` for a jump to T_end."""
        choice = self.model_answer(req)
        if not (choice.needs_full or validate):
            return self._front_dose(req, choice)
        scs = self.scenarios(req)
        trajs: list[Any] = self._trajectories(scs, choice.radius, choice.front_time or 0.0)
        return self._dose(req, choice, scs, trajs)

    def _front_dose(self, req: DoseRequest, choice: ModelChoice) -> DoseAnswer:
        """A front-model answer from the runs stored now (none run): validated when every validation
        run covering the dose is stored, else with the prior.  The verdict is memoised per request
        and cache generation (:meth:`ValidationCache.generation`, docs/speed.md sec. 2); the rest
        of the answer (seconds, a fitted gel's interval) is made afresh."""
        key = (_verdict_key(req, choice), self.cache.generation())
        with self._mem_lock:
            verdict = self._verdicts.get(key)
            if verdict is not None:
                self._verdicts.move_to_end(key)
        if verdict is None:
            if self.unvalidated(req):
                scs, trajs = [truth_scenario(req)], []
            else:
                scs = self.scenarios(req)
                trajs = self.cached_many(scs, choice.radius, choice.front_time or 0.0)
                if any(t is None for t in trajs):
                    trajs = []
            verdict = self._verdict(req, choice, scs, trajs)
            with self._mem_lock:
                self._verdicts[key] = verdict
                while len(self._verdicts) > VERDICTS:
                    self._verdicts.popitem(last=False)
        return self._answer(req, choice, verdict, remembered=True)

    def _verdict(self, req: DoseRequest, choice: ModelChoice, scs: list[Scenario],
                 trajs: list[Any]) -> _Verdict:
        """The validation runs' verdict on the model choice (trajectories or exceptions;
        none: unvalidated): its report, the answer's time and its error estimate."""
        t_front = choice.front_time
        rep = (validation_report(scs, trajs, req.start_radius, choice.radius, t_front)
               if trajs else None)
        if choice.needs_full and (rep is None or rep.time is None):
            raise next((t for t in trajs if isinstance(t, BaseException)),
                       SolverError(f"no full-solver time: {failure(rep) if rep else 'no run'}"))
        time = max(0.0, t_front if t_front is not None else rep.time)  # tiny doses: -1e-17
        est, explain = error_estimate(choice.model, time, rep, req.fraction, req.gel,
                                      req.settings.method)
        return _Verdict(rep, time, est, explain, scs[0].key())

    def _dose(self, req: DoseRequest, choice: ModelChoice, scs: list[Scenario],
              trajs: list[Any]) -> DoseAnswer:
        """The answer from the model choice and the validation runs' trajectories (or
        exceptions; none: unvalidated)."""
        return self._answer(req, choice, self._verdict(req, choice, scs, trajs))

    def _answer(self, req: DoseRequest, choice: ModelChoice, verdict: _Verdict,
                remembered: bool = False) -> DoseAnswer:
        """The answer from the model choice and the validation's verdict (``remembered``:
        one kept for later answers, whose report this answer gets a copy of)."""
        rep = verdict.report
        if remembered and rep is not None:
            rep = _copy_report(rep)
        ans = build_answer(req, choice, verdict.time, verdict.estimate, verdict.explanation,
                           rep, verdict.key)
        from .fits.gel_store import record_for

        if record_for(req.gel) is None:  # a preset or custom gel: no fit, no interval
            from .units import timescale_uncertainty

            ans.timescale_uncertainty = timescale_uncertainty(  # its seconds' range, stated
                req.gel.omega, req.t_end, req.constants, ans.seconds, None)
            return ans
        from .fits.uncertainty import attach_parameter_interval  # scipy.stats: fitted gels only,

        return attach_parameter_interval(req, ans)

    # ------------------------------------------------------------------ validations
    def submit_validation(self, req: DoseRequest) -> str:
        """Queue the full-solver runs that check this dose; returns an id at once."""
        return self._submit_validation(req, self.model_answer(req), self.scenarios(req))

    def _submit_validation(self, req: DoseRequest, choice: ModelChoice,
                           scs: list[Scenario]) -> str:
        keys = [sc.key() for sc in scs]
        f = req.fraction
        vid = hashlib.sha256(json.dumps([keys, round(f, 12)]).encode()).hexdigest()[:24]
        record = {"scenarios": [sc.to_dict() for sc in scs], "keys": keys,
                  "start_radius": req.start_radius, "target_radius": choice.radius,
                  "fraction": f, "front_time": choice.front_time}
        self._advance(record, vid, retry=True)  # admitted whole or not (QueueFullError)
        if self.cache.get_validation(vid) is None:
            self.cache.put_validation(vid, record)
        return vid

    def _advance(self, record: dict[str, Any], vid: str,
                 retry: bool = False) -> tuple[list[Any], list[str]]:
        """Per run: a covering trajectory, an exception, or None and its job state in the
        second list (submitting what is neither cached nor queued, as one group ``vid``;
        a run whose worker died is not run again unless ``retry``: the request asked
        again, not polled)."""
        need_r, need_t = record["target_radius"], record["front_time"] or 0.0
        scs = [Scenario.from_dict(scd) for scd in record["scenarios"]]
        trajs = [self.cached(sc, need_r, need_t) for sc in scs]
        for i, sc in enumerate(scs):
            if trajs[i] is None and self.jobs.state(sc.key()) is None:
                trajs[i] = self.runs.died(sc.key(), retry)
        todo = [sc for sc, traj in zip(scs, trajs, strict=True) if traj is None
                and self.jobs.state(sc.key()) not in ("pending", "running", "failed")]
        if todo:  # never run, or short of the dose
            self.jobs.submit_group(vid, [self.runs.job(sc, need_r, need_t) for sc in todo])
        out: list[Any] = []
        states = []
        for sc, traj in zip(scs, trajs, strict=True):
            state = None if traj is not None else self.jobs.state(sc.key())
            if state == "failed":
                traj = self.jobs.get(sc.key()).exception() or RuntimeError("cancelled")
            elif traj is None:
                states.append(state or "pending")
            out.append(traj)
        return out, states

    def validation(self, vid: str) -> ValidationStatus:
        """The state of a validation (its result when done); unknown ids raise KeyError."""
        record = self.cache.get_validation(vid)
        if record is None:
            raise UnknownValidationError(vid)
        trajs, states = self._advance(record, vid)
        if states:
            return ValidationStatus(vid, "running" if "running" in states else "pending")
        scs = [Scenario.from_dict(d) for d in record["scenarios"]]
        rep = validation_report(scs, trajs, record["start_radius"], record["target_radius"],
                                record["front_time"])
        why = failure(rep)
        if why is not None:
            return ValidationStatus(vid, "failed", error=why)
        return ValidationStatus(vid, "done", result=rep)

    def wait_validation(self, vid: str, timeout: float = 600.0,
                        interval: float = 0.1) -> ValidationStatus:
        """Poll :meth:`validation` until it is done or failed (TimeoutError after
        ``timeout`` seconds)."""
        end = time.monotonic() + timeout
        while (st := self.validation(vid)).status not in ("done", "failed"):
            if time.monotonic() > end:
                raise TimeoutError(f"validation {vid} still {st.status} after {timeout:g} s")
            time.sleep(interval)
        return st

    # ------------------------------------------------------------------ schedules
    def schedule(self, req: ScheduleRequest) -> ScheduleAnswer:
        """Plan a multi-dose schedule (hold assumption, protocol check, shooting:
        :func:`dosing.question.schedule.plan_schedule_with`)."""
        from .question.schedule import plan_schedule_with

        return plan_schedule_with(self, req)

    def schedule_now(self, req: ScheduleRequest) -> ScheduleAnswer | None:
        """The hold schedule when no dose needs a new full-solver run and neither the
        protocol check nor the correction is asked for, else None (queues nothing)."""
        from .question.schedule import hold_now

        return hold_now(self, req)

    def close(self) -> None:
        """Shut down an owned executor and close the cache."""
        self.runs.close()

    def __enter__(self) -> Planner:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


class _Verdict(NamedTuple):
    """What the validation runs say of a dose (:meth:`Planner._verdict`)."""

    report: ValidationReport | None
    time: float
    estimate: float
    explanation: str
    key: str  # the truth run's scenario key


def _verdict_key(req: DoseRequest, choice: ModelChoice) -> tuple[Any, ...]:
    """What a front-model verdict depends on besides the stored runs: the validation runs
    (jump, settings, ell range), the start radius, the dose and the model's answer."""
    s = req.settings
    return (req.gel, req.t_start, req.t_end, req.branch, s, s.auto_length,
            req.interfacial_range, req.start_radius, req.fraction, choice)


def _copy_report(rep: ValidationReport) -> ValidationReport:
    """A remembered report for one answer: its containers copied (an answer's report may
    be changed by its caller; the remembered one may not)."""
    return ValidationReport(*[plain(getattr(rep, f)) for f in _REPORT_FIELDS])


_REPORT_FIELDS = tuple(f.name for f in fields(ValidationReport))


def one_shot(cache_path: str | None, executor: Executor | None, **kw: Any) -> Planner:
    """A throw-away planner on ``cache_path`` whose full-solver work runs in this process (no
    pool start-up): the one-call functions' (``plan_dose``, ``question.plan``, the CLI)."""
    return Planner(cache_path=cache_path, executor=executor or ThreadPoolExecutor(2), **kw)


class _JumpPath:
    """A jump's dose: the planner's own models and the jump's validation runs."""

    @staticmethod
    def answer(planner: Planner, req: DoseRequest, validate: bool) -> Answered | Pending:
        return planner._jump_answer(req, validate)

    @staticmethod
    def dose(planner: Planner, req: DoseRequest, validate: bool) -> Any:
        return planner._jump_dose(req, validate)


class _ProtocolPath:
    """A dose under heating steps (``dosing.heating.response``: the reduced slow-heating
    model in its region, else the full solver)."""

    @staticmethod
    def answer(planner: Planner, req: DoseRequest, validate: bool) -> Answered | Pending:
        from .heating import response

        out = response.answer(planner, req, validate)
        return out if isinstance(out, Pending) else Answered(out)  # type: ignore[arg-type]

    @staticmethod
    def dose(planner: Planner, req: DoseRequest, validate: bool) -> Any:
        from .heating import response

        return response.dose(planner, req, validate)


# the dose paths by the request's heating (``DoseRequest.heating_kind``): a registry like
# ``dosing.question.cells.CELLS``, so the planner's entry points do not branch on it
_DOSE_PATHS: dict[str, type[_JumpPath] | type[_ProtocolPath]] = {
    "jump": _JumpPath, "protocol": _ProtocolPath}
