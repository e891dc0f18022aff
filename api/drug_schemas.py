"""The optional ``drug`` of the dose and schedule requests (a pydantic model).

With it, doses are drug, not fluid: ``dose_fraction`` / ``doses`` are fractions of the
loaded drug and ``drug_mass_ug`` is a drug mass (needs ``load_ug`` or a loading
concentration with a bead size).  Referenced by one line in each request model of
:mod:`api.schemas`.
"""

from __future__ import annotations

from typing import Any, Literal

from pydantic import BaseModel, ConfigDict, Field, ValidationInfo, field_validator, model_validator

from dosing.drug import REFERENCE_TEMPERATURE_K
from solver.limits import T_MAX, T_MIN

from .outputs import Out as _Out
from .outputs import UncertaintyOut


class _StrictIn(BaseModel):
    """Strict and finite like every request model (api.schemas.RequestModel, which imports
    this module: the same config, written here to keep the import one-way)."""

    model_config = ConfigDict(extra="forbid", strict=True, allow_inf_nan=False)

    @field_validator("*", mode="before")
    @classmethod
    def _units(cls, value: Any, info: ValidationInfo) -> Any:
        """Strings with a unit ("1 mg", "5 nm") in physical fields (dosing.quantity)."""
        from dosing.quantity import from_edge

        return from_edge(info.field_name or "", value)


class DrugIn(_StrictIn):
    """A drug dissolved in the pore fluid: diffusion D0 f(phi), partition, release medium,
    load.  Give ``diffusivity_cm2_s`` or ``solute_radius_nm`` (Stokes-Einstein); neither
    means D0 = 0 (carried by the fluid only)."""

    model_config = ConfigDict(json_schema_extra={
        "examples": [{"diffusivity_cm2_s": 1e-7, "mesh_size_nm": 23.0, "load_ug": 1.0}]})

    diffusivity_cm2_s: float | None = Field(
        None, ge=0.0, le=1e-3, examples=[1e-7],
        description="the drug's diffusivity in water D0 in cm^2/s, 0 <= D0 <= 1e-3 (0: no "
                    "diffusion, the drug leaves with the fluid only)")
    solute_radius_nm: float | None = Field(
        None, gt=0.0, le=1e4, description="Stokes-Einstein radius in nm, 0 < r <= 1e4 (gives "
                                          "D0 when diffusivity_cm2_s is not set)")
    hindrance: Literal["free-volume", "ogston", "amsden", "none"] = Field(
        "free-volume", description="hindrance law D = D0 f: 'free-volume' (Lustig & "
        "Peppas 1988: (1 - r_s/xi) exp(-Y v/(1-v)), v the polymer fraction), 'ogston' "
        "(Ogston, Preston & Wells 1973: exp(-sqrt(v) (1 + r_s/r_f))), 'amsden' (1998: "
        "exp(-pi ((r_s + r_f)/(xi + 2 r_f))^2)) or 'none' (no hindrance, no sieving)")
    mesh_size_nm: float | None = Field(
        None, gt=0.0, le=1e4, description="mesh size xi of the swollen gel at t_start in nm, "
        "overriding for the drug the gel's dry mesh (constants.mesh_length_nm, the "
        "interfacial length's); unset: the gel's mesh, affine in the local stretch")
    reference_temperature_k: float = Field(
        REFERENCE_TEMPERATURE_K, ge=T_MIN, le=T_MAX,
        description="temperature at which diffusivity_cm2_s is "
        "given, K (default 25 degC); carried to t_end by Stokes-Einstein with water's "
        "viscosity")
    sieving: bool = Field(True, description="convective sieving of the expelled fluid's "
                                            "solute by the local mesh (Dechadilok & Deen 2006)")
    partition_law: Literal["constant", "ogston"] | None = Field(
        None, description="steric partition K_s(phi) multiplying partition: Ogston 1958 "
        "exp(-v (1 + r_s/r_f)^2) or constant; unset: Ogston's with a fibre radius")
    mesh_stretch: Literal["smallest", "volume"] = Field(
        "smallest", description="which stretch sets the local mesh: the smallest principal "
        "stretch (default) or J^(1/3)")
    fiber_radius_nm: float | None = Field(
        None, gt=0.0, le=1e3, description="polymer fibre radius r_f in nm (Ogston's law)")
    free_volume_y: float = Field(1.0, gt=0.0, le=100.0,
                                 description="Y of the free-volume law, 0 < Y <= 100 (1)")
    partition: float = Field(1.0, ge=1e-6, le=1e6, description=(
        "equilibrium partition K = c_pore / c_medium, 1e-6 <= K <= 1e6 (> 0; default 1)"))
    release_volume_ul: float | None = Field(
        None, gt=0.0, le=1e9, description="volume of a well-mixed release medium in uL, larger "
        "than the swollen bead (needs a bead size); unset: a perfect sink")
    load_ug: float | None = Field(None, gt=0.0, le=1e9,
                                  description="drug loaded per bead in ug, 0 < m <= 1e9")
    loading_concentration_ug_per_ul: float | None = Field(
        None, gt=0.0, le=1e6, description="drug concentration of the loading solution in "
        "ug/uL (the pore fluid holds partition x it; needs a bead size)")
    wait: float | None = Field(None, ge=0.0, le=1e4, description=(
        "time in the medium at t_start before the first heating, dimensionless (units of tau; "
        "default 0): the bead leaks by diffusion meanwhile"))
    wait_seconds: float | None = Field(None, ge=0.0, le=1e9,
                                       description="the wait in seconds (needs a bead size)")

    @model_validator(mode="after")
    def _one_load(self) -> DrugIn:
        if self.load_ug is not None and self.loading_concentration_ug_per_ul is not None:
            raise ValueError("give load_ug or loading_concentration_ug_per_ul, not both")
        if self.wait is not None and self.wait_seconds is not None:
            raise ValueError("give wait or wait_seconds, not both")
        return self

    def model_kwargs(self) -> dict[str, Any]:
        """The fields of dosing.drug.DrugModel (the wait excluded)."""
        return self.model_dump(exclude={"wait", "wait_seconds"}, exclude_none=True)




class _StatedTruthOut(_Out):
    """What every drug answer states: its runs' interfacial length, bead size and model."""

    interfacial_length: float = Field(
        description="interfacial length ell (dry radii) of the full-solver runs: the fluid "
                    "answers' truth, the bead's own xi_dry / a_d by default")
    bead_dry_radius_um: float | None = Field(None, description="the bead size assumed (um)")
    truth: str = Field(description="the model the drug runs use, in words (as the fluid "
                                   "answers' truth)")


class DrugDoseResponse(_StatedTruthOut):
    """HTTP 200 for a dose with a ``drug``: the actuation time for the drug dose, the leak
    before heating and how the drug came out."""

    status: Literal["answered"] = Field("answered", description="always 'answered'")
    drug: Literal[True] = Field(True, description="always true: a drug answer")
    model: str = Field(description="what answered: the fluid answer's model (D0 = 0), "
                                   "'front-solute' (the reduced drug model, the solute on "
                                   "the front model's bead: docs/drug_reduced.md) or "
                                   "'full+solute' (the full solver with the drug)")
    time: float = Field(description="actuation time for the drug dose, units of tau, >= 0")
    seconds: float | None = Field(None, description="the actuation time in s (bead size)")
    dose_fraction: float = Field(description="the dose as a fraction of the loaded drug")
    dose_ug: float | None = Field(None, description="the dose in ug (with a load)")
    load_ug: float | None = Field(None, description="drug loaded per bead in ug")
    wait: float = Field(description="time at t_start before heating, units of tau")
    leaked_before_heating: float = Field(
        description="fraction of the load leaked by diffusion during the wait")
    leaked_before_heating_ug: float | None = Field(None, description="the same in ug")
    leak_time_10pct: float = Field(
        description="time at t_start in which 10 % of the load leaks, units of tau")
    leak_time_10pct_seconds: float | None = Field(None, description="the same in s")
    squeezed_fraction: float = Field(
        description="fraction of the load that left with the expelled fluid")
    diffused_fraction: float = Field(
        description="fraction of the load that left by diffusion through the edge")
    mechanism: str = Field(description="'squeezed out' or 'diffused', with the split")
    fluid_fraction: float = Field(description="fraction of the stored fluid expelled by then")
    medium_concentration_ug_per_ul: float | None = Field(
        None, description="drug concentration in a finite release volume, ug/uL")
    effective_diffusivity_cm2_s: float = Field(
        description="hindered diffusivity D0 f(phi) in the start state, cm^2/s")
    drug_diffusivity_cm2_s: float = Field(description="the drug's diffusivity in water D0")
    mass_balance_error: float = Field(
        description="|loaded - in gel - released| / loaded of the drug run")
    timescale_seconds: float | None = Field(None, description="tau in s (eq. timescale)")
    fluid_answer: dict[str, Any] | None = Field(
        None, description="the fluid answer for the same time (model, interfacial length, "
                          "error estimate)")
    scenario_key: str | None = Field(None, description="key of the drug run")
    note: str = Field(description="caveats, in words")
    peclet: float | None = Field(None, description="the heating's Peclet number: mean "
                                 "shrinking speed x swollen radius / D0 f(phi0)")
    split: str = Field("", description="how squeezed and diffused are defined (squeezed: the "
                                       "release of the same mechanics with D0 = 0)")
    mesh: str = Field("", description="the mesh, solute radius, sieving and partition assumed")
    permeability_law: str = Field("none", description="the permeability's temperature law "
                                                      "(none: k0 as given)")
    uncertainty: UncertaintyOut | None = Field(
        None, description="the drug dose time's uncertainty in three parts: numerical (the "
                          "drug run at n / 2 cells), and the mechanics' interfacial-length "
                          "and model-form parts (from the fluid validation at the same fluid "
                          "fraction where it is cached, else null with how to measure them)")


class DrugScheduleResponse(_StatedTruthOut):
    """HTTP 200 for a schedule with a ``drug``: each reading in drug, leakage, warnings."""

    status: Literal["answered"] = Field("answered", description="always 'answered'")
    drug: Literal[True] = Field(True, description="always true: a drug answer")
    model: str = Field(description="what answered")
    doses: list[float] = Field(description="the doses, fractions of the loaded drug")
    doses_ug: list[float] | None = Field(None, description="the doses in ug (with a load)")
    load_ug: float | None = Field(None, description="drug loaded per bead in ug")
    rests: list[float] = Field(description="rests between doses, units of tau")
    wait: float = Field(description="time at t_start before the first heating, units of tau")
    hold: list[dict[str, Any]] = Field(
        description="hold reading: per dose its actuation time and the drug it delivers")
    protocol_check: dict[str, Any] | None = Field(
        None, description="the hold times simulated as heat/rest: drug per dose, leak per rest")
    corrected: dict[str, Any] | None = Field(
        None, description="actuation times shot so that each drug dose is met")
    warnings: list[str] = Field(description="leaky rests, doses no actuation time can meet")
    leak_time_10pct: float = Field(
        description="time at t_start in which 10 % of the load leaks, units of tau")
    effective_diffusivity_cm2_s: float = Field(
        description="hindered diffusivity in the start state, cm^2/s")
    timescale_seconds: float | None = Field(None, description="tau in s (eq. timescale)")
    note: str = Field(description="caveats, in words")
    uncertainty: UncertaintyOut | None = Field(
        None, description="a simulated schedule's uncertainty: numerical (the same protocol "
                          "on n / 2 cells: the largest change of a delivered dose); the other "
                          "two parts are the single doses' (null here, with how to get them)")
