"""The heat/rest cycles of a schedule: each heating a jump to T_end or a protocol (issue 35).

A schedule's heating is the heating axis of its request (``ScheduleCase.protocol``): the
cycles are a jump's steps, or the protocol's program cut at each actuation time
(:func:`cycle_steps`, :func:`cycle_scenario`), in a bead's own tau (a batch's node) or as
the staircase a drug run takes.  Under a protocol, heating k runs the protocol's steps from
T_start ("Heat to 308 K at 5 K/min", a bath, a trace...) for its actuation time d_k,
holding at the protocol's last temperature once its steps are done (cut short when d_k
ends first), then the bead rests at T_start for r_k (sec. Application, fig.
multidose_schematic, with the jump replaced by the protocol).  The three readings are a
jump's schedule's (``dosing.question.schedule``): the hold reading from the protocol doses of the
cumulative doses (one continuous heating), the check of those times on the full solver,
and the times corrected by the one shooting routine (``dosing.question.shooting.shoot``) on the same
runs, each a continuous program in the solver's kernels (``solver.heating.Program``; a
stand-in solver gets the staircase of holds, as a protocol dose does).  Times are in tau
at the protocol's hottest temperature (eq. timescale), as every protocol answer's.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import replace
from typing import Any

import numpy as np

from ..question import shooting as protocol
from ..question.shooting import heat_cool_protocol
from ..request import ScheduleRequest
from ..runs.scenario import Scenario, Step
from ..units import timescale
from .grammar import Piece
from .program import program_spec, staircase


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


def cycle_pieces(req: Any, tau_s: float | None, durations: Sequence[float],
                 rests: Sequence[float]) -> list[Piece]:
    """The schedule's program: heating k (:func:`heating_pieces`) for ``durations[k]``, the
    ``rests`` at T_start between heatings (tau of the bead whose tau is ``tau_s``)."""
    heat = req.heating.program(tau_s)
    out: list[Piece] = []
    for k, d in enumerate(durations):
        if k > 0 and rests[k - 1] > 0.0:
            cur = _end(out[-1]) if out else req.t_start
            out.append(Piece("hold", cur, req.t_start, float(rests[k - 1])))
        out += heating_pieces(heat, float(d))
    return out


def cycle_steps(req: Any, durations: Sequence[float], rests: Sequence[float],
                tau_s: float | None) -> tuple[Step, ...]:
    """The heat/rest cycles as (duration, temperature) steps: a jump's heat at T_end and
    rest at T_start, or (a protocol) the staircase of its program (0.05 K stairs,
    ``dosing.heating.program.staircase``): the form a drug run takes."""
    if req.heating is None:
        return heat_cool_protocol(durations, rests, req.t_start, req.t_end)
    return tuple(staircase(cycle_pieces(req, tau_s, durations, rests), 0.0))


def cycle_scenario(req: Any, durations: Sequence[float], rests: Sequence[float],
                   tau_s: float | None, settings: Any, mode: Any) -> Scenario:
    """The full-solver run of the heat/rest cycles: a jump's steps, or a protocol's program
    run continuously in the solver's kernels (``mode.continuous``; the staircase on a
    stand-in solver)."""
    if req.heating is None or not mode.continuous:
        steps = cycle_steps(req, durations, rests, tau_s)
        return Scenario(req.gel, req.t_start, protocol=steps, branch=req.branch,
                        settings=settings)
    spec = program_spec(cycle_pieces(req, tau_s, durations, rests), mode.mobility, req.t_end)
    return Scenario(req.gel, req.t_start, program=spec, branch=req.branch, settings=settings)


class ProtocolHeatings(protocol.FluidHeatings):
    """The heatings of a fluid schedule under a protocol
    (:class:`dosing.question.shooting.Heatings`): each run the full solver's run of the
    heat/rest cycles (:func:`cycle_scenario`)."""

    run_until = None  # no terminal event on a program's expelled volume: read off a run

    def __init__(self, planner: Any, req: ScheduleRequest, mode: Any) -> None:
        dry = req.bead_dry_radius_um
        self.tau_s = None if dry is None else timescale(dry, req.t_end, req.constants).seconds
        self.planner, self.mode = planner, mode
        super().__init__(self.trajectory, req)

    def steps(self, durations: Sequence[float]) -> Scenario:  # type: ignore[override]
        """The run of these actuation times."""
        r = self.req
        return cycle_scenario(r, durations, r.rests, self.tau_s, r.settings, self.mode)

    def trajectory(self, sc: Scenario, stop_expelled: float | None = None) -> Any:
        """The run ``sc`` (blocking, cached)."""
        return self.planner.trajectory(sc)

    def rows(self, sc: Scenario) -> list[list[Any]]:  # type: ignore[override]
        """The run's steps as plain rows: the program's, or the staircase's."""
        from ..runs.scenario import plain

        return [plain(list(row)) for row in (sc.program["steps"] if sc.program is not None
                                             else sc.protocol)]
