"""What a job poll answers, typed by the job's kind (a generated client gets each result
as its own model, not as an untyped object).

``GET /v1/validations/{id}`` answers one of :data:`ValidationJob` (tagged by ``kind``): a
dose validation's result is a :class:`~api.schemas.ValidationReport`, a schedule job's a
schedule answer (fluid or drug), a drug-dose job's the drug dose.  ``GET /v1/jobs/{id}``
answers any job: these, a fit job or a sweep.  (The Python client keeps the looser
:class:`~api.schemas.ValidationResponse`, whose result is a dict.)
"""

from __future__ import annotations

from typing import Annotated, Any, Literal

from pydantic import Field

from .outputs import Out
from .schemas import (
    BatchScheduleResponse,
    DoseTimeResponse,
    DrugDoseResponse,
    DrugScheduleResponse,
    ProtocolDoseResponse,
    ScheduleResponse,
    ValidationReport,
)

JobStatus = Literal["pending", "running", "done", "failed"]


class _Job(Out):
    id: str = Field(description="the job's id (poll /v1/validations/{id} or /v1/jobs/{id})")
    status: JobStatus = Field(description="its state")
    error: str | None = Field(None, description="when failed: why")


class DoseValidationJob(_Job):
    """A dose's full-solver validation (when done, the truth for the dose), or a stored
    dose job (``dose-<id>``: a dose whose cell needs its runs; when done, the answer)."""

    kind: Literal["dose"] = Field(description="a dose validation or a stored dose job")
    result: (ValidationReport | DoseTimeResponse | ProtocolDoseResponse | DrugDoseResponse
             | dict[str, Any] | None) = Field(
        None, description="when done: a validation's truth for the dose, every run behind it "
                          "and the front model's errors; a dose job's answer")


class ScheduleJob(_Job):
    """A schedule's protocol check and correction; when done, the schedule."""

    kind: Literal["schedule"] = Field(description="a schedule job")
    result: (ScheduleResponse | DrugScheduleResponse | BatchScheduleResponse
             | dict[str, Any] | None) = Field(
        None, description="when done: the schedule, whatever its cell")


class DrugDoseJob(_Job):
    """A drug dose whose drug runs were not cached; when done, the drug dose."""

    kind: Literal["drug-dose"] = Field(description="a drug dose's runs (round three's ids; "
                                                   "new ones are 'dose' jobs)")
    result: DrugDoseResponse | dict[str, Any] | None = Field(
        None, description="when done: the drug dose")


class BatchScheduleJob(_Job):
    """A batch's schedule (issue 26: every size node's runs); when done, the schedule."""

    kind: Literal["batch-schedule"] = Field(description="a batch's schedule (round three's "
                                                        "ids; new ones are 'schedule' jobs)")
    result: BatchScheduleResponse | None = Field(None, description="when done: the schedule")


ValidationJob = Annotated[DoseValidationJob | ScheduleJob | DrugDoseJob | BatchScheduleJob,
                          Field(discriminator="kind")]
