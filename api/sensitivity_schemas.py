"""Pydantic models of ``POST /v1/sensitivity`` (dosing.studies.sensitivity): strict and finite."""

from __future__ import annotations

from typing import Any, Literal

from pydantic import Field

from dosing.units import PhysicalConstants

from .outputs import Out
from .schemas import GelSpec, RequestModel

VaryName = Literal["dry_radius_um", "t_start", "t_end", "dose_fraction", "viscosity_pa_s",
                   "polymer_volume_m3", "permeability_m2", "omega", "a0", "b0", "a1", "b1"]
_BASE = PhysicalConstants()  # the timescale's defaults, written once (dosing.units)
MAX_TRAJECTORIES = 400  # front trajectories one request may need (~50 ms each)


class VaryIn(RequestModel):
    """One varied input: a request field name and its range."""

    name: VaryName = Field(description="the input (a request field or gel parameter)")
    low: float = Field(description="lower bound, in the field's unit")
    high: float = Field(description="upper bound, in the field's unit")
    log: bool = Field(False, description="log-uniform (uniform in log10) instead of uniform")


class SensitivityRequest(RequestModel):
    """Global sensitivity of the dose time in seconds over the ``vary`` ranges."""

    gel: GelSpec = "ANB"
    t_start: float | str = Field(302.0, description="start temperature: K, or a string with "
                                                    "a unit ('29 degC')")
    t_end: float | str = Field(308.0, description="end temperature: K, or '35 degC'")
    dose_fraction: float = Field(0.8, gt=0.0, lt=1.0, description="base dose, 0-1")
    dry_radius_um: float | str = Field(50.0, description="base dry radius: um, or '50 um'")
    viscosity_pa_s: float = Field(_BASE.viscosity_pa_s, gt=0.0, le=10.0,
                                  description="base eta, Pa s")
    permeability_m2: float = Field(_BASE.permeability_m2, gt=0.0, le=1e-10,
                                   description="base k0, m^2")
    polymer_volume_m3: float | None = Field(
        _BASE.polymer_volume_m3, gt=0.0, le=1e-20,
        description="base Omega_p, m^3 (default Omega Omega_f: consistent with the gel's Omega, "
                    "so it follows a varied omega)")
    vary: list[VaryIn] = Field(min_length=1, max_length=12, description="the varied inputs")
    method: Literal["sobol", "morris"] = Field("sobol", description="Sobol or Morris")
    samples: int = Field(512, ge=4, le=4096, description="Sobol base samples N, or Morris "
                                                          "trajectories")
    seed: int = Field(0, ge=0, le=2**31 - 1, description="sampling seed")


class SensitivityResponse(Out):
    """Indices keyed by input name: S1, S1_conf, ST, ST_conf (Sobol) or mu, mu_star,
    mu_star_conf, sigma (Morris), with the output's summary."""

    method: str = Field(description="'sobol' (S1 and ST with confidence intervals) or "
                                    "'morris' (elementary effects: screening)")
    output: str = Field(description="what the indices are of: the dose time in seconds")
    names: list[str] = Field(description="the varied inputs, request field names")
    indices: dict[str, dict[str, float]] = Field(
        description="per input: S1, S1_conf, ST, ST_conf (Sobol; dimensionless shares of "
                    "the variance) or mu, mu_star, mu_star_conf, sigma (Morris; seconds)")
    vary: list[dict[str, Any]] = Field(description="each input's range and scale as given")
    base: dict[str, Any] = Field(description="the request the inputs vary around")
    samples: int = Field(description="base samples (Sobol N, or Morris trajectories)")
    evaluations: int = Field(description="front-model answers computed")
    output_summary: dict[str, float] = Field(
        description="the dose time's mean, standard deviation, 5th, 50th and 95th "
                    "percentiles over the samples, seconds")
    seconds: float = Field(description="wall time of the analysis, s")
    model: str = Field(description="the model that answered each sample (front-sharp)")
    confidence: float = Field(description="confidence level of the intervals (0.95)")
    notes: list[str] = Field(description="what the indices mean and where they hold, in "
                                         "words")
