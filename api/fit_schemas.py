"""Request and answer models of the fit routes (``api.routers.fit``)."""

from __future__ import annotations

from typing import Annotated, Any, Literal

from pydantic import BaseModel, ConfigDict, Field, field_validator, model_validator

from api.outputs import FitReport
from api.schemas import GelSpec, RequestModel
from dosing.fits.gel_store import check_name
from solver.limits import T_MAX, T_MIN, TRUTH_N_RANGE

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
    polymer_volume_m3: float | None = Field(
        None, gt=0, le=1.0e-20, description="Omega_p in m^3, for k0 (default Omega Omega_f, "
                                            "consistent with the gel's Omega)")
    model: Literal["auto", "front", "front-sharp", "full"] = Field(
        "auto", description="model of the curve: the front models (milliseconds), the full "
        "solver (one run per beta), or auto (the planner's choice)")
    fit_beta: bool = Field(False, description="also fit beta of k = phi/(1-phi)^beta "
                           "(model 'full' only)")
    beta: float | None = Field(None, gt=0, lt=10, description="permeability exponent, "
                               "0 < beta < 10: fixed, or the start of its fit")
    interfacial_length: float | None = Field(None, ge=0, description="full solver's ell")
    size_rel_sigma: float = Field(0.01, gt=0, description="relative size noise")
    compare_laws: bool = Field(True, description="also fit under both front laws (Maxwell "
                                                 "and delayed, about a second) and compare "
                                                 "them by AIC (issue 36: on by default)")

    @model_validator(mode="after")
    def _one_bead_size(self) -> KineticsFitRequest:
        if self.dry_radius_um is not None and self.swollen_radius_um is not None:
            raise ValueError("give at most one bead size: dry_radius_um or swollen_radius_um")
        return self


class ReleaseFitRequest(RequestModel):
    """A cumulative release curve to fit the drug's free diffusivity D0 to: isothermal at
    ``t_start`` or under a heating ``protocol`` from it (dosing.fits.release)."""

    model_config = ConfigDict(
        extra="forbid",
        json_schema_extra={
            "examples": [
                {
                    "time_s": [30, 60, 120, 240, 480, 960],
                    "released": [0.21, 0.30, 0.42, 0.57, 0.74, 0.90],
                    "gel": "ANB",
                    "t_start": 300.0,
                    "dry_radius_um": 50.0,
                },
                {
                    "time_s": [30, 60, 120, 240, 360, 480, 600],
                    "released": [0.25, 0.35, 0.52, 0.75, 0.88, 0.94, 0.97],
                    "gel": "ANB",
                    "t_start": 300.0,
                    "protocol": ["Heat to 308 K at 5 K/min"],
                    "dry_radius_um": 50.0,
                    "solver_n": 100,
                    "solver_rtol": 1e-4,
                },
            ]
        },
    )

    time_s: list[float] = Field(max_length=MAX_POINTS, description="times from the start, s")
    released: list[float] = Field(max_length=MAX_POINTS,
                                  description="cumulative release, in released_unit")
    released_unit: Literal["fraction", "percent", "ug"] = Field(
        "fraction", description="'fraction' of the load, 'percent', or 'ug' (with loaded_ug)")
    loaded_ug: float | None = Field(None, gt=0, description="the load, for released_unit ug")
    gel: GelSpec = "ANB"
    t_start: Temperature = Field(description="release temperature (or the protocol's start), "
                                             "K, 273.15-373.15")
    t_end: Temperature | None = Field(None, description="equal to t_start (isothermal); or "
                                                        "give protocol")
    protocol: list[str] | None = Field(
        None, min_length=1, max_length=100, description="the heating the release ran under, "
        "from t_start ('Heat to 308 K at 5 K/min', 'Hold at 308 K for 10 min', 'Bath at "
        "308 K'; docs/heating.md): one full-solver run of its mechanics, one solute run per "
        "trial D0")
    dry_radius_um: float = Field(gt=0, description="dry bead radius, um")
    hindrance: Literal["none", "free-volume", "ogston"] = Field(
        "none", description="hindrance of the drug by the gel")
    mesh_size_nm: float | None = Field(None, gt=0, description="swollen mesh size, nm "
                                                               "(free-volume sieve)")
    fiber_radius_nm: float | None = Field(None, gt=0, description="fibre radius, nm (Ogston)")
    solver_n: int | None = Field(None, ge=TRUTH_N_RANGE[0], le=TRUTH_N_RANGE[1],
                                 description="full solver's cells under a protocol (default "
                                             "the truth's)")
    solver_rtol: float | None = Field(None, gt=0, le=1e-2, description="full solver's rtol "
                                      "under a protocol (default the truth's)")


class ReleaseBand(BaseModel):
    """The fitted curve and its 95% band (D0 at its interval's ends)."""

    time_s: list[float] = Field(description="times, s")
    released: list[float] = Field(description="the fitted released fraction")
    lower: list[float] = Field(description="released fraction at one end of D0's interval")
    upper: list[float] = Field(description="released fraction at its other end")


class ReleaseFitReport(BaseModel):
    """A release fit's report (dosing.fits.release.fit_release)."""

    model_config = ConfigDict(extra="allow")

    names: list[str] = Field(description="the fitted parameters")
    parameters: dict[str, float] = Field(description="drug_diffusivity_cm2_s: the free D0")
    intervals: dict[str, list[float]] = Field(description="95% intervals")
    stderr: dict[str, float] = Field(description="standard errors")
    interval_kind: str = Field(description="how the intervals are made")
    f2: float = Field(description="FDA similarity factor (1997 rules) of the prediction and "
                                  "the data as two profiles: a similarity, not a goodness "
                                  "of fit (50-100: similar)")
    f2_meaning: str = Field(description="f2 in words")
    similarity: dict[str, Any] | None = Field(
        None, description="f1, f2, the points used, the FDA conditions and the outcome in the "
                          "guidance's words (dosing.analysis.similarity)")
    residuals: list[float] | None = Field(None, description="data - fit at the measured "
                                                            "times, fraction of the load")
    rms_residual: float = Field(description="rms misfit, fraction of the load")
    chi2_reduced: float = Field(description="residual variance per degree of freedom")
    n_points: int = Field(description="points fitted")
    success: bool = Field(description="whether the least-squares fit converged")
    effective_diffusivity_cm2_s: float = Field(description="D0 H(phi0) in the swollen start")
    hindrance_factor: float = Field(description="H(phi0) of the hindrance law")
    hindrance: str = Field(description="the hindrance law")
    swollen_radius_um: float = Field(description="the bead's radius at t_start, um")
    porosity: float = Field(description="phi0 at t_start")
    drug_diffusivity_temperature_K: float = Field(description="where D0 is D0 in water")
    model: str = Field(description="the release model, its settings and scale")
    protocol: dict[str, Any] | None = Field(None, description="the protocol, when given")
    squeezed_released: list[float] | None = Field(
        None, description="under a protocol: the release of the fluid's motion alone")
    cost: dict[str, Any] | None = Field(None, description="under a protocol: CPU seconds of "
                                        "the mechanics run and of the solute runs")
    fitted: list[float] = Field(description="the fit at the measured times")
    time_s: list[float] = Field(description="the measured times, s")
    released: list[float] = Field(description="the measured released fraction")
    band: ReleaseBand = Field(description="the fitted curve and its 95% band")
    warnings: list[str] = Field(description="what to watch")
    not_pinned: list[str] = Field(description="what the data do not determine")
    confidence: float = Field(description="the intervals' level")


class FitJobResponse(BaseModel):
    """A fit job: poll ``status_url`` until ``status`` is done (``result``) or failed."""

    model_config = ConfigDict(extra="allow")

    id: str = Field(description="the job id")
    kind: Literal["swelling", "kinetics", "release"] = Field(description="which fit")
    status: Literal["pending", "running", "done", "failed"] = Field(description="job state")
    status_url: str = Field(description="where to poll")
    result: FitReport | None = Field(
        None,
        description="the fit report: parameters, intervals (95%), chi2, aic, bic, "
        "rms_orthogonal_K, rms_temperature_residual_K, not_pinned, warnings, ...",
    )
    error: str | None = Field(None, description="why a failed fit failed")


class ReleaseFitJobResponse(FitJobResponse):
    """A release-fit job: ``result`` is the typed report when done."""

    kind: Literal["release"] = Field(description="which fit")
    result: ReleaseFitReport | None = Field(None, description="the release fit's report")
