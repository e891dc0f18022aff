"""An HTTP body as the planner's one request (``dosing.question.Request``): the body's
optional fields (``protocol``, ``drug``, ``size_distribution``) pick the value of each
axis here, once, so that the service's adapter only plans the request it is given."""

from __future__ import annotations

import math
from typing import Any

from dosing.question import Batch, Dose, Drug, Fluid, Heating, Jump, OneBead, Request, Schedule
from dosing.request import resolve_gel
from dosing.runs.scenario import SolverSettings
from solver.errors import ParameterError
from solver.gel import Gel

from . import schemas as s


def to_gel(spec: str | s.GelParameters) -> Gel:
    """The solver gel a request names: a preset or stored gel, or one with parameters
    replaced (``dosing.request.resolve_gel``: one rule for HTTP, CLI and Python)."""
    if isinstance(spec, str):
        return resolve_gel(spec)
    return resolve_gel(spec.model_dump(include=set(s.GelParameters.model_fields),
                                       exclude_none=True))


def http_protocol(t_start: float, steps: Any) -> Any:
    """The one parser of a protocol sent over HTTP (every route): steps as text or data, a
    measured trace as CSV text or lists; a step naming a file ('Trace from <path>') is a
    422 naming it (``protocol[i].trace``): no route opens a path a request names."""
    from dosing.heating.grammar import Protocol

    for i, step in enumerate(steps if isinstance(steps, list) else []):
        for key, value in (step.items() if isinstance(step, dict) else ()):
            if _non_finite(value):  # JSON's NaN / Infinity in a structured step
                raise ParameterError(f"protocol[{i}]", f"{str(key)[:40]}: {value!r:.40}",
                                     "finite numbers")
    return Protocol(t_start, steps, files=False)


def _non_finite(value: Any) -> bool:
    if isinstance(value, float):
        return not math.isfinite(value)
    if isinstance(value, (list, tuple)):
        return any(isinstance(x, float) and not math.isfinite(x) for x in value)
    if isinstance(value, dict):
        return any(_non_finite(x) for x in value.values())
    return False


def _heating(body: Any) -> Jump | Heating:
    """A jump to t_end, or the protocol (no file paths over HTTP)."""
    if getattr(body, "protocol", None) is None:
        return Jump(body.t_end)
    if body.t_end is not None:
        raise ParameterError("t_end", body.t_end, "absent when a protocol is given (the "
                             "protocol's steps set the heating)")
    return Heating(http_protocol(body.t_start, body.protocol))


def _payload(body: Any) -> Fluid | Drug:
    """The fluid, or the drug with its batch's medium; a medium without a drug is refused."""
    medium = {"medium_volume_ml": getattr(body, "medium_volume_ml", None),
              "bead_count": getattr(body, "bead_count", None)}
    if body.drug is None:
        for name, value in medium.items():
            if value is not None:
                raise ParameterError(name, value, "null without a drug and a "
                                     "size_distribution (the medium a drug batch shares)")
        return Fluid()
    from dosing.payload.drug import DrugModel

    return Drug(DrugModel(**body.drug.model_kwargs()), wait=body.drug.wait,
                wait_seconds=body.drug.wait_seconds, **medium)


def _population(body: Any) -> OneBead | Batch:
    if body.size_distribution is None:
        return OneBead()
    return Batch(body.size_distribution.model_dump(exclude_none=True))


def _question(body: s.DoseTimeRequest | s.ScheduleRequest) -> Dose | Schedule:
    if isinstance(body, s.ScheduleRequest):
        return Schedule(doses=body.doses, rests=body.rests, rests_seconds=body.rests_seconds,
                        check_protocol=body.check_protocol, correct=body.correct,
                        tolerance=body.tolerance)
    return Dose(fraction=body.dose_fraction, volume_ul=body.dose_volume_ul,
                drug_mass_ug=body.drug_mass_ug,
                concentration_ug_per_ul=body.concentration_ug_per_ul)


def to_request(body: s.DoseTimeRequest | s.ScheduleRequest) -> Request:
    """The planner's request (ParameterError names a bad field: HTTP 422)."""
    return Request(
        to_gel(body.gel), body.t_start, _heating(body), _question(body),
        payload=_payload(body), population=_population(body),
        dry_radius_um=body.dry_radius_um, swollen_radius_um=body.swollen_radius_um,
        constants=None if body.constants is None
        else body.constants.model_dump(exclude_none=True),
        branch=body.branch,
        settings=SolverSettings(interfacial_length=body.interfacial_length,
                                method=body.validation_method),
        validate=bool(getattr(body, "validate_full", False)))
