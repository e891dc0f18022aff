"""Heat-cool-heat protocols on the full solver: delivered volumes and shooting.

A schedule heats at T_end for each actuation and rests at T_start between them; while it
rests the gel takes up fresh fluid.  The volume a dose really delivers is what leaves
during its heating window, (4 pi/3)(a(start)^3 - a(end)^3) (eq. FluidVolExpelled),
reported as a fraction of the stored fluid (4 pi/3)(a0^3 - 1).  ``shoot_durations`` is the
one shooting routine of fluid and drug schedules (and the one horizon search of the drug
dose): each actuation time is read off a longer run of the same protocol prefix, then
refined by the secant method on the exact protocol; a schedule is a :class:`Heatings`.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import asdict, dataclass
from typing import Any, Protocol

import numpy as np
from scipy.optimize import brentq

from solver.errors import ParameterError, SolverError

from ..request import ScheduleRequest
from ..runs.scenario import Step, Trajectory

Runner = Callable[..., Trajectory]  # run(steps, stop_expelled=None): the protocol's run
STOP_MARGIN = 1e-6  # a read-off heating stops this much (relative) past its dose's volume
MAX_EXTENSIONS = 6  # longer heatings tried when reading a dose off (x GROWTH each)
GROWTH = 4.0
MAX_SECANT = 10  # secant steps per heating
READ_OFF_FLOOR = 0.05  # tau: a read-off heating lasts at least its guess plus this


def heat_cool_protocol(durations: Sequence[float], rests: Sequence[float], t_start: float,
                       t_end: float) -> tuple[Step, ...]:
    """(duration, temperature) steps: heat, rest, heat, ... (zero-length rests dropped)."""
    steps: list[Step] = []
    for k, d in enumerate(durations):
        if k > 0 and rests[k - 1] > 0.0:
            steps.append((float(rests[k - 1]), t_start))
        steps.append((float(d), t_end))
    return tuple(steps)


def windows(durations: Sequence[float], rests: Sequence[float]) -> list[tuple[float, float]]:
    """(start, end) time of each heating."""
    out, t = [], 0.0
    for k, d in enumerate(durations):
        if k > 0:
            t += rests[k - 1]
        out.append((t, t + d))
        t += d
    return out


@dataclass
class Delivery:
    """Per heating: the fraction of the stored fluid delivered; per rest: the uptake."""

    delivered: list[float]
    uptake: list[float]
    radii: list[tuple[float, float]]

    def to_dict(self) -> dict[str, Any]:
        """Plain-data form."""
        return asdict(self)


def delivery(traj: Trajectory, durations: Sequence[float], rests: Sequence[float],
             start_radius: float) -> Delivery:
    """What each heating window delivers and each rest takes up, as stored-fluid fractions."""
    scale = start_radius**3 - 1.0
    win = windows(durations, rests)
    radii = [(traj.radius_at(s), traj.radius_at(e)) for s, e in win]
    delivered = [(a**3 - b**3) / scale for a, b in radii]
    uptake = [(radii[k + 1][0] ** 3 - radii[k][1] ** 3) / scale for k in range(len(win) - 1)]
    return Delivery(delivered, uptake, radii)


def check(run: Runner, req: ScheduleRequest, durations: Sequence[float],
          h: FluidHeatings | None = None) -> dict[str, Any]:
    """Simulate the heat/cool protocol with these actuation times (each heating a jump to
    T_end, or ``h``'s heatings); compare with the doses."""
    h = h or FluidHeatings(run, req)
    steps = h.steps(durations)
    traj = run(steps)
    dl = delivery(traj, durations, req.rests, req.start_radius)
    errors = [g / f - 1.0 for g, f in zip(dl.delivered, req.doses, strict=True)]
    return {"actuation_times": list(map(float, durations)), "protocol": h.rows(steps),
            "delivered_fractions": dl.delivered, "relative_errors": errors,
            "rest_uptake_fractions": dl.uptake, "radii": [list(r) for r in dl.radii],
            "scenario_key": traj.meta.get("key")}


def _window_target(req: ScheduleRequest, a_start: float, fraction: float, k: int) -> float:
    """Radius at which heating k has delivered ``fraction`` from radius ``a_start``."""
    a3 = a_start**3 - fraction * (req.start_radius**3 - 1.0)
    if a3 <= req.jump.final_radius**3:
        most = (a_start**3 - req.jump.final_radius**3) / (req.start_radius**3 - 1.0)
        raise ParameterError(f"doses[{k}]", fraction, f"below {most:.4f}",
                             "after the earlier doses and rests the bead can give up at most "
                             "that fraction of the stored fluid at T_end")
    return a3 ** (1.0 / 3.0)


# ---------------------------------------------------------------- the one shooting routine

class Heatings(Protocol):
    """What shooting needs of a schedule, fluid or drug: the doses (``targets``, one per
    heating), the tolerance, runs of the heat/rest protocol for given actuation times, what
    each heating of a run delivers, and where in a run's heating k dose k is reached."""

    targets: Sequence[float]
    tolerance: float
    max_horizon: float

    def run(self, durations: Sequence[float]) -> Any: ...

    def delivered(self, result: Any, durations: Sequence[float]) -> list[float]: ...

    def reach(self, result: Any, durations: Sequence[float], k: int) -> Reach: ...


@dataclass(frozen=True)
class Reach:
    """Heating k of a run: the duration at which it delivers dose k (``duration``), or, when
    it does not within the run, the most it delivers and what its second half delivered
    (``late``; None where no late-rate bound applies, as for the fluid's exact limit)."""

    duration: float | None = None
    most: float = 0.0
    late: float | None = None


@dataclass(frozen=True)
class Short:
    """Dose ``k`` is not reached: heating k delivers at most ``most`` (of a heating up to
    ``horizon``); ``capped``: the horizon reached the runs' cap (else the late rate showed
    the dose out of reach)."""

    k: int
    most: float
    horizon: float
    capped: bool


@dataclass(frozen=True)
class ReadOff:
    """Heating k delivers dose k after ``duration``, read off ``result``, the run of the
    actuation times ``trial`` (the earlier ones and the longer heating)."""

    duration: float
    result: Any
    trial: list[float]


def read_off(h: Heatings, durations: Sequence[float], k: int, guess: float,
             floor: float = READ_OFF_FLOOR) -> ReadOff | Short:
    """Heating k's duration delivering dose k, read off a longer heating after the earlier
    ``durations``: the one horizon search (from twice ``guess``, at least ``guess + floor``,
    x GROWTH up to MAX_EXTENSIONS times and the runs' cap; a slowly releasing heating whose
    late rate kept to the cap falls short is given up early).  Heatings that can end a run
    where heating k delivers dose k (``run_until(durations, k)``, a terminal event) run so:
    nothing past the dose is computed."""
    horizon = min(max(2.0 * guess, guess + floor), h.max_horizon)
    until = getattr(h, "run_until", None)  # a run that may stop at dose k (terminal event)
    for _ in range(MAX_EXTENSIONS):
        trial = [*durations, horizon]
        result = h.run(trial) if until is None else until(trial, k)
        got = h.reach(result, trial, k)
        if got.duration is not None:
            return ReadOff(got.duration, result, trial)
        capped = horizon >= h.max_horizon
        hopeless = got.late is not None and got.most + max(got.late, 0.0) * (
            h.max_horizon - horizon) / (horizon / 2.0) < h.targets[k]
        if capped or hopeless:
            return Short(k, got.most, horizon, capped)
        horizon = min(GROWTH * horizon, h.max_horizon)
    return Short(k, got.most, horizon, False)


def secant(h: Heatings, durations: Sequence[float], k: int, d0: float, tol: float) -> float:
    """Refine heating k's duration (after ``durations``) until it delivers dose k within
    ``tol`` on the exact protocol (at most MAX_SECANT steps)."""
    target = h.targets[k]

    def got(d: float) -> float:
        trial = [*durations, d]
        return h.delivered(h.run(trial), trial)[k]

    g0 = got(d0)
    if abs(g0 / target - 1.0) <= tol:
        return d0
    d1 = d0 * target / g0 if g0 > 0 else 1.5 * d0
    g1 = got(d1)
    for _ in range(MAX_SECANT):
        if abs(g1 / target - 1.0) <= tol or g1 == g0:
            break
        d0, g0, d1 = d1, g1, max(d1 + (target - g1) * (d1 - d0) / (g1 - g0), 1e-9)
        g1 = got(d1)
    return d1


def shoot_durations(h: Heatings, guesses: Sequence[float]) -> tuple[list[float], Short | None]:
    """Actuation times meeting the doses one after another (a heating's delivery depends only
    on the steps before it): each read off a longer heating, then refined by the secant
    method aiming inside half the tolerance; stops at the first dose out of reach."""
    tol = h.tolerance / 2.0  # aim inside the tolerance, the final check must pass
    durations: list[float] = []
    for k, g in enumerate(guesses):
        got = read_off(h, durations, k, g)
        if isinstance(got, Short):
            return durations, got
        durations.append(secant(h, durations, k, got.duration, tol))
    return durations, None


@dataclass(frozen=True)
class Member:
    """One node of a population lifted over: its share ``weight`` of the batch's payload,
    ``rho`` = its tau over the reference bead's (eq. timescale: (R / R_ref)^2) and its own
    heatings (durations in its own tau)."""

    weight: float
    rho: float
    heatings: Any


class NodeHeatings:
    """A population's heatings (:class:`Heatings`) lifted from its nodes' own (pvlib's one
    chain over several arrays): durations in the reference bead's tau, node k's in its own
    (over rho_k); heating k of the batch delivers the weighted sum of the nodes' deliveries,
    and reaches dose k where that sum does (a root).  Any payload whose heatings say what
    heating k has delivered ``x`` after its start (``released_within``) lifts."""

    def __init__(self, members: Sequence[Member], targets: Sequence[float],
                 tolerance: float) -> None:
        self.members = list(members)
        self.targets, self.tolerance = tuple(targets), tolerance
        self.max_horizon = min(m.heatings.max_horizon * m.rho for m in self.members)
        self.count = 0

    def own(self, m: Member, durations: Sequence[float]) -> list[float]:
        """``durations`` in node ``m``'s own tau."""
        return [d / m.rho for d in durations]

    def run(self, durations: Sequence[float]) -> list[Any]:
        """Every node's run of these actuation times."""
        self.count += 1
        return [m.heatings.run(self.own(m, durations)) for m in self.members]

    def delivered(self, result: list[Any], durations: Sequence[float]) -> list[float]:
        """Each heating's delivery, fractions of the batch's payload (weighted)."""
        rows = [m.heatings.delivered(r, self.own(m, durations))
                for m, r in zip(self.members, result, strict=True)]
        return [sum(m.weight * row[k] for m, row in zip(self.members, rows, strict=True))
                for k in range(len(durations))]

    def reach(self, result: list[Any], durations: Sequence[float], k: int) -> Reach:
        """Where the batch's heating k delivers dose k: the root of the weighted sum (one
        node of the reference size: its own reading, so that a CV of 0 is the single bead's
        exactly)."""
        if len(self.members) == 1 and self.members[0].rho == 1.0:
            return self.members[0].heatings.reach(result[0], durations, k)

        def got(x: float) -> float:
            return sum(m.weight * m.heatings.released_within(r, self.own(m, durations), k,
                                                             x / m.rho)
                       for m, r in zip(self.members, result, strict=True))

        length, target = float(durations[k]), self.targets[k]
        end = got(length)
        if end < target:
            return Reach(None, end, end - got(length / 2.0))
        return Reach(float(brentq(lambda x: got(x) - target, 0.0, length,
                                  xtol=1e-13 * length, rtol=1e-12)))


class FluidHeatings:
    """A fluid schedule's heatings (:class:`Heatings`): doses of the stored fluid, runs of
    the heat/rest protocol by ``run``, counted."""

    max_horizon = math.inf  # a fluid dose beyond reach is refused exactly (_window_target)

    def __init__(self, run: Runner, req: ScheduleRequest) -> None:
        self._run, self.req = run, req
        self.targets, self.tolerance = req.doses, req.tolerance
        self.count = 0

    def steps(self, durations: Sequence[float]) -> tuple[Step, ...]:
        """The protocol's (duration, temperature) steps."""
        return heat_cool_protocol(durations, self.req.rests, self.req.t_start, self.req.t_end)

    def rows(self, steps: Sequence[Any]) -> list[list[Any]]:
        """The run's steps as plain rows (JSON)."""
        return [list(s) for s in steps]

    def run(self, durations: Sequence[float]) -> Trajectory:
        """The protocol run with these actuation times."""
        self.count += 1
        return self._run(self.steps(durations))

    def run_until(self, durations: Sequence[float], k: int) -> Trajectory:
        """The protocol run with these actuation times, ending where the last heating (k)
        has expelled dose k (a little past it: STOP_MARGIN), or at its end."""
        self.count += 1
        volume = self.req.doses[k] * (self.req.start_radius**3 - 1.0) * (1.0 + STOP_MARGIN)
        return self._run(self.steps(durations), stop_expelled=volume)

    def delivered(self, result: Trajectory, durations: Sequence[float]) -> list[float]:
        """Each heating's delivery, fractions of the stored fluid."""
        return delivery(result, durations, self.req.rests, self.req.start_radius).delivered

    def reach(self, result: Trajectory, durations: Sequence[float], k: int) -> Reach:
        """Where heating k delivers dose k (the radius it must fall to); a run that
        stopped at the dose (:meth:`run_until`) delivers it where it stopped (the dose and
        STOP_MARGIN: that run is then also the run of the heating ending there)."""
        start = windows(durations, self.req.rests)[k][0]
        if result.status == "stopped" and result.terminal_time is not None:
            return Reach(result.terminal_time - start)
        target = _window_target(self.req, result.radius_at(start), self.req.doses[k], k)
        try:
            return Reach(result.time_to_radius(target, after=start) - start)
        except ValueError:
            return Reach(None, self.delivered(result, durations)[k])


def corrected(h: Heatings, guesses: Sequence[float],
              reading: Callable[[list[float]], dict[str, Any]], extra_runs: int = 0,
              what: str = "the doses", partial: bool = False
              ) -> tuple[dict[str, Any], Short | None]:
    """The corrected schedule of any payload and population: :func:`shoot_durations`, then
    ``reading`` of the times found (its ``relative_errors``) with the worst error, whether
    every dose is met and the runs it took (``h.count`` + ``extra_runs``).  A dose out of
    reach raises (``partial``: the times before it are kept, with its :class:`Short`);
    found times missing the tolerance raise.  ``what``: the doses in the messages ("the
    batch's doses")."""
    durations, short = shoot_durations(h, guesses)
    if short is not None and not partial:
        raise SolverError(f"{what}: dose {short.k} is not reached within a heating of "
                          f"{short.horizon:.4g} (it delivers at most {short.most:.4g})",
                          {"dose": short.k, "horizon": short.horizon})
    if not durations:
        return {"actuation_times": [], "met": False, "runs": h.count + extra_runs}, short
    res = reading(durations)
    worst = float(np.max(np.abs(res["relative_errors"])))
    complete = len(durations) == len(h.targets)
    res.update({"runs": h.count + extra_runs, "max_relative_error": worst,
                "met": bool(complete and worst <= h.tolerance)})
    if complete and worst > h.tolerance:
        raise SolverError(f"shooting did not meet {what} within "
                          f"{h.tolerance:.2%} (worst {worst:.2%})", res)
    return res, short


def shoot(run: Runner, req: ScheduleRequest, guesses: Sequence[float],
          h: FluidHeatings | None = None) -> dict[str, Any]:
    """Actuation times meeting every dose within ``req.tolerance`` in the real protocol
    (each heating a jump to T_end, or ``h``'s heatings): :func:`corrected`, its reading
    the protocol check (one run more)."""
    h = h or FluidHeatings(run, req)
    return corrected(h, guesses, lambda d: check(run, req, d, h), extra_runs=1)[0]
