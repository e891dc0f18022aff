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


class EnvelopePart(UncertaintyPart):
    """One typed part of an answer's uncertainty (dosing.question.envelope.Part): the
    time's factors at its ends, in words, and how to pin it."""

    name: str | None = Field(None, description="numerical | reduction | interfacial_length | "
                                               "front_law | timescale | mesh | quadrature | "
                                               "parameters")
    low: float | None = Field(None, description="the time's factor at the part's low end")
    high: float | None = Field(None, description="the time's factor at its high end")
    factor: float | None = Field(None, description="high / low")
    counted: bool | None = Field(None, description="in the envelope (false: listed only)")
    measured: bool | None = Field(None, description="false: a stated bracket, not a run")
    how_to_pin: str | None = Field(None, description="the measurement or fit that pins it")
    ratio: float | None = Field(None, description="front_law: delayed / Maxwell time")


class DominantOut(Out):
    """The widest part of the envelope and how to pin it."""

    name: str = Field(description="the part's name")
    factor: float = Field(description="its width, high / low")
    how_to_pin: str = Field(description="the measurement or fit that pins it")
    text: str = Field("", description="the part in words")


class EnvelopeOut(Out):
    """What the user cannot rule out: the point times the counted parts' factors."""

    seconds: list[list[float]] | None = Field(
        None, description="[lo, hi] s per answer time (null without a bead size)")
    time: list[list[float]] = Field(description="[lo, hi] tau per answer time (the "
                                                "timescale part aside)")
    low: float = Field(description="the product of the counted parts' low factors")
    high: float = Field(description="the product of their high factors")
    parts: dict[str, EnvelopePart] = Field(description="every part, by name")
    dominant: DominantOut | None = Field(None, description="the widest counted part")


class EnvelopeFields(Out):
    """The envelope's fields on every dose and schedule answer (issue 36)."""

    envelope_seconds: list[float] | list[list[float]] | None = Field(
        None, description="[lo, hi] s (a schedule: one per heating): the bracket the user "
                          "cannot rule out with what they gave; the point stays as seconds")
    envelope_time: list[float] | list[list[float]] | None = Field(
        None, description="the same in tau (without the timescale part)")
    dominant_uncertainty: DominantOut | None = Field(
        None, description="the largest part and the measurement that pins it")
    envelope: EnvelopeOut | None = Field(None, description="the ranges and every part")


class UncertaintyOut(Out):
    """An answer's uncertainty by part: the typed parts of its envelope (reduction,
    numerical, interfacial_length, front_law, timescale, mesh, quadrature, parameters) and,
    for a validated direct answer, the truth's three parts (dosing.truth.Uncertainty)."""

    numerical: UncertaintyPart | None = Field(
        None, description="grid and time step: the relative gap of the run at n and n / 2 "
                          "cells")
    interfacial_length_range: UncertaintyPart | None = Field(
        None, description="the largest relative change of the time over ell = xi_dry / a_d "
                          "with xi_dry over its plausible range (needs a bead size)")
    model_form: UncertaintyPart | None = Field(
        None, description="validated: the delayed-transition front law (the ell = 0 "
                          "lattice) against this local-equilibrium (Maxwell) answer")
    reduction: EnvelopePart | None = Field(None, description="a reduced model's gap to its "
                                                             "truth")
    interfacial_length: EnvelopePart | None = Field(None, description="the mesh length's part")
    front_law: EnvelopePart | None = Field(None, description="delayed vs Maxwell front law")
    timescale: EnvelopePart | None = Field(None, description="the timescale constants")
    mesh: EnvelopePart | None = Field(None, description="a sieved drug's mesh")
    quadrature: EnvelopePart | None = Field(None, description="a batch's quadrature")
    parameters: EnvelopePart | None = Field(None, description="a fitted gel's parameters")
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
