"""Request and answer models of the fit routes (``api.routers.fit``)."""

from __future__ import annotations

from typing import Annotated, Literal

from pydantic import BaseModel, ConfigDict, Field, field_validator, model_validator

from api.outputs import FitReport
from api.schemas import GelSpec, RequestModel
from dosing.gel_store import check_name
from solver.limits import T_MAX, T_MIN

SIZE_FIELDS = ("radius", "diameter", "volume_ratio")
FixedName = Literal["omega", "a0", "b0", "a1", "b1", "scale"]  # solver.fit.equilibrium.PARAMS
Temperature = Annotated[float, Field(ge=T_MIN, le=T_MAX)]
MAX_POINTS = 2000


class _In(RequestModel):

    radius: list[float] | None = Field(
        None, max_length=MAX_POINTS, description="bead radius, any unit"
    )
    diameter: list[float] | None = Field(
        None, max_length=MAX_POINTS, description="bead diameter, any unit"
    )
    volume_ratio: list[float] | None = Field(
        None, max_length=MAX_POINTS, description="volume, any reference"
    )
    weight: list[float] | None = Field(
        None, max_length=MAX_POINTS, description="optional relative weights (> 0)"
    )
    save: str | None = Field(
        None,
        description="store the fitted gel under this name (usable "
        "as the gel of later dose, schedule and simulate requests)",
    )

    @field_validator("save")
    @classmethod
    def _storable(cls, name: str | None) -> str | None:
        if name is not None:
            check_name(name)  # ParameterError is a ValueError: a 422 at ['body', 'save']
        return name

    @model_validator(mode="after")
    def _one_size(self) -> _In:
        given = [f for f in SIZE_FIELDS if getattr(self, f) is not None]
        if len(given) != 1:
            raise ValueError("give exactly one size column: radius, diameter or volume_ratio")
        return self

    @property
    def size_kind(self) -> str:
        """The size column given."""
        return next(f for f in SIZE_FIELDS if getattr(self, f) is not None)

    @property
    def size(self) -> list[float]:
        """Its values."""
        return getattr(self, self.size_kind)


class SwellingFitRequest(_In):
    """Equilibrium points (T, size) to fit Omega, A0, B0, A1, B1 and the size scale to."""

    model_config = ConfigDict(
        extra="forbid",
        json_schema_extra={
            "examples": [
                {
                    "temperature_K": [290, 295, 300, 303, 305, 306, 307, 308, 310, 315, 320],
                    "radius": [2.87, 2.69, 2.44, 2.19, 1.95, 1.13, 1.12, 1.11, 1.10, 1.085, 1.078],
                    "fixed": {"omega": 100.0},
                }
            ]
        },
    )

    temperature_K: list[float] = Field(max_length=MAX_POINTS, description="temperatures in K")
    sigma_t: float = Field(0.05, gt=0, description="temperature noise, K")
    size_rel_sigma: float = Field(0.01, gt=0, description="relative size noise")
    fixed: dict[FixedName, float] | None = Field(
        None, description="parameters kept fixed (omega, scale, b0, b1; a0 with b0, a1 with b1)"
    )
    n_starts: int = Field(6, ge=1, le=50, description="polished starts of the global search")
    objective: Literal["orthogonal", "temperature"] = Field(
        "orthogonal", description="'orthogonal' (errors in both variables, judged by "
        "chi-square under the stated noise) or 'temperature' (the paper's residual)")
    dry_size: float | None = Field(
        None, gt=0, description="a measured dry size in the data's unit: fixes the scale")
    dose_jump: list[float] | None = Field(
        None, min_length=2, max_length=2, description="[T_start, T_end] in K: also state the "
        "dose time of this jump under both objectives, flagged when they disagree")
    dose_fraction: float = Field(0.8, gt=0, lt=1, description="the dose of dose_jump")


class KineticsFitRequest(_In):
    """A shrinking curve after a jump T_start -> T_end, to fit tau (hence k0)."""

    model_config = ConfigDict(
        extra="forbid",
        json_schema_extra={
            "examples": [
                {
                    "time_s": [0, 50, 100, 200, 400, 800],
                    "radius": [115, 100, 90, 75, 62, 56],
                    "gel": "ANB",
                    "t_start": 302.0,
                    "t_end": 308.0,
                    "dry_radius_um": 50.0,
                }
            ]
        },
    )

    time_s: list[float] = Field(max_length=MAX_POINTS, description="times after the jump, s")
    gel: GelSpec = "ANB"
    t_start: Temperature = Field(description="start temperature, K, 273.15-373.15")
    t_end: Temperature = Field(description="jump temperature, K, 273.15-373.15")
    branch: Literal["swollen", "shrunken"] | None = Field(
        None, description="start branch at T_start (default swollen when heating)")
    dry_radius_um: float | None = Field(None, gt=0, description="dry bead radius, um")
    swollen_radius_um: float | None = Field(None, gt=0, description="bead radius at T_start")
    viscosity_pa_s: Annotated[float, Field(gt=0.0, le=10.0)] | Literal["water"] = Field(
        1.0e-3, description="fluid viscosity in Pa s, 0 < eta <= 10, or 'water' (water at "
                            "T_end), for k0")
    polymer_volume_m3: float = Field(3.0e-25, gt=0, description="Omega_p in m^3, for k0")
    model: Literal["auto", "front", "front-sharp", "full"] = Field(
        "auto", description="model of the curve: the front models (milliseconds), the full "
        "solver (one run per beta), or auto (the planner's choice)")
    fit_beta: bool = Field(False, description="also fit beta of k = phi/(1-phi)^beta "
                           "(model 'full' only)")
    beta: float | None = Field(None, gt=0, lt=10, description="permeability exponent, "
                               "0 < beta < 10: fixed, or the start of its fit")
    interfacial_length: float | None = Field(None, ge=0, description="full solver's ell")
    size_rel_sigma: float = Field(0.01, gt=0, description="relative size noise")

    @model_validator(mode="after")
    def _one_bead_size(self) -> KineticsFitRequest:
        if self.dry_radius_um is not None and self.swollen_radius_um is not None:
            raise ValueError("give at most one bead size: dry_radius_um or swollen_radius_um")
        return self


class FitJobResponse(BaseModel):
    """A fit job: poll ``status_url`` until ``status`` is done (``result``) or failed."""

    model_config = ConfigDict(extra="allow")

    id: str = Field(description="the job id")
    kind: Literal["swelling", "kinetics"] = Field(description="which fit")
    status: Literal["pending", "running", "done", "failed"] = Field(description="job state")
    status_url: str = Field(description="where to poll")
    result: FitReport | None = Field(
        None,
        description="the fit report: parameters, intervals (95%), chi2, aic, bic, "
        "rms_orthogonal_K, rms_temperature_residual_K, not_pinned, warnings, ...",
    )
    error: str | None = Field(None, description="why a failed fit failed")
