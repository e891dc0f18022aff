"""The drug answers of the dose and schedule routes: the fluid answers' fields
(:class:`api.schemas.DoseOut`, :class:`api.schemas.ScheduleOut`, written once there) and
what the drug adds.  The drug itself, the requests' optional ``drug``, is
:class:`api.schemas.DrugIn`."""

from __future__ import annotations

from typing import Any, Literal

from pydantic import Field

from .outputs import Out
from .schemas import DoseOut, ScheduleOut, StatedOut


class DrugOut(Out):
    """What every drug answer adds (dosing.drug_dose.DrugCase): the load, the wait before
    the first heating, and how fast the bead leaks at T_start."""

    drug: Literal[True] = Field(True, description="always true: a drug answer")
    load_ug: float | None = Field(None, description="drug loaded per bead in ug")
    wait: float = Field(description="time at t_start before the first heating, units of tau")
    leak_time_10pct: float = Field(
        description="time at t_start in which 10 % of the load leaks, units of tau")
    effective_diffusivity_cm2_s: float = Field(
        description="hindered diffusivity D0 f(phi) in the start state, cm^2/s")


class DrugDoseResponse(DrugOut, DoseOut):
    """HTTP 200 for a dose with a ``drug``: the actuation time for the drug dose, the leak
    before heating and how the drug came out."""

    model: str = Field(description="what answered: the fluid answer's model (D0 = 0), "
                                   "'front-solute' (the reduced drug model, the solute on "
                                   "the front model's bead: docs/drug_reduced.md) or "
                                   "'full+solute' (the full solver with the drug)")
    dose_ug: float | None = Field(None, description="the dose in ug (with a load)")
    leaked_before_heating: float = Field(
        description="fraction of the load leaked by diffusion during the wait")
    leaked_before_heating_ug: float | None = Field(None, description="the same in ug")
    leak_time_10pct_seconds: float | None = Field(None, description="the same in s")
    squeezed_fraction: float = Field(
        description="fraction of the load that left with the expelled fluid")
    diffused_fraction: float = Field(
        description="fraction of the load that left by diffusion through the edge")
    mechanism: str = Field(description="'squeezed out' or 'diffused', with the split")
    fluid_fraction: float = Field(description="fraction of the stored fluid expelled by then")
    medium_concentration_ug_per_ul: float | None = Field(
        None, description="drug concentration in a finite release volume, ug/uL")
    drug_diffusivity_cm2_s: float = Field(description="the drug's diffusivity in water D0")
    mass_balance_error: float = Field(
        description="|loaded - in gel - released| / loaded of the drug run")
    fluid_answer: dict[str, Any] | None = Field(
        None, description="the fluid answer for the same time (model, interfacial length, "
                          "error estimate)")
    scenario_key: str | None = Field(None, description="key of the drug run")
    peclet: float | None = Field(None, description="the heating's Peclet number: mean "
                                 "shrinking speed x swollen radius / D0 f(phi0)")
    split: str = Field("", description="how squeezed and diffused are defined (squeezed: the "
                                       "release of the same mechanics with D0 = 0)")
    mesh: str = Field("", description="the mesh, solute radius, sieving and partition assumed")
    permeability_law: str = Field("none", description="the permeability's temperature law "
                                                      "(none: k0 as given)")


class DrugScheduleResponse(DrugOut, ScheduleOut, StatedOut):
    """HTTP 200 for a schedule with a ``drug``: each reading in drug, leakage, warnings."""

    doses_ug: list[float] | None = Field(None, description="the doses in ug (with a load)")
    warnings: list[str] = Field(description="leaky rests, doses no actuation time can meet")
