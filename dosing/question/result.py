"""One answer per question: :class:`DoseResult` and :class:`ScheduleResult`.

Whatever the cell, the headline answers the question asked: a dose's ``time`` / ``seconds`` is
the population's (a batch's own time: issue 35), a schedule's ``actuation_times`` / ``_seconds``
the corrected ones when found, else the hold reading (``reading`` says).  The cell's ``answer``
and sections are kept whole; ``to_dict()`` is the JSON every way in returns (docs/results.md)."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from solver.presenters import presenter


@dataclass
class DoseResult:
    """A dose's answer: the headline (``time`` in the reference bead's tau, ``seconds``),
    the cell that answered, the cell's own answer (None for a drug batch, whose answer is
    its batch section) and, for a batch, the batch section (its own time; the answer's
    fields are then its number-weighted mean bead's)."""

    cell: str
    answer: Any
    batch: Any = None
    validation_id: str | None = None
    request: dict[str, Any] | None = None
    tags: dict[str, Any] = field(default_factory=dict)  # the payload's flags ({"drug": True})
    envelope: Any = None  # dosing.question.envelope.Envelope: what cannot be ruled out

    @property
    def time(self) -> float:
        """The dose time (dimensionless, tau of the reference bead): the population's."""
        return (self.batch or self.answer).time

    @property
    def seconds(self) -> float | None:
        """The dose time in seconds (with a bead size): the population's."""
        return (self.batch or self.answer).seconds

    @property
    def model(self) -> str:
        """The model that answered."""
        return (self.batch or self.answer).model

    @property
    def headline(self) -> str:
        """The answer in one line."""
        secs = "" if self.seconds is None else f" = {self.seconds:.4g} s"
        who = "the batch" if self.batch is not None else "the bead"
        return (f"{self.cell}: {who} releases the dose at t = {self.time:.4g} tau{secs} "
                f"({self.model} model)")

    def __getattr__(self, name: str) -> Any:
        # the cell's answer's own fields (error_estimate, final_radius, uncertainty, ...)
        if name.startswith("__") or name in ("answer", "batch"):
            raise AttributeError(name)
        return getattr(self.answer if self.answer is not None else self.batch, name)

    def to_dataframe(self) -> Any:
        """One row led by the envelope (pandas; ``dosing.present.tables.result_frame``)."""
        return presenter("result_frame")(self)

    def _repr_html_(self) -> str:
        return presenter("result_html")(self)

    def to_dict(self) -> dict[str, Any]:
        """The cell's answer with the headline over it and the sections beside it."""
        # a drug batch's answer is its batch section, also at the top
        d = (self.answer or self.batch).to_dict()
        if self.batch is not None:
            if self.answer is not None:  # the bead's fields are its mean bead's
                d["reference_bead"] = {"time": d.get("time"), "seconds": d.get("seconds"),
                                       "model": d.get("model"),
                                       "dry_radius_um": self.batch.reference_dry_radius_um}
            d["batch"] = self.batch.to_dict()
        d.update(self.tags)
        d.update(time=self.time, seconds=self.seconds, model=self.model, question="dose",
                 cell=self.cell, headline=self.headline)
        if self.validation_id is not None:
            d["validation_id"] = self.validation_id
        if self.request is not None:
            d["request"] = self.request
        _envelope_fields(d, self.envelope, single=True)
        return d


@dataclass
class ScheduleResult:
    """A schedule's answer: the headline ``actuation_times`` (tau of the reference bead)
    and ``actuation_seconds``, the corrected times when the schedule was corrected
    (``reading`` 'corrected'), else the hold reading ('hold'); the cell's own answer with
    every reading."""

    cell: str
    answer: Any
    request: dict[str, Any] | None = None
    tags: dict[str, Any] = field(default_factory=dict)
    envelope: Any = None  # dosing.question.envelope.Envelope: what cannot be ruled out

    @property
    def reading(self) -> str:
        """Which reading the headline is: 'corrected' or 'hold'."""
        corrected = getattr(self.answer, "corrected", None)
        return "corrected" if corrected and corrected.get("actuation_times") else "hold"

    @property
    def actuation_times(self) -> list[float]:
        """Each heating's duration (tau of the reference bead)."""
        if self.reading == "corrected":
            return [float(x) for x in self.answer.corrected["actuation_times"]]
        return [float(row.actuation_time) for row in self.answer.hold]

    @property
    def actuation_seconds(self) -> list[float] | None:
        """Each heating's duration in seconds (with a bead size)."""
        if self.reading == "corrected":
            secs = self.answer.corrected.get("actuation_seconds")
            return None if secs is None else [float(x) for x in secs]
        secs = [getattr(row, "actuation_seconds", None) for row in self.answer.hold]
        return None if any(s is None for s in secs) else [float(s) for s in secs]

    @property
    def model(self) -> str:
        """The model that answered."""
        return self.answer.model

    @property
    def headline(self) -> str:
        """The answer in one line."""
        secs = self.actuation_seconds
        times = ", ".join(f"{t:.4g}" for t in (secs or self.actuation_times))
        got, asked = len(self.actuation_times), len(self.answer.doses)
        short = "" if got >= asked else (
            f"; dose {got + 1} of {asked} is not reached by any heating: see the warnings")
        return (f"{self.cell}: heat for {times} {'s' if secs else 'tau'} "
                f"({self.reading} times){short}")

    def __getattr__(self, name: str) -> Any:
        if name.startswith("__") or name == "answer":
            raise AttributeError(name)
        return getattr(self.answer, name)

    def to_dataframe(self) -> Any:
        """The events, one row per step (pandas; ``dosing.present.tables``)."""
        return presenter("schedule_result_frame")(self)

    def to_xarray(self, request: Any = None) -> Any:
        """The events as an xarray Dataset with provenance (what ``--out`` writes)."""
        return presenter("schedule_result_dataset")(self, request)

    def _repr_html_(self) -> str:
        return presenter("schedule_result_html")(self)

    def to_dict(self) -> dict[str, Any]:
        """The cell's answer with the headline over it."""
        d = self.answer.to_dict()
        d.update(self.tags)
        d.update(question="schedule", cell=self.cell, reading=self.reading,
                 actuation_times=self.actuation_times,
                 actuation_seconds=self.actuation_seconds, headline=self.headline)
        if self.request is not None:
            d["request"] = self.request
        _envelope_fields(d, self.envelope, single=False)
        return d


def _envelope_fields(d: dict[str, Any], env: Any, single: bool) -> None:
    """The envelope's JSON beside the point: ``envelope_seconds`` (one [lo, hi] for a dose,
    one per heating for a schedule), ``envelope_time``, ``dominant_uncertainty``, the
    ``envelope`` section, and ``uncertainty`` as the typed parts by name (the truth's
    three parts of a validated answer kept beside them)."""
    if env is None:
        return
    e = env.to_dict()
    secs, times = e["seconds"], e["time"]
    d["envelope_seconds"] = (secs[0] if single else secs) if secs is not None else None
    d["envelope_time"] = times[0] if single else times
    d["dominant_uncertainty"] = e["dominant"]
    d["envelope"] = e
    old = d.get("uncertainty")
    d["uncertainty"] = {**(old if isinstance(old, dict) else {}), **e["parts"]}
