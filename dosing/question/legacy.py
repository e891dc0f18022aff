"""The planner's older request types as one :class:`~dosing.question.request.Request`
(kept for one release: ``DoseRequest``, ``ScheduleRequest`` and the drug ones answer through
the one pipeline where their cell needs it, e.g. a ``DoseRequest`` with a batch)."""

from __future__ import annotations

from typing import Any

from .axes import Batch, Dose, Drug, Fluid, Heating, Jump, OneBead, Schedule
from .request import Request


def request_of(req: Any, validate: bool = False) -> Request:
    """The one request a resolved older request asks (its resolved fields: the gel, the
    bead's size, the settings at its own interfacial length)."""
    sizes = getattr(req, "size_distribution", None)
    drug = getattr(req, "drug", None)
    heating = getattr(req, "heating", None)
    if hasattr(req, "doses"):
        question: Any = Schedule(doses=getattr(req, "fractions", None) or req.doses,
                                 rests=req.rests, check_protocol=req.check_protocol,
                                 correct=req.correct, tolerance=req.tolerance)
    else:
        question = Dose(fraction=req.fraction)
    return Request(
        req.gel, req.t_start, Jump(req.t_end) if heating is None else Heating(heating),
        question, payload=Fluid() if drug is None else Drug(drug, wait=req.lead),
        population=OneBead() if sizes is None else Batch(sizes),
        dry_radius_um=req.dry_radius_um, swollen_radius_um=req.swollen_radius_um,
        constants=req.constants, branch=req.branch, settings=req.settings,
        validate=validate)

