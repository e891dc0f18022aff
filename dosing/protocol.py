"""Heat-cool-heat protocols on the full solver: delivered volumes and shooting.

A schedule heats at T_end for each actuation and rests at T_start between them; while it
rests the gel takes up fresh fluid.  The volume a dose really delivers is what leaves
during its heating window, (4 pi/3)(a(start)^3 - a(end)^3) (eq. FluidVolExpelled),
reported as a fraction of the stored fluid (4 pi/3)(a0^3 - 1).  ``shoot`` finds
actuation times that meet every dose: each time is read off a longer run of the same
protocol prefix, then refined by the secant method on the exact protocol.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np

from solver.errors import ParameterError, SolverError

from .request import ScheduleRequest
from .scenario import Step, Trajectory

Runner = Callable[[tuple[Step, ...]], Trajectory]
MAX_EXTENSIONS = 6
MAX_SECANT = 8


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


def check(run: Runner, req: ScheduleRequest, durations: Sequence[float]) -> dict[str, Any]:
    """Simulate the heat/cool protocol with these actuation times; compare with the doses."""
    steps = heat_cool_protocol(durations, req.rests, req.t_start, req.t_end)
    traj = run(steps)
    dl = delivery(traj, durations, req.rests, req.start_radius)
    errors = [g / f - 1.0 for g, f in zip(dl.delivered, req.doses, strict=True)]
    return {"actuation_times": list(map(float, durations)), "protocol": [list(s) for s in steps],
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


def _read_off(run: Runner, req: ScheduleRequest, durations: list[float], k: int,
              guess: float) -> float:
    """Duration of heating k read off a longer run of the same prefix."""
    horizon = max(2.0 * guess, guess + 0.05)
    for _ in range(MAX_EXTENSIONS):
        traj = run(heat_cool_protocol([*durations, horizon], req.rests, req.t_start, req.t_end))
        start = windows([*durations, horizon], req.rests)[k][0]
        target = _window_target(req, traj.radius_at(start), req.doses[k], k)
        try:
            return traj.time_to_radius(target, after=start) - start
        except ValueError:
            horizon *= 3.0
    raise SolverError(f"dose {k} is not reached within a heating of {horizon:.4g}",
                      {"dose": k, "horizon": horizon})


def _delivered_k(run: Runner, req: ScheduleRequest, durations: list[float], k: int,
                 d: float) -> float:
    trial = [*durations[:k], d]
    traj = run(heat_cool_protocol(trial, req.rests, req.t_start, req.t_end))
    return delivery(traj, trial, req.rests, req.start_radius).delivered[k]


def _secant(run: Runner, req: ScheduleRequest, durations: list[float], k: int, d0: float,
            got0: float, tol: float) -> tuple[float, int]:
    """Refine heating k's duration until its delivery meets the dose within ``tol``."""
    target = req.doses[k]
    d1 = d0 * target / got0 if got0 > 0 else 1.5 * d0
    got1 = _delivered_k(run, req, durations, k, d1)
    runs = 1
    while abs(got1 / target - 1.0) > tol and runs < MAX_SECANT:
        if got1 == got0:
            break
        d0, got0, d1 = d1, got1, d1 + (target - got1) * (d1 - d0) / (got1 - got0)
        d1 = max(d1, 1e-9)
        got1 = _delivered_k(run, req, durations, k, d1)
        runs += 1
    return d1, runs


def shoot(run: Runner, req: ScheduleRequest, guesses: Sequence[float]) -> dict[str, Any]:
    """Actuation times meeting every dose within ``req.tolerance`` in the real protocol."""
    tol = req.tolerance / 2.0  # aim inside the tolerance, the final check must pass
    durations: list[float] = []
    for k, g in enumerate(guesses):
        durations.append(_read_off(run, req, durations, k, g))
    runs = len(guesses)
    for _ in range(3):
        res = check(run, req, durations)
        runs += 1
        bad = [k for k, e in enumerate(res["relative_errors"]) if abs(e) > tol]
        if not bad:
            break
        k0 = bad[0]
        for k in range(k0, len(durations)):
            got = _delivered_k(run, req, durations, k, durations[k])
            if abs(got / req.doses[k] - 1.0) > tol:
                durations[k], n = _secant(run, req, durations, k, durations[k], got, tol)
                runs += n
            runs += 1
    res = check(run, req, durations)
    worst = float(np.max(np.abs(res["relative_errors"])))
    res.update({"runs": runs, "max_relative_error": worst,
                "met": bool(worst <= req.tolerance)})
    if not res["met"]:
        raise SolverError(f"shooting did not meet the doses within {req.tolerance:.2%} "
                          f"(worst {worst:.2%})", res)
    return res
