"""The base of every answer model and the uncertainty parts fluid and drug answers share
(a leaf: api.schemas and api.drug_schemas both import it)."""

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
