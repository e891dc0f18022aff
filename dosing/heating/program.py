"""A protocol's program (``dosing.heating.grammar.Piece``s in tau) as the solver runs it.

:func:`program_spec` / :func:`solver_program`: plain data for a ``Scenario`` and the
``solver.heating.Program`` built from it (continuous T(t), the mobility relative to T_ref).
:func:`staircase`: each ramp, bath or trace as piecewise-constant holds, for a stand-in solver
without programs and the staircase benchmark (docs/heating.md, "Planner: a dose ...")."""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np

from solver.errors import ParameterError

from .grammar import Piece

# ----------------------------------------------------------------------------- staircase
STAIR_KELVIN = 0.05  # the staircase's temperature resolution (K per stair)
MAX_STAIRS = 4000


def staircase(pieces: Sequence[Piece], tail: float, resolution: float = STAIR_KELVIN
              ) -> list[tuple[float, float]]:
    """The program as piecewise-constant (duration, temperature) steps in tau: each continuous
    piece cut where T moved ``resolution`` K, each stair at its time-mean T (second order); a bath
    without an end in stairs until within resolution / 2, then held; ``tail`` tau held after the
    last piece.  Every piece needs a duration (until-steps resolved first)."""
    out: list[tuple[float, float]] = []
    end = pieces[0].t0 if pieces else math.nan  # the temperature the last piece ends at
    for p in pieces:
        d = p.duration
        end = p.t1
        if p.shape == "hold":
            if d is None:
                raise ParameterError(f"protocol[{p.step}]", None, "a duration (until-steps "
                                     "are resolved by the planner first)")
            out.append((d, p.t1))
            continue
        if p.shape == "bath" and d is None:
            gap = abs(p.t0 - p.t1)
            d = (p.time_constant * math.log(2.0 * gap / resolution)
                 if gap > resolution / 2.0 else 0.0)
        if d is None:
            raise ParameterError(f"protocol[{p.step}]", None, "a duration")
        if d <= 0.0:
            continue
        if p.shape == "trace":  # the samples, refined to 1/8 stair between them
            s = _refine(np.asarray(p.times), np.asarray(p.temps), resolution / 8.0)
        else:
            s = np.linspace(0.0, d, 2049)
        temps = p.temperature(s)
        end = float(temps[-1]) if p.duration is not None else p.t1
        out.extend(_stairs(s, temps, resolution))
        if p.shape == "bath" and p.duration is None:
            out.append((0.0, p.t1))  # the hold at the bath's temperature follows
    if tail > 0.0:
        out.append((tail, end))
    merged: list[tuple[float, float]] = []
    for d, temp in out:
        if merged and abs(merged[-1][1] - temp) < 1e-12:
            merged[-1] = (merged[-1][0] + d, temp)
        elif d > 0.0:
            merged.append((d, temp))
    if len(merged) > MAX_STAIRS:
        return staircase(pieces, tail, resolution * 2.0)
    return [(float(d), float(round(temp, 9))) for d, temp in merged]


def _refine(times: np.ndarray, temps: np.ndarray, step: float) -> np.ndarray:
    """``times`` with points added so that T moves by at most ``step`` between them."""
    parts = np.maximum(1, np.ceil(np.abs(np.diff(temps)) / step)).astype(int)
    parts = np.minimum(parts, max(1, 400_000 // max(1, times.size)))
    k = np.repeat(np.arange(times.size - 1), parts)
    frac = np.concatenate([np.arange(n) / n for n in parts]) if parts.size else np.array([])
    return np.append(times[k] + frac * np.diff(times)[k], times[-1])


def _stairs(s: np.ndarray, temps: np.ndarray, resolution: float) -> list[tuple[float, float]]:
    """Cut a sampled T(s) where it has moved by ``resolution``; time-mean temperature each."""
    out = []
    k0 = 0
    n = s.size
    while k0 < n - 1:
        k = k0 + 1
        while k < n - 1 and abs(temps[k] - temps[k0]) < resolution:
            k += 1
        seg_t, seg_T = s[k0:k + 1], temps[k0:k + 1]
        dur = float(seg_t[-1] - seg_t[0])
        mean = float(np.trapezoid(seg_T, seg_t) / dur) if dur > 0 else float(seg_T[-1])
        if dur > 0:
            out.append((dur, mean))
        k0 = k
    return out


# ----------------------------------------------------------------------------- solver program
OPEN_BATH_CONSTANTS = 40.0  # an open bath runs 40 time constants (within e^-40 of the bath)
MOBILITY_TEXT = {
    "kT": "the mobility's temperature dependence m(T) = T / T_ref inside the rate (k_B T; "
          "the viscosity held at its given value)",
    "water": "the mobility's temperature dependence m(T) = (T / T_ref) eta_w(T_ref) / "
             "eta_w(T) inside the rate (k_B T and water's viscosity)",
    "constant": "the mobility held at its value at T_ref (the paper's choice)",
}


def program_spec(pieces: Sequence[Piece], mobility: str, reference: float) -> dict[str, Any]:
    """The program as plain data for ``solver.heating.Program`` (:func:`solver_program`):
    a last hold without a duration is dropped when it holds the temperature the bead is
    at (the run holds there after its last step anyway), else kept for an instant; a bath
    without an end runs ``OPEN_BATH_CONSTANTS`` time constants."""
    steps: list[list[Any]] = []
    cur = pieces[0].t0 if pieces else reference
    for p in pieces:
        rows, cur = _piece_rows(p, cur)
        steps.extend(rows)
    if not steps:
        steps.append(["hold", cur, 1e-12])
    return {"steps": steps, "mobility": mobility, "reference": float(reference)}


def _piece_rows(p: Piece, cur: float) -> tuple[list[list[Any]], float]:
    """One piece's rows of :func:`program_spec` (none, or one) from temperature ``cur``, and
    the temperature it ends at."""
    rows: list[list[Any]] = []
    if p.shape == "ramp":
        if p.duration and p.t1 != p.t0:
            rows.append(["ramp", p.t1, abs(p.t1 - p.t0) / p.duration])
    elif p.shape == "hold":
        if p.duration is None:
            if p.t1 != cur:
                rows.append(["hold", p.t1, 1e-12])
        elif p.duration > 0.0:
            rows.append(["hold", p.t1, p.duration])
    elif p.shape == "bath":
        d = p.duration if p.duration is not None else OPEN_BATH_CONSTANTS * p.time_constant
        if d > 0.0:
            rows.append(["bath", p.t1, p.time_constant, d])
    else:
        rows.append(["trace", list(p.times), list(p.temps)])
    if p.shape == "bath" and p.duration is not None:
        cur = float(p.temperature(np.array([p.duration]))[0])
    elif p.shape == "trace":
        cur = p.temps[-1]
    else:
        cur = p.t1
    return rows, cur


# the solver's field of a program step -> the grammar's name of it
_GRAMMAR_FIELD = {"duration": "for", "rate": "rate", "target": "to", "temperature": "at",
                  "time_constant": "time_constant", "times": "trace", "temperatures": "trace"}


def check_program(protocol: Any, tau_s: float | None) -> None:
    """What the grammar accepted, checked by the solver's rules before anything runs: ``protocol``'s
    steps in tau (``tau_s``: tau in s, None for tau alone) through ``solver.heating``'s checks
    (durations, rates, time constants, traces: ``solver.limits``), none over PROGRAM_STEP_MAX tau.
    A ParameterError names the step and the grammar's field (``protocol[0].time_constant``)."""
    from solver.limits import PROGRAM_STEP_MAX

    try:
        pieces = protocol.program(tau_s)
    except ParameterError:
        if tau_s is None:  # seconds without a bead size: refused where they are converted
            return
        raise
    cur = pieces[0].t0 if pieces else protocol.t_start
    for p in pieces:
        text = protocol.steps[p.step].text
        reason = f"in step {p.step}: {text!r}, as the solver runs it (in tau"
        reason += "" if tau_s is None else f", tau = {tau_s:.4g} s"
        d = p.duration
        if p.shape == "ramp" and not (d is not None and d <= PROGRAM_STEP_MAX):
            raise ParameterError(f"protocol[{p.step}].rate", text,
                                 f"a rate that takes at most {PROGRAM_STEP_MAX:g} tau "
                                 f"(from {p.t0:g} K to {p.t1:g} K: at least "
                                 f"{abs(p.t1 - p.t0) / PROGRAM_STEP_MAX:.3g} K/tau)",
                                 f"{reason}: {d!r} tau)")
        rows, cur = _piece_rows(p, cur)
        try:
            solver_program({"steps": rows or [["hold", cur, 1e-12]], "mobility": "constant",
                            "reference": cur})
        except ParameterError as exc:
            name = exc.field.split(".", 1)[1] if "." in exc.field else exc.field
            base = name.split("[", 1)[0]
            valid = exc.valid
            if p.shape == "bath" and p.duration is None and base == "duration":
                base = "time_constant"
                valid = (f"0 < time_constant <= {PROGRAM_STEP_MAX / OPEN_BATH_CONSTANTS:g} tau "
                         f"for a bath without 'for' or 'until' (it runs "
                         f"{OPEN_BATH_CONSTANTS:g} time constants, at most "
                         f"{PROGRAM_STEP_MAX:g} tau)")
            field = _GRAMMAR_FIELD.get(base, base)
            raise ParameterError(f"protocol[{p.step}].{field}", text, valid,
                                 f"{reason}: {name} = {exc.value!r})") from None
    from .grammar import check_physical

    check_physical(protocol, tau_s)  # durations in tau, by their seconds (issue 40, R8)


def solver_program(spec: dict[str, Any]) -> Any:
    """A ``solver.heating.Program`` from :func:`program_spec`'s plain data."""
    from solver import heating as sh

    steps = []
    for row in spec["steps"]:
        kind = row[0]
        if kind == "ramp":
            steps.append(sh.Ramp(float(row[1]), float(row[2])))
        elif kind == "hold":
            steps.append(sh.Hold(float(row[1]), float(row[2])))
        elif kind == "bath":
            steps.append(sh.Bath(float(row[1]), float(row[2]), float(row[3])))
        else:
            steps.append(sh.Trace(tuple(row[1]), tuple(row[2])))
    return sh.Program(tuple(steps), spec.get("mobility", "constant"), spec.get("reference"))
