"""A schedule as events: the one table a bath controller or a lab notebook takes (issue 37).

Every schedule answer (fluid or drug, bead or batch, jump or protocol) carries ``events``, built
here alone: one row per heat/rest step, on one clock; the corrected reading when found, else
the checked hold times, else the hold reading (rough).  ``present.export.events_dataset``: the
xarray Dataset for ``--out FILE.csv|.nc``.  Columns: docs/results.md, "Tables and notebooks"."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

KINDS = ("heat", "rest", "hold")

# name -> (unit, long name): the columns in order (CF units; "" for text)
EVENT_COLUMNS: dict[str, tuple[str, str]] = {
    "step": ("1", "step number (1 = first)"),
    "kind": ("", "heat (a heating), rest (at T_start between heatings) or hold (a wait at "
                 "T_start before the first heating)"),
    "start_s": ("s", "start of the step on the protocol's clock"),
    "duration_s": ("s", "duration of the step"),
    "temperature_K": ("K", "set temperature (a protocol heating: at the step's end)"),
    "dose_fraction": ("1", "what the step delivers, a fraction of the stored fluid (a drug: "
                           "of the load)"),
    "released_fraction": ("1", "cumulative release at the step's end (same fraction)"),
    "amount_ul": ("uL", "fluid volume the step delivers"),
    "amount_ug": ("ug", "drug mass the step delivers"),
    "target_fraction": ("1", "the dose asked of this heating"),
    "dose_error": ("1", "delivered / asked - 1 on the full solver (corrected: the shooting "
                        "residual)"),
    "uptake_fraction": ("1", "fluid taken back up during a rest, a fraction of the stored "
                             "fluid"),
    "heating": ("1", "heating number (1 = first; 0: not a heating)"),
    "start_tau": ("1", "start of the step / tau of the reference bead"),
    "duration_tau": ("1", "duration of the step / tau of the reference bead"),
    "program": ("", "a protocol heating's steps, cut at its time (the step grammar)"),
    "reading": ("", "corrected, checked or hold"),
    "rough": ("1", "1: the hold reading (one continuous heating), not checked"),
}


def reading_of(answer: Any) -> tuple[str, dict[str, Any] | None]:
    """('corrected' | 'checked' | 'hold', the reading's dict or None for the hold reading)."""
    corrected = getattr(answer, "corrected", None)
    if corrected and corrected.get("actuation_times"):
        return "corrected", corrected
    checked = getattr(answer, "protocol_check", None)
    if checked and checked.get("actuation_times"):
        return "checked", checked
    return "hold", None


def _seconds(x: float | None, tau: float | None) -> float | None:
    return None if x is None or tau is None else float(x) * float(tau)


def _fmt_s(seconds: float | None, tau_value: float) -> str:
    if seconds is None:
        return f"{tau_value:.4g} tau"
    if seconds >= 120.0:
        return f"{seconds / 60.0:.4g} min"
    return f"{seconds:.4g} s"


def piece_text(p: Any, tau_s: float | None) -> str:
    """One program piece (``dosing.heating.grammar.Piece``, in tau) in the step grammar's words."""
    d = float(p.duration or 0.0)
    span = _fmt_s(_seconds(d, tau_s), d)
    if p.shape == "ramp":
        verb = "Heat" if p.t1 >= p.t0 else "Cool"
        rate = abs(p.t1 - p.t0) / d if d > 0 else 0.0
        rate_text = (f"{rate:.4g} K/tau" if tau_s is None else
                     f"{rate / tau_s * 60.0:.4g} K/min")
        return f"{verb} to {p.t1:.5g} K at {rate_text}"
    if p.shape == "bath":
        tc = _fmt_s(_seconds(p.time_constant, tau_s), float(p.time_constant or 0.0))
        return f"Bath at {p.t1:.5g} K with a time constant of {tc} for {span}"
    if p.shape == "trace":
        return f"Follow the measured trace for {span}"
    return f"Hold at {p.t1:.5g} K for {span}"


def _protocol_heating(req: Any, tau_s: float | None, duration: float) -> tuple[float, str]:
    """(set temperature at the heating's end, its steps in words) of a protocol heating of
    ``duration`` tau."""
    from ..heating.cycles import _end, heating_pieces

    pieces = heating_pieces(req.heating.program(tau_s), float(duration))
    return _end(pieces[-1]), "; ".join(piece_text(p, tau_s) for p in pieces)


def _get(values: Sequence[Any] | None, k: int) -> Any:
    return None if values is None or k >= len(values) else values[k]


def schedule_events(answer: Any, req: Any) -> list[dict[str, Any]]:
    """The answer's schedule as events (module doc): one dict per step, in order.  ``answer``: a
    fluid (``dosing.question.schedule.ScheduleAnswer``), drug (``dosing.payload.cycles.
    DrugScheduleAnswer``) or batch (``dosing.population.cycles.BatchScheduleAnswer``) schedule
    answer; ``req``: the planner's request it answers (temperatures, heating, rests, a wait)."""
    reading, res = reading_of(answer)
    tau = getattr(answer, "timescale_seconds", None)
    doses = list(answer.doses)
    rests = [float(r) for r in answer.rests]
    if res is None:
        durations = [float(r.actuation_time) for r in answer.hold]
        delivered = [float(r.dose_fraction) for r in answer.hold]
        errors = None
    else:
        durations = [float(x) for x in res["actuation_times"]]
        delivered = [float(x) for x in (res.get("delivered_fractions") or [])]
        errors = res.get("relative_errors")
    leaks = None if res is None else res.get("rest_leak_fractions")
    uptake = None if res is None else res.get("rest_uptake_fractions")
    before = None if res is None else res.get("leaked_before_heating")
    stored_ul = getattr(answer, "stored_volume_ul", None)
    load_ug = getattr(answer, "load_ug", None)
    t_start, t_end = float(req.t_start), float(req.t_end)
    heating = getattr(req, "heating", None)
    tau_s = None
    if heating is not None:  # the protocol's seconds in the reference bead's tau
        from ..units import timescale

        dry = req.bead_dry_radius_um
        tau_s = None if dry is None else timescale(dry, req.t_end, req.constants).seconds
    rough = reading == "hold"
    rows: list[dict[str, Any]] = []
    clock, released = 0.0, 0.0

    def add(kind: str, duration: float, temperature: float, dose: float | None,
            k: int = 0, **more: Any) -> None:
        nonlocal clock, released
        if dose is not None:
            released += dose
        rows.append({
            "step": len(rows) + 1, "kind": kind, "start_s": _seconds(clock, tau),
            "duration_s": _seconds(duration, tau), "temperature_K": temperature,
            "dose_fraction": dose, "released_fraction": released,
            "amount_ul": None if dose is None or stored_ul is None else dose * stored_ul,
            "amount_ug": None if dose is None or load_ug is None else dose * load_ug,
            "target_fraction": None, "dose_error": None, "uptake_fraction": None,
            "heating": k, "start_tau": clock, "duration_tau": duration, "program": None,
            "reading": reading, "rough": rough, **more})
        clock += duration

    lead = float(getattr(req, "lead", 0.0) or 0.0)
    if lead > 0.0:
        add("hold", lead, t_start, 0.0 if before is None else float(before))
    for k, d in enumerate(durations):
        if k > 0 and k - 1 < len(rests) and rests[k - 1] > 0.0:
            leak = _get(leaks, k - 1)
            add("rest", rests[k - 1], t_start, 0.0 if leak is None else float(leak),
                uptake_fraction=_get(uptake, k - 1))
        temp, program = t_end, None
        if heating is not None:
            temp, program = _protocol_heating(req, tau_s, d)
        err = _get(errors, k)
        add("heat", d, temp, _get(delivered, k), k + 1, target_fraction=_get(doses, k),
            dose_error=None if err is None else float(err), program=program)
    return rows
