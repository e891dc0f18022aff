"""Which model answers a dose under a heating protocol, and the reduced model's answer.

The reduced model is the front model under slow heating (``solver.front.slow``).  It answers,
in milliseconds, inside the region its tables measured within ``STATED_ERROR`` (``RAMP_MIN``,
``BATH_MAX``, doses, bead sizes, the regularized truth, not validated); elsewhere the full
solver does.  Model, tables, region: docs/heating.md, "The reduced model for slow heating"."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from solver.errors import NotApplicableError, ParameterError, SolverError
from solver.front.slow import slow_front_trajectory

from ..answers import Verdict
from ..request import DoseRequest
from ..truth import Part
from ..units import timescale
from .grammar import Piece
from .program import program_spec, solver_program

STATED_ERROR = 0.05  # the measured gap to the truth in the region is at most 4.6 %
NUMERICAL = 1e-5  # measured <= 2.4e-6 (tests/test_heating_slow.py: rtol, thin-shell start, tables)
# tau of the tables' 50 um dry bead at 308 K (eq. timescale): the paper's constants (one tau
# for every gel), and Omega_p = Omega Omega_f (benchmarks/heating_truth.py --constants)
TABLE_TAU_S = {"paper": 2205.0, "ANB": 22.05, "HHT": 158.7, "custom": 66.14}
RAMP_MIN = 10.0  # K per tau: the 30-90 % doses within 3.3 % from here up (ANB: 4.9 % at 9)
BATH_MAX = 0.17  # tau: the 50-90 % doses within 4.6 % up to here (HHT's 90 %: 5.1 % at 0.19)
FRACTION_RANGE = (0.3, 0.9)
BATH_FRACTION_MIN = 0.5
TABLE_ELL = 8e-5  # the table's interfacial length (4 nm / 50 um); larger ell delays nucleation
MODEL = "front-slow-sharp"
MODEL_TEXT = ("the front model under slow heating (solver/front/slow.py): uniform shrinking "
              "with a linear poro-elastic lag, a front that nucleates when the bead's state "
              "enters the coexistence region and its edge loses the swollen root, then the "
              "sharp-interface front with its levels at the current temperature")


def _per_minute(rate: float, tau_s: float) -> str:
    return f"{rate * 60.0 / tau_s:.2g} K/min"


_PAPER, _ANB = TABLE_TAU_S["paper"], TABLE_TAU_S["ANB"]
RAMP_MIN_TEXT = (f"{_per_minute(RAMP_MIN, _PAPER)} for a 50 um bead at tau = {_PAPER:g} s, "
                 f"{_per_minute(RAMP_MIN, _ANB)} for ANB's at tau = {_ANB:g} s")
BATH_MAX_TEXT = (f"{BATH_MAX * _PAPER:.3g} s for a 50 um bead at tau = {_PAPER:g} s, "
                 f"{BATH_MAX * _ANB:.2g} s for ANB's at tau = {_ANB:g} s")
REGION_TEXT = ("one ramp or bath to the hottest temperature then holds there, ramps of at "
               f"least {RAMP_MIN:.3g} K per tau ({RAMP_MIN_TEXT}), baths with time "
               f"constants up to {BATH_MAX:.3g} tau ({BATH_MAX_TEXT}), no traces, doses of "
               "30-90 % (50-90 % with a bath), beads of 50 um and larger")
TABLE_TEXT = ("measured against the truth (the full solver at the bead's own interfacial "
              "length, moving grid) for ANB, HHT and a custom gel, ramps of 0.03-3675 K per "
              "tau, baths of 4.5e-4-13.6 tau and doses of 10-90 % of a 50 um dry bead "
              "(benchmarks/heating_reduced.py, docs/heating.md)")


def choose(req: DoseRequest, pieces: list[Piece], validate: bool) -> Verdict:
    """The reduced model where the measured table says it is within STATED_ERROR."""
    if validate:
        return Verdict(False, "a validated answer runs the full solver")
    if not req.settings.regularized:
        return Verdict(False, "the reduced model's error was measured against the "
                      "regularized truth only, not the paper's model")
    ell = req.settings.interfacial_length
    if ell > TABLE_ELL * (1.0 + 1e-9):
        return Verdict(False, f"the interfacial length {ell:.3g} is larger than the table's "
                      f"{TABLE_ELL:g} (beads under 50 um, or no bead size): the truth's "
                      "front nucleates later there than the reduced model's (a 20 um HHT "
                      "bead's jump: 30 % dose 14 % later, 50 % 5.2 %)")
    lo, hi = FRACTION_RANGE
    has_bath = any(p.shape == "bath" for p in pieces)
    if has_bath:
        lo = BATH_FRACTION_MIN
    if not lo <= req.fraction <= hi:
        return Verdict(False, f"the dose {req.fraction:.0%} is outside {lo:.0%}-{hi:.0%}, where "
                      "the reduced model is within its stated error (small doses are mostly "
                      "the front's nucleation and the uniform shrinking before it"
                      + (", and with a bath doses under 50 % too)" if has_bath else ")"))
    hot = req.t_end
    heating = [p for p in pieces if not (p.shape == "hold" and p.t1 == hot)]
    if len(heating) > 1 or (heating and (heating[0] is not pieces[0] or heating[0].t1 != hot)):
        return Verdict(False, "the protocol is not one ramp or bath to its hottest temperature "
                      "followed by holds there, the heatings the reduced model's error was "
                      "measured for")
    cur = req.t_start
    dry = getattr(req, "bead_dry_radius_um", None)
    tau_s = None if dry is None else timescale(dry, hot, req.constants).seconds
    for p in pieces:
        where = f"protocol[{p.step}]"
        if p.shape == "trace":
            return Verdict(False, f"{where} is a measured trace: the reduced model's error "
                          "was not measured for traces")
        if p.t1 < cur - 1e-9:
            return Verdict(False, f"{where} cools: the reduced model covers heating only")
        if p.shape == "ramp" and p.duration and abs(p.t1 - p.t0) / p.duration < RAMP_MIN:
            rate = abs(p.t1 - p.t0) / p.duration
            here = "" if tau_s is None else f" ({_per_minute(rate, tau_s)} at tau = {tau_s:.4g} s)"
            return Verdict(False, f"{where} ramps at {rate:.3g} K per tau{here}, slower than "
                          f"the measured {RAMP_MIN:.3g} ({RAMP_MIN_TEXT}"
                          + ("" if tau_s is None else
                             f", {_per_minute(RAMP_MIN, tau_s)} for this bead") + ")")
        if p.shape == "bath" and (p.time_constant or 0.0) > BATH_MAX:
            here = "" if tau_s is None else f" ({p.time_constant * tau_s:.4g} s)"
            return Verdict(False, f"{where} has a time constant of {p.time_constant:.3g} tau"
                          f"{here}, longer than the measured {BATH_MAX:.3g} ({BATH_MAX_TEXT}"
                          + ("" if tau_s is None else
                             f", {BATH_MAX * tau_s:.3g} s for this bead") + ")")
        cur = p.t1
    return Verdict(True, f"the protocol and dose are inside the region where the reduced "
                   f"model is within {STATED_ERROR:.0%} of the truth ({REGION_TEXT}; "
                   f"{TABLE_TEXT})", STATED_ERROR)


@dataclass
class ReducedRun:
    """A reduced-model run standing in for a truth trajectory in the until/dose search:
    the crossing time of its target (``terminal_time``) and its samples."""

    terminal_time: float | None
    t: Any
    radius: Any
    horizon: float
    result: Any

    def time_to_radius(self, target: float, after: float = 0.0) -> float:
        """The model's crossing (ValueError if the run never reaches it)."""
        return self.result.time_to_radius(target, after)


def run(req: DoseRequest, pieces: list[Piece], mobility: str, target: float) -> ReducedRun:
    """The reduced model under ``pieces`` (until-steps resolved or bounded) to ``target``."""
    spec = program_spec(pieces, mobility, req.t_end)
    prog = solver_program(spec)
    res = slow_front_trajectory(req.gel, req.t_start, prog, targets=(target,))
    hit = res.hits.get(float(target), math.nan)
    return ReducedRun(hit if math.isfinite(hit) else None, res.t, res.radius,
                      float(res.t[-1]), res)


def reduced_time(req: DoseRequest, pieces: list[Piece], mobility: str,
                 target: float) -> float | None:
    """The reduced model's time to ``target`` under resolved ``pieces``, or None where it
    does not apply (cooling, no front) or fails."""
    try:
        return run(req, pieces, mobility, target).terminal_time
    except (NotApplicableError, SolverError, ParameterError, ValueError):
        return None


def model_form_part(req: DoseRequest, pieces: list[Piece], mobility: str, target: float,
                    truth_time: float) -> Part:
    """The model-form part of a full-solver protocol answer: the gap between the reduced
    model and the truth at this dose (both exist: the reduced model costs milliseconds),
    not the delayed-transition lattice (not run for protocols)."""
    t_red = reduced_time(req, pieces, mobility, target)
    if t_red is None or truth_time <= 0.0:
        return Part(None, (
            "model form: not measured for this protocol: the reduced model does not apply "
            "(it covers heating only, with a front) and the delayed-transition lattice "
            "(the step answers' model-form part) is not run for protocols"))
    gap = t_red / truth_time - 1.0
    return Part(abs(gap), (
        f"model form: {100 * abs(gap):.2g}%, the gap between the truth ({truth_time:.5g}) "
        f"and the reduced model ({t_red:.5g}; {MODEL_TEXT}): how far the leading-order "
        "physics of the front under heating is from the regularized model. The other "
        "consistent front law (the delayed transition of the ell = 0 lattice, the step "
        "answers' model-form part) is not run for protocols"))
