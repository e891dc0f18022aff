"""Request and job models of the design routes (``api.routers.design``, issue 39)."""

from __future__ import annotations

from typing import Annotated, Any, Literal

from pydantic import BaseModel, ConfigDict, Field

from api.schemas import ConstantsIn, GelSpec, RequestModel
from solver.limits import T_MAX, T_MIN

Temperature = Annotated[float, Field(ge=T_MIN, le=T_MAX)]


class HeatingDesignRequest(RequestModel):
    """The heating (jump temperature, ramp rate or bath set point) at which a dose is out at
    ``at_seconds`` (dosing.design.heating)."""

    model_config = ConfigDict(extra="forbid", strict=True, allow_inf_nan=False,
                              json_schema_extra={"examples": [
                                  {"gel": "ANB", "t_start": 302.0, "fraction": 0.5,
                                   "at_seconds": 60.0, "dry_radius_um": 50.0}]})

    gel: GelSpec = "ANB"
    t_start: Temperature = Field(description="start temperature, K")
    at_seconds: float = Field(gt=0, le=1e7, description="when the dose must be out, s")
    fraction: float | None = Field(None, gt=0, lt=1, description="dose, fraction of the "
                                   "stored fluid")
    dose_ug: float | None = Field(None, gt=0, description="dose as a drug mass, ug")
    concentration_ug_per_ul: float | None = Field(None, gt=0, description="the drug's "
                                                  "concentration in the fluid, ug/uL")
    dry_radius_um: float = Field(gt=0, le=1e5, description="dry bead radius, um")
    constants: ConstantsIn | None = Field(None, description="timescale constants (default: "
                                          "Omega_p = Omega Omega_f; paper: the paper's)")
    size_cv: float | None = Field(None, gt=0, le=1.0, description="a batch: lognormal CV")
    mode: Literal["jump", "ramp", "bath"] = Field("jump", description="what is found: the "
                                                  "jump temperature, a ramp's rate or a "
                                                  "bath's set point")
    t_end: Temperature | None = Field(None, description="a ramp's final temperature, K")
    time_constant_s: float = Field(30.0, gt=0, le=1e6, description="a bath's time "
                                   "constant, s")
    bounds: list[float] | None = Field(None, min_length=2, max_length=2, description="the "
                                       "search range (K; K/min for a ramp)")
    validate_full: bool = Field(False, alias="validate", description="polish on the truth "
                                "(full-solver validations)")
    confidence: float | None = Field(None, gt=0, lt=1, description="also the heating "
                                     "meeting the target with this probability")
    full: bool = Field(True, description="search where only the full solver answers")


class ExperimentDesignRequest(RequestModel):
    """The shrinking-curve experiment that best pins an answer (dosing.design.experiment)."""

    model_config = ConfigDict(extra="forbid", strict=True, allow_inf_nan=False,
                              json_schema_extra={"examples": [
                                  {"gel": "ANB", "t_start": 302.0, "t_end": 308.0,
                                   "fraction": 0.8, "dry_radius_um": 50.0,
                                   "size_noise": 0.005, "jumps": [308.0]}]})

    gel: GelSpec = "ANB"
    t_start: Temperature = Field(description="start temperature, K")
    t_end: Temperature = Field(description="the answer's jump temperature, K")
    fraction: float = Field(gt=0, lt=1, description="the answer's dose")
    dry_radius_um: float = Field(gt=0, le=1e5, description="the answer's dry bead radius, um")
    constants: ConstantsIn | None = Field(None, description="timescale constants (default: "
                                          "Omega_p = Omega Omega_f; paper: the paper's)")
    size_noise: float = Field(0.01, ge=1e-5, le=0.3, description="relative radius noise")
    max_duration_s: float = Field(3600.0, ge=1.0, le=1e6, description="longest measurement")
    n_points: int = Field(20, ge=4, le=200, description="radii measured")
    min_interval_s: float = Field(1.0, ge=0.0, le=1e5, description="shortest time between "
                                  "samples, s")
    sizes_um: list[Annotated[float, Field(gt=0, le=1e5)]] | None = Field(
        None, max_length=20, description="the dry radii the lab can make, um")
    jumps: list[Temperature] | None = Field(None, max_length=12, description="candidate "
                                            "jump temperatures of the experiment, K")
    criterion: Literal["d-optimal", "interval"] = Field(
        "d-optimal", description="sampling times: robust D-optimal for tau, or the widest "
        "predicted dose-time interval minimised")
    simulate: int = Field(0, ge=0, le=500, description="also check the Fisher interval "
                          "with this many simulated fits")


class DesignJobResponse(BaseModel):
    """A design job: pending, running, done (``result``) or failed (``error``)."""

    model_config = ConfigDict(extra="allow")
    id: str = Field(description="the job's id: its kind and the request's hash")
    kind: Literal["design-heating", "design-experiment"] = Field(description="the kind")
    status: str = Field(description="pending, running, done or failed")
    status_url: str | None = Field(None, description="where to poll it")
    result: dict[str, Any] | None = Field(None, description="the design (dosing.design: "
                                          "to_dict), when done")
    error: str | None = Field(None, description="why it failed, when failed")
