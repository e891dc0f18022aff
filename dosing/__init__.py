"""thermogel dose planner: actuation times, schedules, units, validation cache.

    from . import DoseRequest, plan_dose
    ans = plan_dose(DoseRequest("ANB", 302, 308, dose_fraction=0.8, dry_radius_um=50))

Times in tau (eq. timescale), s given a bead size; no fastapi/matplotlib (docs/architecture.md)."""

from __future__ import annotations

from concurrent.futures import Executor
from typing import TYPE_CHECKING, Any

from solver.lazy import lazy_names
from solver.presenters import register as _register_presenters

# the solver's records (runs, fits) and the planner's answers get their tables, netCDF and
# notebook views from this layer (dosing.present: export, tables), imported only when asked
_EXPORT, _TABLES = "dosing.present.export:", "dosing.present.tables:"
_register_presenters(
    **{name: _EXPORT + name for name in ("run_dataset", "fit_dataset", "to_netcdf",
                                         "schedule_dataset", "schedule_result_dataset",
                                         "sweep_dataset")},
    # the planner's own answers, schedules and sweeps among them (their tables live above
    # them: no import of dosing.present from the modules they present)
    **{name: _TABLES + name for name in ("run_frame", "run_html", "fit_frame", "fit_html",
                                         "answer_frame", "answer_html", "schedule_frame",
                                         "schedule_html", "sweep_frame", "result_frame",
                                         "result_html", "schedule_result_frame",
                                         "schedule_result_html")})

if TYPE_CHECKING:
    from .answers import (
        Answered,
        DoseAnswer,
        ModelChoice,
        Pending,
        ValidationReport,
        ValidationStatus,
    )
    from .planner import Planner, UnknownValidationError
    from .question.schedule import ScheduleAnswer
    from .request import DoseRequest, ScheduleRequest
    from .runs.cache import ValidationCache
    from .runs.jobs import JobRunner, QueueFullError
    from .runs.scenario import LADDER, PAPER, TRUTH, Scenario, SolverSettings, Trajectory
    from .truth import Uncertainty
    from .units import PhysicalConstants, Timescale, timescale, water_viscosity

# imported on first use (PEP 562): ``import dosing.x`` or a CLI command pays only for the
# modules it touches
_LAZY = {
    **dict.fromkeys(("Answered", "DoseAnswer", "ModelChoice", "Pending", "ValidationReport",
                     "ValidationStatus"), ".answers"),
    "ValidationCache": ".runs.cache", "JobRunner": ".runs.jobs", "QueueFullError": ".runs.jobs",
    "Planner": ".planner", "UnknownValidationError": ".planner",
    "DoseRequest": ".request", "ScheduleRequest": ".request",
    **dict.fromkeys(("LADDER", "PAPER", "TRUTH", "Scenario", "SolverSettings", "Trajectory"),
                    ".runs.scenario"),
    "ScheduleAnswer": ".question.schedule", "Uncertainty": ".truth",
    **dict.fromkeys(("PhysicalConstants", "Timescale", "timescale", "water_viscosity"),
                    ".units"),
}


__getattr__ = lazy_names(__name__, _LAZY, globals())


def plan_dose(req: DoseRequest, validate: bool = False, cache_path: str | None = None,
              executor: Executor | None = None, **planner_kw: Any) -> Any:
    """One dose with a throw-away :class:`Planner` (the cache persists), through the one
    pipeline (``dosing.question``): a ``DoseResult`` whatever the request's cell (a batch's
    own time for a batch), with the envelope; the cell's answer's fields read through it
    (``time``, ``seconds``, ``error_estimate``, ...) as the older ``DoseAnswer``'s did."""
    return _one_request(req, validate, cache_path, executor, planner_kw)


def plan_schedule(req: ScheduleRequest, cache_path: str | None = None,
                  executor: Executor | None = None, **planner_kw: Any) -> Any:
    """One schedule with a throw-away :class:`Planner` (the cache persists), through the one
    pipeline: a ``ScheduleResult`` (its headline the corrected times when corrected), with
    the envelope; the ``ScheduleAnswer``'s fields read through it."""
    return _one_request(req, False, cache_path, executor, planner_kw)


def _one_request(req: Any, validate: bool, cache_path: str | None,
                 executor: Executor | None, planner_kw: dict[str, Any]) -> Any:
    from . import planner as planner_module
    from .question import run
    from .question.legacy import request_of

    request = request_of(req, validate)  # a bad request fails before a planner starts
    planner = planner_module.one_shot(cache_path, executor, **planner_kw)
    try:
        return run(planner, request)
    finally:
        planner.close()
        if executor is None:
            planner.jobs.executor.shutdown(wait=True)


__all__ = [
    "LADDER", "PAPER", "TRUTH", "Answered", "DoseAnswer", "DoseRequest", "JobRunner",
    "ModelChoice", "Pending", "PhysicalConstants", "Planner",
    "QueueFullError", "Scenario", "ScheduleAnswer", "ScheduleRequest", "SolverSettings",
    "Timescale", "Trajectory", "Uncertainty", "UnknownValidationError", "ValidationCache",
    "ValidationReport", "ValidationStatus",
    "plan_dose", "plan_schedule", "timescale", "water_viscosity",
]
