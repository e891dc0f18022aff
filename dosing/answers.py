"""The planner's answers as types: the model choice, the validation report, a dose's answer,
``Answered | Pending`` (one planner call per request), a validation's state, hold rows.

A leaf (the planner, the report, the schedules and the service import it; it imports none of
them).  ``to_dict()`` is a record's JSON; reports that were dicts still index like them
(``report["time"]``, ``row.get("end")``).  docs/architecture.md, "The life of a dose request"."""

from __future__ import annotations

import copy
import functools
from dataclasses import dataclass, fields
from typing import Any

from solver.presenters import presenter

from .truth import Uncertainty

_ATOMS = (str, int, float, type(None))  # immutable leaves (bool is an int)
_EXACT_ATOMS = frozenset((str, int, float, bool, type(None)))


@functools.cache
def _field_names(cls: type) -> tuple[str, ...]:
    return tuple(f.name for f in fields(cls))


def plain(obj: Any) -> Any:
    """``dataclasses.asdict(obj)``: records as dicts, lists, tuples and dicts copied, other
    leaves deep-copied; the same result, but immutable leaves (str, int, float, None) are
    not passed through ``copy.deepcopy``, which made an answer's ``to_dict`` a quarter of
    its cost."""
    cls = type(obj)
    # the JSON-like bulk of a report first, by exact type (a report's runs are dicts and
    # lists of numbers and strings: this path copies them in a quarter of the general one)
    if cls in _EXACT_ATOMS:
        return obj
    if cls is dict:
        return {k if type(k) is str else plain(k): plain(v) for k, v in obj.items()}
    if cls is list:
        return [plain(v) for v in obj]
    if isinstance(obj, _ATOMS):
        return obj
    if hasattr(cls, "__dataclass_fields__"):
        return {name: plain(getattr(obj, name)) for name in _field_names(cls)}
    if isinstance(obj, tuple) and hasattr(obj, "_fields"):  # a namedtuple
        return cls(*[plain(v) for v in obj])
    if isinstance(obj, (list, tuple)):
        return cls(plain(v) for v in obj)
    if isinstance(obj, dict):
        return cls((plain(k), plain(v)) for k, v in obj.items())
    return copy.deepcopy(obj)


class ByKey:
    """Read access by field name, as the dict such a record replaced (``rec["time"]``)."""

    def __getitem__(self, key: str) -> Any:
        if key not in {f.name for f in fields(self)}:  # type: ignore[arg-type]
            raise KeyError(key)
        return getattr(self, key)

    def get(self, key: str, default: Any = None) -> Any:
        """The field ``key``, or ``default`` when there is no such field."""
        try:
            return self[key]
        except KeyError:
            return default

    def to_dict(self) -> dict[str, Any]:
        """Plain-data form (JSON-ready)."""
        return plain(self)


@dataclass(frozen=True)
class ModelChoice:
    """Which model answers a dose request, decided from the initial equilibrium alone: ``radius``
    the target radius (eq. FluidVolExpelled); ``model`` 'front' (the paper's), 'front-sharp' or
    'full'; ``why`` in words; ``front_time`` the front model's time in tau (None where the full
    solver answers); ``behaviour`` the jump classifier's verdict."""

    radius: float
    model: str
    why: str
    front_time: float | None
    behaviour: str

    @property
    def needs_full(self) -> bool:
        """True when only the full solver can answer (no front-model time)."""
        return self.front_time is None


@dataclass(frozen=True)
class Verdict:
    """A reduced model's verdict on a request, one shape for every such model (the slow-
    heating front model, ``dosing.heating.reduced``; the reduced drug model,
    ``dosing.payload.reduced``): whether it ``applies`` (the request is inside its measured
    region), ``why`` in words, and the ``stated_error`` it answers with where it applies."""

    applies: bool
    why: str
    stated_error: float | None = None


@dataclass(frozen=True)
class ValidationReport(ByKey):
    """The full solver's verdict on a dose (:func:`dosing.validation.validation_report`): ``runs``
    (per run: grid, n, ell, key, times, wall time, warning or error, ``role``); ``time`` the truth's
    (None if its runs failed), ``error``; ``limit`` (ladder), ``grid_spread`` (the paper's grids),
    ``uncertainty`` (``Uncertainty.to_dict``), ``front_*`` the front model's time and errors."""

    model: str
    method: str
    interfacial_length: float
    settings: dict[str, Any]
    runs: list[dict[str, Any]]
    time: float | None = None
    error: float | None = None
    limit: dict[str, Any] | None = None
    grid_spread: float | None = None
    front_time: float | None = None
    front_time_error: float | None = None
    front_volume_error: float | None = None
    uncertainty: dict[str, Any] | None = None


@dataclass
class DoseAnswer:
    """How long to heat: dimensionless and in seconds, with the model and its error."""

    model: str
    interfacial_length: float
    truth: str
    time: float
    seconds: float | None
    timescale_seconds: float | None
    timescale_formula: str
    start_radius: float
    final_radius: float
    final_radius_um: float | None
    expelled_volume: float
    expelled_volume_ul: float | None
    stored_volume: float
    stored_volume_ul: float | None
    dose_fraction: float
    error_estimate: float
    error_explanation: str
    validation: ValidationReport | None
    scenario_key: str
    behaviour: str
    note: str
    parameter_interval: dict[str, Any] | None = None  # a fitted gel's (dosing.fits.uncertainty)
    method: str = "direct"  # the truth: 'direct', 'ladder' or 'paper'
    bead_dry_radius_um: float | None = None  # the bead size the truth's ell assumes
    uncertainty: Uncertainty | None = None  # the direct truth's three parts (validated)
    # the seconds' uncertainty from the timescale constants, or a kinetics fit's interval
    # (dosing.units.timescale_uncertainty)
    timescale_uncertainty: dict[str, Any] | None = None

    def to_dict(self) -> dict[str, Any]:
        """Plain-data form (JSON-ready)."""
        return plain(self)

    def to_dataframe(self) -> Any:
        """One row: the answer, its error and uncertainty parts, the truth (pandas)."""
        return presenter("answer_frame")(self)

    def _repr_html_(self) -> str:
        return presenter("answer_html")(self)


@dataclass(frozen=True)
class Answered:
    """A dose answered now (front model, or full-solver runs already cached): HTTP 200.
    ``validation_id``: the validation queued alongside when one was asked for."""

    answer: DoseAnswer
    validation_id: str | None = None


@dataclass(frozen=True)
class Pending:
    """A dose that needs full-solver runs not cached yet: they are queued as the validation
    ``validation_id`` (HTTP 202); asked again once it is done, the dose is answered."""

    validation_id: str


@dataclass
class ValidationStatus:
    """A validation's state; ``result`` when done, ``error`` when failed."""

    id: str
    status: str
    result: ValidationReport | None = None
    error: str | None = None

    def to_dict(self) -> dict[str, Any]:
        """Plain-data form."""
        return plain(self)


@dataclass(frozen=True)
class HoldRow(ByKey):
    """One dose of a schedule under the hold assumption (doses read off one heating)."""

    dose_fraction: float
    cumulative_fraction: float
    start: float
    end: float
    actuation_time: float
    actuation_seconds: float | None
    error_estimate: float | None = None  # None: a drug run's hold reading (no estimate)
