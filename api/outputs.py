"""The base of every answer model and the uncertainty parts fluid and drug answers share
(a leaf: api.schemas imports it)."""

from __future__ import annotations

from pydantic import BaseModel, ConfigDict, Field


class Out(BaseModel):
    """Base of answers: tolerant of fields a newer server adds."""

    model_config = ConfigDict(extra="allow")


class UncertaintyPart(Out):
    """One part of the truth's uncertainty, in numbers and in words."""

    relative: float | None = Field(None, description="its size relative to the truth's time "
                                                     "(null: not measured or not applicable)")
    text: str = Field(description="what it is and how it was measured, in words")


class UncertaintyOut(Out):
    """The direct truth's uncertainty in three parts (dosing.truth.Uncertainty)."""

    numerical: UncertaintyPart = Field(
        description="grid and time step: the relative gap of the run at n and n / 2 cells")
    interfacial_length_range: UncertaintyPart = Field(
        description="the largest relative change of the time over ell = xi_dry / a_d with "
                    "xi_dry over its plausible range (needs a bead size)")
    model_form: UncertaintyPart = Field(
        description="the delayed-transition front law (the ell = 0 lattice) against this "
                    "local-equilibrium (Maxwell) answer: |ratio - 1|; not in the estimate")
    interfacial_lengths: list[float] | None = Field(
        None, description="the ends of the ell range that were run, dry radii")
    interfacial_length_times: list[float] | None = Field(
        None, description="the truth's time at those ells, dimensionless")
    delayed_transition_time: float | None = Field(
        None, description="the delayed-transition time (finest lattice), dimensionless")
    delayed_transition_ratio: float | None = Field(
        None, description="delayed-transition time / the truth's time")
    delayed_transition_ns: list[int] | None = Field(
        None, description="the lattice sizes N of the delayed-transition runs")
    delayed_transition_times: list[float] | None = Field(
        None, description="the delayed-transition time at each N")
    delayed_transition_spread: float | None = Field(
        None, description="(max - min) / finest of those times: its N-independence")


class FitReport(Out):
    """A fit job's report (solver.fit.result.FitResult.to_dict, plus what the fit adds:
    transition temperatures, tau, the saved name, ...; non-finite numbers as null)."""

    names: list[str] | None = Field(None, description="the fitted parameters' names")
    parameters: dict[str, float | None] | None = Field(None, description="the estimates")
    intervals: dict[str, list[float | None] | None] | None = Field(
        None, description="95% interval of each parameter (null: fixed)")
    stderr: dict[str, float | None] | None = Field(None, description="standard errors")
    covariance: list[list[float | None]] | None = Field(None, description="covariance "
                                                                         "matrix")
    correlation: list[list[float | None]] | None = Field(None, description="correlation "
                                                                           "matrix")
    fixed: dict[str, float | None] | None = Field(None, description="parameters held fixed")
    success: bool | None = Field(None, description="the optimiser converged")
    status: int | None = Field(None, description="the optimiser's status code")
    message: str | None = Field(None, description="the optimiser's message")
    nfev: int | None = Field(None, description="function evaluations")
    n_points: int | None = Field(None, description="data points fitted")
    rms_residual: float | None = Field(None, description="root-mean-square residual")
    chi2_reduced: float | None = Field(None, description="reduced chi^2")
    confidence: float | None = Field(None, description="the intervals' confidence (0.95)")
    warnings: list[str] = Field(default_factory=list, description="what the fit could not "
                                                                  "pin, in words")
    saved: str | None = Field(None, description="the stored gel's name, with save")
