"""Multi-dose schedules (sec. Application, fig. multidose_schematic).

Three readings of one schedule of doses d_1..d_n with rests r_1..r_{n-1}:
1. the hold assumption (the paper's reading): one continuous heating, doses read off
   cumulatively, t_k = t(d_1 + ... + d_k), actuation k lasts t_k - t_{k-1};
2. the protocol check: those actuation times simulated with the full solver as heat at
   T_end / rest at T_start steps; the gel takes up fresh fluid while it rests, so each
   heating starts from a larger radius than the hold assumption supposes;
3. the corrected schedule: actuation times found by shooting on the full solver so that
   every dose is met within the tolerance (1 % by default).

A schedule needs of the planner only what :class:`SchedulePlanner` names, so
``dosing.planner`` imports this module and not the other way round
(``Planner.schedule`` is :func:`plan_schedule_with`).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import asdict, dataclass, field
from itertools import accumulate
from typing import Any, Protocol

from solver.full import FullResult
from solver.presenters import presenter

from ..answers import DoseAnswer, HoldRow
from ..heating.cycles import ProtocolHeatings
from ..request import DoseRequest, ScheduleRequest
from ..runs.scenario import Scenario, Step
from ..truth import truth_text
from ..units import SYMBOLIC_FORMULA, stored_volume, timescale, volume_to_ul
from . import shooting as protocol
from .events import schedule_events


class SchedulePlanner(Protocol):
    """What a schedule needs of the planner (``dosing.planner.Planner`` is one): single-dose
    answers, blocking or only when cached, and full-solver runs of a protocol."""

    def dose(self, req: DoseRequest, validate: bool = False) -> DoseAnswer: ...

    def answer_now(self, req: DoseRequest) -> DoseAnswer | None: ...

    def trajectory(self, sc: Scenario, need_radius: float | None = None,
                   need_time: float = 0.0) -> FullResult: ...


class ScheduleViews:
    """What every schedule answer (fluid or drug, one bead or a batch) shows of itself: its
    events as a table and in a notebook (``dosing.present.tables``)."""

    def to_dataframe(self) -> Any:
        """The events, one row per step (heat, rest, a drug's wait; pandas)."""
        return presenter("schedule_frame")(self)

    def _repr_html_(self) -> str:
        return presenter("schedule_html")(self)


@dataclass
class ScheduleAnswer(ScheduleViews):
    """A schedule's actuation times under each reading, with delivered volumes."""

    model: str
    doses: list[float]
    rests: list[float]
    hold: list[HoldRow]
    protocol_check: dict[str, Any] | None
    corrected: dict[str, Any] | None
    start_radius: float
    stored_volume: float
    stored_volume_ul: float | None
    timescale_seconds: float | None
    timescale_formula: str
    scenario_key: str
    note: str
    truth: str = ""  # the protocol runs' model, ell and bead size, in words
    interfacial_length: float = 0.0
    method: str = "direct"
    t_start: float | None = None  # K: the rests' temperature
    t_end: float | None = None  # K: the actuation temperature
    # the schedule as a lab runs it, one row per step (dosing.question.events)
    events: list[dict[str, Any]] = field(default_factory=list)

    def to_dict(self) -> dict[str, Any]:
        """Plain-data form (JSON-ready)."""
        return asdict(self)

    def to_xarray(self, request: Any = None) -> Any:
        """The event table as an xarray Dataset (:func:`dosing.present.export.schedule_dataset`)."""
        return presenter("schedule_dataset")(self, request)


def hold_rows(req: ScheduleRequest, answers: Sequence[DoseAnswer]) -> tuple[str, list[HoldRow]]:
    """(models, rows) under the hold assumption from the single-dose answers for the
    cumulative doses d_1 + ... + d_k (in order)."""
    rows, prev = [], 0.0
    for d, cum, ans in zip(req.doses, accumulate(req.doses), answers, strict=True):
        rows.append(HoldRow(dose_fraction=d, cumulative_fraction=cum, start=prev, end=ans.time,
                            actuation_time=ans.time - prev,
                            actuation_seconds=None if ans.seconds is None
                            else (ans.time - prev) * ans.timescale_seconds,
                            error_estimate=ans.error_estimate))
        prev = ans.time
    return "+".join(sorted({ans.model for ans in answers})), rows


def hold_schedule(planner: SchedulePlanner, req: ScheduleRequest) -> tuple[str, list[HoldRow]]:
    """Actuation times under the hold assumption, from the planner's single-dose answers."""
    return hold_rows(req, [planner.dose(req.dose_request(cum)) for cum in accumulate(req.doses)])


def hold_now(planner: SchedulePlanner, req: ScheduleRequest) -> ScheduleAnswer | None:
    """The schedule's hold reading when every dose is answered without a new full-solver
    run and neither the protocol check nor the correction is asked for; else None."""
    if req.check_protocol or req.correct:
        return None
    answers = []
    for cum in accumulate(req.doses):
        ans = planner.answer_now(req.dose_request(cum))
        if ans is None:
            return None
        answers.append(ans)
    model, hold = hold_rows(req, answers)
    return _answer(req, model, hold, None, None)


def with_seconds(tau: float | None, *readings: dict[str, Any] | None) -> None:
    """Each reading's actuation times in seconds (None without a bead size), any schedule."""
    for res in readings:
        if res is not None and "actuation_times" in res:
            res["actuation_seconds"] = (None if tau is None
                                        else [d * tau for d in res["actuation_times"]])


def plan_schedule_with(planner: SchedulePlanner, req: ScheduleRequest) -> ScheduleAnswer:
    """Plan ``req`` with ``planner``: hold times, then the protocol check and shooting
    (every heating a jump to T_end, or a heating protocol's: ``dosing.heating.cycles``)."""
    model, hold = hold_schedule(planner, req)
    guesses = [row.actuation_time for row in hold]

    def run(steps: tuple[Step, ...], stop_expelled: float | None = None) -> FullResult:
        sc = Scenario(req.gel, req.t_start, protocol=steps, branch=req.branch,
                      settings=req.settings, stop_expelled=stop_expelled)
        return planner.trajectory(sc)

    h = None
    if req.heating is not None:  # the heating's cycles (its program, cut at each time)
        from ..heating.response import mode_for

        h = ProtocolHeatings(planner, req, mode_for(planner, req))
        run = h.trajectory
    checked = protocol.check(run, req, guesses, h) if req.check_protocol else None
    corrected = protocol.shoot(run, req, guesses, h) if req.correct else None
    return _answer(req, model, hold, checked, corrected)


def _answer(req: ScheduleRequest, model: str, hold: list[HoldRow],
            checked: dict[str, Any] | None, corrected: dict[str, Any] | None) -> ScheduleAnswer:
    """The schedule's answer from its readings: seconds, volumes, the truth and a note."""
    dry = req.bead_dry_radius_um
    tau = timescale(dry, req.t_end, req.constants) if dry is not None else None
    with_seconds(tau and tau.seconds, checked, corrected)
    sv = stored_volume(req.start_radius)
    s = req.settings
    solver = (f"full solver, {s.grid} grid, N = {s.n}" + (
        f", the regularized model at interfacial length {s.interfacial_length:.3g}"
        if s.regularized else ", the paper's model"))
    note = ("Hold times assume the gel keeps its state while it rests (the paper's reading: "
            "doses read off one continuous heating). In the real protocol the gel takes up "
            "fresh fluid at T_start during each rest, so the next heating starts from a larger "
            f"radius; the protocol check shows what those times really deliver ({solver}), "
            f"and the corrected times were found by shooting on the same solver to meet each "
            f"dose within {req.tolerance:.0%}. Volumes are fluid volumes; the model does not "
            "track the drug in re-absorbed fluid.")
    if s.direct:
        note += (f" The protocol check and the shooting run the same truth as each dose's "
                 f"validation (the regularized model at ell = {s.interfacial_length:.3g}, "
                 f"moving grid, {s.n} cells"
                 + ("; the bead's own ell" if req.bead_dry_radius_um is not None else
                    "; no bead size: ell stands for the limit ell -> 0")
                 + "), so a corrected first actuation equals the single-dose answer within "
                 "that answer's validated error.")
    elif "front" in model and s.regularized:
        note += (" In this front regime the hold times are the sharp-interface limit "
                 "(ell -> 0) while the protocol runs use the ladder's coarsest ell, whose "
                 "front first has to nucleate at the edge: part of the correction is that "
                 "delay (a few % of an 80 % dose for ANB, more for HHT; each dose's "
                 "validation gives the ladder).")
    elif "front" in model:
        note += (" In this front regime the full solver's own answers depend on its grid "
                 "(no interfacial energy in the paper's model): treat its times as uncertain "
                 "by the grid spread shown in each dose's validation.")
    if req.heating is not None:
        note = (f"Each heating follows the protocol ({'; '.join(req.heating.texts)}) from "
                f"T_start = {req.t_start:g} K, then holds at its last temperature; times in "
                f"tau at its hottest temperature {req.t_end:g} K. " + note)
    ans = ScheduleAnswer(
        model=model, doses=list(req.doses), rests=list(req.rests), hold=hold,
        protocol_check=checked, corrected=corrected, start_radius=req.start_radius,
        stored_volume=sv, stored_volume_ul=None if dry is None else volume_to_ul(sv, dry),
        timescale_seconds=None if tau is None else tau.seconds,
        timescale_formula=SYMBOLIC_FORMULA if tau is None else tau.formula,
        scenario_key=Scenario(req.gel, req.t_start, req.t_end, branch=req.branch,
                              settings=req.settings).key(), note=note,
        truth=truth_text(req), interfacial_length=s.interfacial_length,
        method=s.method if s.regularized else "paper", t_start=req.t_start, t_end=req.t_end)
    ans.events = schedule_events(ans, req)
    return ans
