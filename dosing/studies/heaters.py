"""Studies over heatings: which heater reaches a dose in time (a sweep of ramp rates or bath
time constants through the protocol dose, ``dosing.heating.response``), and a multi-dose
schedule run as one protocol of until-steps."""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np

from solver.errors import ParameterError

from ..heating.response import ProtocolDoseAnswer
from ..request import DoseRequest

# ----------------------------------------------------------------------------- heater sweeps
HEATERS = {"ramp": ("Heat to {t} K at {x:g} K/min", "K/min"),
           "bath": ("Bath at {t} K with a time constant of {x:g} s", "s")}


@dataclass
class HeaterRow:
    """One heater of a sweep: its kind and setting, the protocol and the dose's time."""

    kind: str
    value: float
    unit: str
    protocol: str
    seconds: float | None
    time: float
    error_estimate: float | None

    def to_dict(self) -> dict[str, Any]:
        """Plain-data form."""
        return asdict(self)


def heater_sweep(planner: Any, kind: str, values: list[float], t_end: float,
                 **fields: Any) -> list[HeaterRow]:
    """The dose's time for each heater setting: ``kind`` 'ramp' (rates in K/min to
    ``t_end``) or 'bath' (time constants in s, a bath at ``t_end``); ``fields`` are the
    rest of the :class:`DoseRequest` (gel, t_start, the dose, the bead size, ...).
    Blocking; every run is cached like any protocol dose's."""
    if kind not in HEATERS:
        raise ParameterError("kind", kind, "'ramp' or 'bath'")
    if not values:
        raise ParameterError("values", values, "at least one heating rate or time constant")
    text, unit = HEATERS[kind]
    rows = []
    for x in values:
        step = text.format(t=f"{float(t_end):g}", x=float(x))
        ans = planner.dose(DoseRequest(protocol=[step], **fields))
        rows.append(HeaterRow(kind, float(x), unit, step, ans.seconds, ans.time,
                              ans.error_estimate))
    return rows


def heater_needed(rows: list[HeaterRow], within_seconds: float) -> HeaterRow | None:
    """The least demanding heater of a sweep that reaches the dose within the time (the
    slowest ramp, or the bath with the largest time constant), or None."""
    ok = [r for r in rows if r.seconds is not None and r.seconds <= within_seconds]
    if not ok:
        return None
    return min(ok, key=lambda r: r.value) if ok[0].kind == "ramp" else max(
        ok, key=lambda r: r.value)


# ----------------------------------------------------------------------------- schedules
@dataclass
class ScheduleDose:
    """One dose of a schedule run as a protocol: its until-step, the cumulative fraction
    released since the protocol's start when it ends, and when its heating began and ended."""

    dose: int
    step: int
    text: str
    released: float
    start: float
    end: float
    start_seconds: float | None
    end_seconds: float | None


def schedule_steps(doses: list[float], t_start: float, t_end: float, rest: str,
                   heat: str | None = None) -> list[str]:
    """A multi-dose schedule as protocol steps: for each dose an optional heating step
    (``heat``, a rate such as '5 K/min'; None: a jump), 'Hold at T_end until <cumulative> %
    released', and between doses 'Rest at T_start for <rest>' (e.g. '10 min')."""
    if not doses:
        raise ParameterError("doses", doses, "at least one dose fraction")
    cum = 0.0
    steps: list[str] = []
    for k, f in enumerate(doses):
        try:
            x = float(f)
        except (TypeError, ValueError):
            x = math.nan
        if not (math.isfinite(x) and x > 0.0) or cum + x >= 1.0:
            raise ParameterError(f"doses[{k}]", f, f"a fraction > 0 with the doses' sum < 1 "
                                 f"(the doses before it release {cum:.4g})")
        cum += x
        if heat is not None:
            steps.append(f"Heat to {t_end:g} K at {heat}")
        steps.append(f"Hold at {t_end:g} K until {100.0 * cum:.10g} % released")
        if k < len(doses) - 1:
            steps.append(f"Rest at {t_start:g} K for {rest}")
    return steps


def protocol_schedule(planner: Any, doses: list[float], t_end: float, rest: str,
                      heat: str | None = None, **fields: Any
                      ) -> tuple[list[ScheduleDose], ProtocolDoseAnswer]:
    """A multi-dose schedule run as one protocol (:func:`schedule_steps`) through the
    protocol dose (every until-step resolved in order on the planner's runs, blocking and
    cached): each dose's heating start and end, and the last dose's answer.  ``fields`` are
    the rest of the :class:`DoseRequest` (gel, t_start, the bead size, ...)."""
    steps = schedule_steps(doses, float(fields["t_start"]), t_end, rest, heat)
    req = DoseRequest(protocol=steps, dose_fraction=float(np.sum([float(f) for f in doses])),
                      **fields)
    ans = planner.dose(req)
    tau_s = ans.timescale_seconds
    pieces = req.heating.with_durations(
        {u.step: u.end - u.start for u in ans.until_steps}).program(tau_s)
    begins, t = {}, 0.0
    for piece in pieces:
        begins.setdefault(piece.step, t)
        t += piece.duration or 0.0
    firsts = [i for i, st in enumerate(steps) if not st.startswith("Rest")
              and (i == 0 or steps[i - 1].startswith("Rest"))]
    rows, total = [], 0.0
    for k, (u, f) in enumerate(zip(ans.until_steps, doses, strict=True)):
        total += float(f)
        t0 = begins[firsts[k]]
        rows.append(ScheduleDose(k, u.step, u.text, total, t0, u.end,
                                 None if tau_s is None else t0 * tau_s, u.end_seconds))
    return rows, ans
