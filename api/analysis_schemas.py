"""Request and answer models of the release-analysis routes (``api.routers.analysis``,
issue 38): the empirical models fitted to a profile, two profiles compared (f1/f2)."""

from __future__ import annotations

from typing import Any, Literal

from pydantic import Field

from api.fit_schemas import FitJobResponse
from api.outputs import Out
from api.schemas import RequestModel

MAX_TIMES = 200  # a dissolution profile has a few to a few dozen times
MAX_UNITS = 48  # dosage units (vessels) per profile
MAX_CSV_CHARS = 200_000  # a profile's CSV is a few kB
ModelName = Literal["zero_order", "first_order", "higuchi", "korsmeyer_peppas",
                    "hixson_crowell", "weibull", "peppas_sahlin"]  # dosing.analysis.MODELS


class ProfileIn(RequestModel):
    """One release profile: its times, and either one ``released`` profile or ``units``
    (one profile per dosage unit, each at every time)."""

    csv: str | None = Field(None, max_length=MAX_CSV_CHARS, description="the profile as a "
                            "lab's CSV text (time with its unit, one release column per unit), "
                            "read as the command line reads a file; instead of time and "
                            "released/units (released_unit and time_unit then come from the "
                            "header)")
    time: list[float] | None = Field(None, max_length=MAX_TIMES, description="times from the "
                                     "start, in time_unit, increasing")
    time_unit: Literal["s", "min", "h", "d"] = Field("s", description="the times' unit (the "
                                                     "empirical parameters are stated in it)")
    released: list[float] | None = Field(None, max_length=MAX_TIMES,
                                         description="cumulative release (one profile)")
    units: list[list[float]] | None = Field(
        None, max_length=MAX_UNITS, description="cumulative release of each dosage unit "
        "(replicates: averaged, their spread used)")
    released_unit: Literal["fraction", "percent", "ug"] = Field(
        "fraction", description="'fraction' of the load, 'percent', or 'ug' with loaded_ug")
    loaded_ug: float | None = Field(None, gt=0, description="the load, for released_unit ug")

    def profile(self, label: str = "") -> Any:
        """The checked ``dosing.analysis.Profile`` (a ParameterError names the field)."""
        from dosing.analysis import from_arrays, read_profile
        from solver.errors import ParameterError

        pre = f"{label}." if label else ""
        if self.csv is not None:
            if self.time is not None or self.released is not None or self.units is not None:
                raise ParameterError(f"{pre}csv", "csv and arrays", "either csv, or time with "
                                     "released or units")
            text = self.csv if self.csv.endswith("\n") else self.csv + "\n"  # text, no path
            return read_profile(text, self.loaded_ug, label=f"{pre}csv")
        if self.time is None:
            raise ParameterError(f"{pre}time", None, "times (with released or units), or csv")
        return from_arrays(self.time, self.released, self.units, time_unit=self.time_unit,
                           released_unit=self.released_unit, loaded_ug=self.loaded_ug,
                           label=label)


class EmpiricalFitRequest(ProfileIn):
    """A profile to fit the empirical release models to (dosing.analysis.empirical)."""

    model_config = {**ProfileIn.model_config, "json_schema_extra": {"examples": [{
        "time": [5, 10, 15, 20, 30, 45, 60, 90, 120, 150, 180, 240], "time_unit": "min",
        "released": [21.6, 33.5, 41.3, 47.9, 57.6, 67.9, 75.0, 84.6, 90.1, 93.7, 96.0, 98.3],
        "released_unit": "percent"}]}}

    models: list[ModelName] | None = Field(None, min_length=1, max_length=7,
                                           description="the models to fit (default all)")
    lag: bool = Field(False, description="fit a lag time where the model has one")
    kp_window: float = Field(60.0, gt=0, le=105, description="percent released that "
                             "Korsmeyer-Peppas and Peppas-Sahlin are fitted up to (60: the "
                             "literature's; above it the fit is flagged)")


class CompareRequest(RequestModel):
    """Two profiles on the same times: f1/f2 with the FDA rules, Shah's bootstrap."""

    model_config = {**RequestModel.model_config, "json_schema_extra": {"examples": [{
        "reference": {"time": [15, 30, 45, 60], "time_unit": "min",
                      "released": [35, 60, 79, 95], "released_unit": "percent"},
        "test": {"time": [15, 30, 45, 60], "time_unit": "min",
                 "released": [40, 67, 87, 98], "released_unit": "percent"}}]}}

    reference: ProfileIn = Field(description="the reference profile")
    test: ProfileIn = Field(description="the test profile, on the reference's times")
    n_boot: int = Field(1000, ge=1000, le=10_000, description="bootstrap draws")
    seed: int = Field(0, ge=0, le=2**32 - 1, description="the bootstrap's seed")
    confidence: float = Field(0.90, ge=0.5, lt=1.0, description="the bootstrap interval's "
                                                                "level (0.90: Shah's)")


class CompareResponse(Out):
    """f1/f2 of two profiles (dosing.analysis.similarity.Comparison)."""

    f1: float = Field(description="difference factor f1 (0-15: the same)")
    f2: float = Field(description="similarity factor f2 (50-100: similar)")
    points_used: list[int] = Field(description="indices of the times f1 and f2 use")
    times_used: list[float] = Field(description="those times, in time_unit")
    time_unit: str = Field(description="the reference's time unit")
    reference_mean: list[float] = Field(description="the reference's mean, % released")
    test_mean: list[float] = Field(description="the test's mean, % released")
    conditions: dict[str, dict[str, Any]] = Field(description="the guidance's conditions: "
                                                  "rule, met, found")
    conditions_met: bool = Field(description="whether every condition is met")
    outcome: str = Field(description="f2's outcome in the guidance's words")
    f1_outcome: str = Field(description="f1's")
    bootstrap: dict[str, Any] | None = Field(
        None, description="Shah et al. 1998: draws, seed, BCa and percentile intervals, "
                          "outcome (null: neither profile has replicate units)")
    reference: dict[str, Any] = Field(description="the reference: units, mean, SD, CV")
    test: dict[str, Any] = Field(description="the test: units, mean, SD, CV")
    notes: list[str] = Field(description="the points used, in words")


class EmpiricalFitReport(Out):
    """Every empirical model's fit (dosing.analysis.empirical.EmpiricalResult.report)."""

    best: str | None = Field(description="the lowest AIC among the models on the whole curve")
    ranked_by_aic: list[str] = Field(description="those models, best first")
    models: dict[str, dict[str, Any]] = Field(
        description="per model: parameters with units, stderr, 95 % intervals, r2_adjusted, "
                    "aic, msc, residuals, the curve; Korsmeyer-Peppas's interpretation")
    errors: dict[str, str] = Field(description="models that could not be fitted, and why")
    time_unit: str = Field(description="the parameters' time unit")
    weighted: bool = Field(description="weighted by 1/SD of the units")


class EmpiricalFitJobResponse(FitJobResponse):
    """An empirical-fit job: ``result`` is the report when done."""

    kind: Literal["empirical"] = Field(description="which fit")
    result: EmpiricalFitReport | None = Field(None, description="the models' report")
