"""One request: a case x payload x population x heating x question, validated once.

The case (``dosing.request.Case``: gel, T_start, bead size, timescale constants, start branch,
truth settings) is what every request shares; the axes are ``dosing.question.axes``' values.
Construction resolves it into its cell's planner request (``dosing.question.cells``), so a bad
field raises ``ParameterError`` at once, whatever the way in (HTTP 422, CLI exit 2)."""

from __future__ import annotations

import functools
from dataclasses import dataclass, field
from typing import Any

from .axes import Dose, Fluid, Heating, Jump, OneBead, Schedule


def _plain(value: Any) -> Any:
    return value.to_dict() if hasattr(value, "to_dict") else value


def _gel(gel: Any) -> Any:
    """The gel as asked: a preset's or a stored gel's name (it resolves to the same gel),
    a custom gel's parameters."""
    name = getattr(gel, "name", None)
    return name if isinstance(name, str) and name != "custom" else _plain(gel)


@dataclass(frozen=True)
class Request:
    """What the planner is asked: ``gel``, ``t_start``, the bead (``dry_radius_um`` or
    ``swollen_radius_um``; a batch's reference size), ``constants``, ``branch``, ``settings``; the
    axes ``payload`` (default ``Fluid``), ``population`` (``OneBead``), ``heating`` (``Jump`` or
    ``Heating``), ``question`` (``Dose`` or ``Schedule``); ``validate`` (also run the truth)."""

    gel: Any
    t_start: Any
    heating: Jump | Heating
    question: Dose | Schedule
    payload: Any = field(default_factory=Fluid)
    population: Any = field(default_factory=OneBead)
    dry_radius_um: Any = None
    swollen_radius_um: Any = None
    constants: Any = None
    branch: str | None = None
    settings: Any = None
    validate: bool = False

    def __post_init__(self) -> None:
        self.planned  # noqa: B018 - resolved (and so validated) once, on construction

    @property
    def cell_key(self) -> tuple[str, str, str, str]:
        """(payload, population, heating, question): the cell that answers."""
        return (self.payload.key, self.population.key, self.heating.key, self.question.key)

    @property
    def cell_name(self) -> str:
        """The cell in words, e.g. 'fluid · batch · jump · dose'."""
        return " · ".join(self.cell_key)

    @functools.cached_property
    def cell(self) -> Any:
        """The cell's implementation (``dosing.question.cells.CELLS``)."""
        from .cells import cell_for

        return cell_for(self.cell_key)

    @functools.cached_property
    def planned(self) -> Any:
        """The planner's request of this cell, resolved (gel, jump, bead, dose...)."""
        return self.cell.build(self)

    def case_fields(self) -> dict[str, Any]:
        """The case's fields as the planner's requests take them."""
        return {"gel": self.gel, "t_start": self.t_start, "dry_radius_um": self.dry_radius_um,
                "swollen_radius_um": self.swollen_radius_um, "constants": self.constants,
                "branch": self.branch, "settings": self.settings}

    def to_dict(self) -> dict[str, Any]:
        """The request as asked (JSON-ready): echoed in its answer."""
        case = {k: _plain(v) for k, v in self.case_fields().items()}
        case["gel"] = _gel(self.gel)
        return {**case, "payload": self.payload.to_dict(),
                "population": self.population.to_dict(), "heating": self.heating.to_dict(),
                "question": self.question.to_dict(), "validate": self.validate}
