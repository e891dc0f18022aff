"""A fluid schedule whose every heating follows a heating protocol (issue 35).

The schedule of sec. Application (fig. multidose_schematic) with the jump to T_end replaced
by the protocol: heating k runs the protocol's steps from T_start ("Heat to 308 K at
5 K/min", a bath, a trace...) for its actuation time d_k, holding at the protocol's last
temperature once its steps are done (cut short when d_k ends first), then the bead rests
at T_start for r_k.  The three readings are those of a jump's schedule
(``dosing.schedule``): the hold reading from the protocol doses of the cumulative doses
(one continuous heating), the check of those times on the full solver, and the times
corrected by the one shooting routine (``dosing.protocol.shoot``) on the same runs, each a
continuous program in the solver's kernels (``solver.heating.Program``; a stand-in solver
gets the staircase of holds, as a protocol dose does).  Times are in tau at the protocol's
hottest temperature (eq. timescale), as every protocol answer's.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field, replace
from itertools import accumulate
from typing import Any

import numpy as np

from solver.errors import ParameterError

from . import protocol
from .heating import Piece
from .heating_program import program_spec, staircase
from .request import DoseRequest, ScheduleRequest, _resolve_protocol
from .scenario import Scenario
from .schedule import ScheduleAnswer, _answer, hold_rows
from .units import timescale


@dataclass(frozen=True)
class ProtocolScheduleRequest(ScheduleRequest):
    """A fluid schedule (:class:`~dosing.request.ScheduleRequest`) whose heatings follow
    ``protocol`` (steps without until-steps: the doses end each heating); T_end is the
    protocol's hottest temperature."""

    protocol: Any = field(default=None, kw_only=True)
    heating: Any = field(init=False, repr=False, compare=False, default=None)

    def __post_init__(self) -> None:
        _resolve_protocol(self)
        for i in self.heating.until_steps:
            raise ParameterError(f"protocol[{i}].until", self.heating.steps[i].text,
                                 "a step with a duration or none (a schedule's doses end "
                                 "each heating)")
        super().__post_init__()

    def dose_request(self, fraction: float) -> DoseRequest:
        """The protocol dose of ``fraction`` of the stored fluid (one continuous heating)."""
        fields = {**self.case_fields(), "t_end": None}
        return DoseRequest(**fields, protocol=self.heating, dose_fraction=fraction)


def _cut(p: Piece, length: float) -> Piece:
    """Piece ``p`` cut to its first ``length`` tau."""
    if p.shape == "ramp":
        end = float(p.temperature(np.array([length]))[0])
        return replace(p, t1=end, duration=length)
    if p.shape == "trace":
        keep = [t for t in p.times if t < length]
        temps = [*p.temps[:len(keep)], float(np.interp(length, p.times, p.temps))]
        return replace(p, times=(*keep, length), temps=tuple(temps), duration=length,
                       t1=temps[-1])
    return replace(p, duration=length, until=None)


def _end(p: Piece) -> float:
    """The temperature at which piece ``p`` (with a duration) ends."""
    return float(p.temperature(np.array([p.duration or 0.0]))[0])


def heating_pieces(heat: Sequence[Piece], length: float) -> list[Piece]:
    """One heating of ``length`` tau: the protocol's pieces ``heat`` cut where it ends, or
    followed by a hold at their last temperature."""
    out: list[Piece] = []
    t = 0.0
    for p in heat:
        left = length - t
        if left <= 0.0:
            break
        if p.duration is None or p.duration >= left:
            out.append(_cut(p, left))
            t = length
            break
        out.append(p)
        t += p.duration
    if t < length:
        last = _end(out[-1]) if out else heat[0].t0
        out.append(Piece("hold", last, last, length - t))
    return out


def cycle_pieces(req: ProtocolScheduleRequest, tau_s: float | None,
                 durations: Sequence[float]) -> list[Piece]:
    """The schedule's program: heating k (:func:`heating_pieces`) for ``durations[k]``, the
    rests at T_start between heatings."""
    heat = req.heating.program(tau_s)
    out: list[Piece] = []
    for k, d in enumerate(durations):
        if k > 0 and req.rests[k - 1] > 0.0:
            cur = _end(out[-1]) if out else req.t_start
            out.append(Piece("hold", cur, req.t_start, float(req.rests[k - 1])))
        out += heating_pieces(heat, float(d))
    return out


class ProtocolHeatings(protocol.FluidHeatings):
    """The heatings of a schedule under a protocol (:class:`dosing.protocol.Heatings`):
    each run the schedule's program on the planner's solver, continuous (``mode``) or the
    staircase of a stand-in solver."""

    run_until = None  # no terminal event on a program's expelled volume: read off a run

    def __init__(self, planner: Any, req: ProtocolScheduleRequest, mode: Any) -> None:
        dry = req.bead_dry_radius_um
        self.tau_s = None if dry is None else timescale(dry, req.t_end, req.constants).seconds
        self.planner, self.mode = planner, mode
        super().__init__(self.trajectory, req)

    def steps(self, durations: Sequence[float]) -> list[Piece]:  # type: ignore[override]
        """The schedule's program pieces for these actuation times."""
        return cycle_pieces(self.req, self.tau_s, durations)

    def scenario(self, pieces: Sequence[Piece]) -> Scenario:
        """The full-solver run of ``pieces``."""
        r = self.req
        if self.mode.continuous:
            return Scenario(r.gel, r.t_start, program=program_spec(pieces, self.mode.mobility,
                                                                    r.t_end),
                            branch=r.branch, settings=r.settings)
        return Scenario(r.gel, r.t_start, protocol=tuple(staircase(pieces, 0.0)),
                        branch=r.branch, settings=r.settings)

    def trajectory(self, pieces: Sequence[Piece], stop_expelled: float | None = None) -> Any:
        """The run of ``pieces`` (blocking, cached)."""
        return self.planner.trajectory(self.scenario(pieces))

    def rows(self, pieces: Sequence[Piece]) -> list[list[Any]]:
        """The program's steps as plain rows."""
        return [list(row) for row in program_spec(pieces, self.mode.mobility,
                                                  self.req.t_end)["steps"]]


def plan_protocol_schedule(planner: Any, req: ProtocolScheduleRequest) -> ScheduleAnswer:
    """The schedule's hold reading, protocol check and corrected times (module doc)."""
    from .protocol_dose import mode_for

    answers = [planner.dose(req.dose_request(cum)) for cum in accumulate(req.doses)]
    model, hold = hold_rows(req, answers)
    guesses = [row.actuation_time for row in hold]
    h = ProtocolHeatings(planner, req, mode_for(planner, req))
    checked = protocol.check(h.trajectory, req, guesses, h) if req.check_protocol else None
    corrected = protocol.shoot(h.trajectory, req, guesses, h) if req.correct else None
    ans = _answer(req, model, hold, checked, corrected)
    ans.note = (f"Each heating follows the protocol ({'; '.join(req.heating.texts)}) from "
                f"T_start = {req.t_start:g} K, then holds at its last temperature; times in "
                f"tau at its hottest temperature {req.t_end:g} K. " + ans.note)
    return ans
