"""A dose under a heating protocol: the time from the protocol's start at which it is reached.

The truth is the full solver (the request's ``SolverSettings``); the dose radius is eq.
FluidVolExpelled's, the answer in tau and in seconds through tau at the protocol's hottest
temperature (eq. timescale).  Until-steps, the tail (``TAIL``, ``MAX_TAIL``), program or
staircase, cache and jobs: docs/heating.md, "Planner: a dose under a protocol"."""

from __future__ import annotations

import hashlib
import json
import math
from collections.abc import Callable
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np

from solver.equilibrium import nearest_stable
from solver.errors import NotApplicableError, ParameterError, SolverError
from solver.front.slow import slow_front_trajectory

from ..answers import Pending, Verdict
from ..request import DoseRequest
from ..runs.scenario import Scenario, Trajectory
from ..truth import Part, Uncertainty, truth_text
from ..units import (
    expelled_volume,
    radius_after_dose,
    released_fraction,
    timescale,
    ul_to_volume,
    volume_to_ul,
)
from ..validation import validation_report
from . import reduced as heating_reduced
from .grammar import Piece, Protocol, Until, reference_text
from .program import MOBILITY_TEXT, STAIR_KELVIN, program_spec, staircase

TAIL = 0.1  # tau held after the last step (the moving grid's first horizon of a jump)
MAX_TAIL = 64.0
CURVE_POINTS = 400


@dataclass
class UntilResult:
    """When an until-step ended: its index and text, start and end in tau and seconds."""

    step: int
    text: str
    start: float
    end: float
    start_seconds: float | None
    end_seconds: float | None
    # 'until': its condition ended it; 'duration': a 'for D or until X' step whose D came
    # first (the condition not met within it)
    ended_by: str = "until"


@dataclass
class ProtocolDoseAnswer:
    """How long from the protocol's start until the dose is out, and what the protocol is."""

    model: str
    truth: str
    protocol: list[str]
    protocol_steps: list[dict[str, Any]]
    t_start: float
    reference_temperature: float
    reference: str
    time: float
    seconds: float | None
    timescale_seconds: float | None
    timescale_formula: str | None
    program: str
    dose_fraction: float
    start_radius: float
    final_radius: float
    final_radius_um: float | None
    expelled_volume: float
    expelled_volume_ul: float | None
    stored_volume_ul: float | None
    temperature_at_dose: float
    until_steps: list[UntilResult]
    error_estimate: float | None
    error_explanation: str
    # the parts (dosing.truth.Part) by name; validated, also the truth's other fields
    # (dosing.truth.Uncertainty.by_name)
    uncertainty: dict[str, Any] | None
    validation: dict[str, Any] | None
    scenario_key: str
    interfacial_length: float
    bead_dry_radius_um: float | None
    curve: dict[str, list[float]]
    note: str = ""
    model_reason: str = ""

    def to_dict(self) -> dict[str, Any]:
        """Plain-data form (JSON-ready)."""
        return asdict(self)




def _tau_seconds(req: DoseRequest) -> float | None:
    dry = req.bead_dry_radius_um
    return None if dry is None else timescale(dry, req.t_end, req.constants).seconds


def until_radius(req: DoseRequest, until: Until, step: int) -> float:
    """The dimensionless radius at which an until-condition holds."""
    a0 = req.start_radius
    dry = req.bead_dry_radius_um
    where = f"protocol[{step}].until.{until.kind}"
    if until.kind == "fraction":
        return radius_after_dose(a0, until.value)
    if dry is None:
        raise ParameterError("dry_radius_um", None, f"a finite number > 0 (um) for {where}")
    if until.kind == "radius_um":
        return until.value / dry
    vol = until.value
    if until.kind == "mass_ug":
        if req.concentration_ug_per_ul is None:
            raise ParameterError("concentration_ug_per_ul", None,
                                 f"a finite number > 0 (ug/uL) for {where}")
        vol = until.value / req.concentration_ug_per_ul
    f = ul_to_volume(vol, dry) / req.jump.stored_volume
    if not 0.0 < f < 1.0:
        raise ParameterError(where, until.value, f"less than the stored "
                             f"{volume_to_ul(req.jump.stored_volume, dry):.4g} uL")
    return radius_after_dose(a0, f)


def _open(pieces: list[Piece], tail: float) -> list[tuple[float, float]]:
    """The staircase of ``pieces`` whose last one may be open (no duration), held ``tail``."""
    last = pieces[-1]
    if last.duration is None and last.shape == "hold":
        pieces = [*pieces[:-1], Piece("hold", last.t0, last.t1, 0.0, step=last.step)]
    return staircase(pieces, tail)


def _scenario(req: DoseRequest, steps: list[tuple[float, float]], settings: Any) -> Scenario:
    return Scenario(req.gel, req.t_start, protocol=tuple(steps), branch=req.branch,
                    settings=settings)


Getter = Callable[[list[Scenario], float, float], list[Trajectory] | Pending]


@dataclass(frozen=True)
class Mode:
    """How a protocol runs: ``continuous`` T(t) in the solver's kernels with a terminal
    event at the target radius (``solver.heating.Program``, ``simulate(stop=...)``) and the
    ``mobility`` law, or (False) the staircase of holds on the piecewise-constant protocol
    (a stand-in solver that takes no program)."""

    continuous: bool = True
    mobility: str = "kT"


def mode_for(planner: Any, req: DoseRequest) -> Mode:
    """Continuous on the real solver (its mobility: 'water' with water's viscosity, else
    'kT'); the staircase on a stand-in solver."""
    from ..runs.full import is_full_solver

    return Mode(is_full_solver(planner.solver), req.constants.mobility)


def _settings_list(req: DoseRequest, check: Any) -> list[Any]:
    out = [req.settings]
    if check:
        out.append(req.settings.check())
        if req.interfacial_range is not None and check == "range":
            out += [req.settings.with_length(ell) for ell in req.interfacial_range]
    return out


def _reach_event(req: DoseRequest, get: Getter, pieces: list[Piece], target: float,
                 after: float, field: str, check: Any, mode: Mode
                 ) -> tuple[float, Trajectory, list[Scenario], list[Any]] | Pending:
    """The continuous program of ``pieces`` run until the radius reaches ``target`` (a
    terminal event; the solver holds at the last temperature after the last step)."""
    spec = program_spec(pieces, mode.mobility, req.t_end)
    scs = [Scenario(req.gel, req.t_start, program=spec, stop=target, branch=req.branch,
                    settings=s) for s in _settings_list(req, check)]
    trajs = _runs(get, scs, target, after)
    if isinstance(trajs, Pending):
        return trajs
    traj = trajs[0]
    t_hit = _event_time(traj, target)
    if t_hit is None:
        raise ParameterError(field, target, f"a radius the bead reaches: the run ends at "
                             f"radius {float(traj.radius[-1]):.4g} dry radii after "
                             f"{traj.horizon:.4g} tau, held at the last temperature")
    trajs = [tr if k == 0 or isinstance(tr, BaseException) or _event_time(tr, target)
             is not None else ValueError(f"the run does not reach radius {target:.6g}")
             for k, tr in enumerate(trajs)]
    return t_hit, traj, scs, trajs


def _runs(get: Getter, scs: list[Scenario], target: float, after: float
          ) -> list[Any] | Pending:
    """The runs' trajectories from ``get`` (or its Pending); the truth's failure raised."""
    trajs = get(scs, target, after)
    if not isinstance(trajs, Pending) and isinstance(trajs[0], BaseException):
        raise trajs[0]
    return trajs


def _event_time(traj: Any, target: float) -> float | None:
    t = getattr(traj, "terminal_time", None)
    if t is not None:
        return float(t)
    try:
        return traj.time_to_radius(target)
    except ValueError:
        return None


def _reach(req: DoseRequest, get: Getter, pieces: list[Piece], target: float, after: float,
           field: str, check: Any, mode: Mode = Mode()) -> tuple[float, Trajectory,
                                                                list[Scenario], list[Any]
                                                                ] | Pending:
    """First time >= ``after`` the truth run of ``pieces`` (+ a tail) reaches ``target``:
    (time, truth trajectory, scenarios, their trajectories), or Pending."""
    if mode.continuous:
        return _reach_event(req, get, pieces, target, after, field, check, mode)
    tail = TAIL
    while True:
        steps = _open(pieces, tail)
        scs = [_scenario(req, steps, s) for s in _settings_list(req, check)]
        trajs = _runs(get, scs, target, after)
        if isinstance(trajs, Pending):
            return trajs
        traj = trajs[0]
        try:
            t_hit = traj.time_to_radius(target, after)
        except ValueError:
            t_hit = None
        if t_hit is not None:
            short = [k for k, tr in enumerate(trajs) if k and not _reaches(tr, target, after)]
            if not short or tail >= MAX_TAIL:  # a check run short of it at the end: failed
                trajs = [ValueError(f"the run does not reach radius {target:.6g}")
                         if k in short else tr for k, tr in enumerate(trajs)]
                return t_hit, traj, scs, trajs
            tail = min(4.0 * tail, MAX_TAIL)
            continue
        a_end = float(traj.radius[-1])
        t_last = steps[-1][1]
        a_inf = nearest_stable(req.gel, t_last, a_end).stretch
        if (a_inf - target) * (a_end - target) > 0.0 or tail >= MAX_TAIL:
            raise ParameterError(field, target, f"a radius the bead reaches: held at "
                                 f"{t_last:g} K it goes to {a_inf:.4g} dry radii (it is "
                                 f"{a_end:.4g} at the run's end)")
        tail = min(4.0 * tail, MAX_TAIL)


def _reaches(traj: Any, target: float, after: float) -> bool:
    if isinstance(traj, BaseException):
        return True  # a failed run is reported as such, not extended
    try:
        traj.time_to_radius(target, after)
    except ValueError:
        return False
    return True


def resolve_untils(req: DoseRequest, get: Getter, mode: Mode = Mode()
                   ) -> tuple[Protocol, list[UntilResult]] | Pending:
    """The protocol with each until-step's duration found by its truth run, in order."""
    prot: Protocol = req.heating
    tau_s = _tau_seconds(req)
    durations: dict[int, float] = {}
    done: list[UntilResult] = []
    for i in prot.until_steps:
        pieces = prot.with_durations(durations).program(tau_s)[: i + 1]
        start = sum(p.duration for p in pieces[:-1])
        piece = pieces[-1]
        target = until_radius(req, piece.until, i)
        bound = piece.duration  # 'for D or until X': whichever comes first
        try:
            got = _reach(req, get, pieces, target, start, f"protocol[{i}].until", False, mode)
        except ParameterError:
            if bound is None:
                raise
            got = (math.inf,)  # never met: the duration ends the step
        if isinstance(got, Pending):
            return got
        t_hit = max(got[0], start)  # met before the step: it ends at once
        by = "until"
        if bound is not None and t_hit - start > bound:
            t_hit, by = start + bound, "duration"
        durations[i] = max(t_hit - start, 0.0)
        done.append(UntilResult(i, prot.steps[i].text, start, t_hit,
                                None if tau_s is None else start * tau_s,
                                None if tau_s is None else t_hit * tau_s, by))
    return (prot.with_durations(durations) if durations else prot), done


def protocol_dose(req: DoseRequest, get: Getter, ranges: bool = False, mode: Mode = Mode(),
                  why: str = "") -> ProtocolDoseAnswer | Pending:
    """The dose under ``req.heating``: its until-steps resolved, then the time from the
    protocol's start at which the truth run reaches the dose radius (with its check run,
    and with ``ranges`` the interfacial-length range runs).  ``why``: why the full solver
    answers (the reduced model's verdict)."""
    resolved = resolve_untils(req, get, mode)
    if isinstance(resolved, Pending):
        return resolved
    prot, untils = resolved
    tau_s = _tau_seconds(req)
    pieces = prot.program(tau_s)
    target = radius_after_dose(req.start_radius, req.fraction)
    got = _reach(req, get, pieces, target, 0.0, "dose_fraction",
                 "range" if ranges else True, mode)
    if isinstance(got, Pending):
        return got
    time, traj, scs, trajs = got
    rep = _report(scs, trajs, req.start_radius, target)
    truth = Uncertainty.from_dict(rep.uncertainty)  # the report's is plain data
    unc = None if truth is None else truth.by_name()
    if unc is not None and mode.continuous:
        unc["model_form"] = heating_reduced.model_form_part(
            req, pieces, mode.mobility, target, float(rep.time or time))
    explain = (unc["numerical"].text if unc else
               "numerical: not measured (the check run failed)")
    out = Outcome("full", why or "the full solver answers protocol doses", unc, rep.error,
                  explain, rep.to_dict(), scs[0].key(), _program_text(req, scs, mode))
    return _answer(req, prot, untils, pieces, time, traj, out, tau_s)


@dataclass
class Outcome:
    """Which model answered and its error parts (the answer's model-specific fields)."""

    model: str
    why: str
    uncertainty: dict[str, Any] | None
    error: float | None
    explain: str
    validation: dict[str, Any] | None
    key: str
    program: str


def _program_text(req: DoseRequest, scs: list[Scenario], mode: Mode) -> str:
    if mode.continuous:
        return (f"continuous T(t) inside the solver's kernels (solver.heating.Program, "
                f"T_ref = {req.t_end:g} K), {MOBILITY_TEXT[mode.mobility]}; each run stops "
                "at its target radius (a terminal event)")
    return (f"ramps, baths and traces run as a staircase of holds, {STAIR_KELVIN:g} K "
            f"per stair, each at its stair's time-mean temperature "
            f"({len(scs[0].protocol)} steps with the tail; mobility held at T_ref: the "
            "stand-in solver takes no continuous program)")


def reduced_getter(req: DoseRequest) -> Getter:
    """Runs of the reduced model (solver.front.slow) in place of truth runs."""
    def get(scs: list[Scenario], target: float, after: float) -> list[Any]:
        from .program import solver_program

        prog = solver_program(scs[0].program)
        res = slow_front_trajectory(req.gel, req.t_start, prog, targets=(target,))
        hit = res.hits.get(float(target), math.nan)
        return [heating_reduced.ReducedRun(hit if math.isfinite(hit) else None, res.t,
                                           res.radius, float(res.t[-1]), res)]
    return get


def reduced_dose(req: DoseRequest, mode: Mode, choice: Verdict
                 ) -> ProtocolDoseAnswer:
    """The dose under ``req.heating`` from the reduced model (its until-steps by its own
    crossings), with its stated error as the model-form part."""
    get = reduced_getter(req)
    resolved = resolve_untils(req, get, mode)
    assert not isinstance(resolved, Pending)
    prot, untils = resolved
    tau_s = _tau_seconds(req)
    pieces = prot.program(tau_s)
    target = radius_after_dose(req.start_radius, req.fraction)
    got = _reach(req, get, pieces, target, 0.0, "dose_fraction", False, mode)
    assert not isinstance(got, Pending)
    time, traj, scs, _ = got
    stated = heating_reduced.STATED_ERROR
    unc: dict[str, Any] = {
        "numerical": Part(heating_reduced.NUMERICAL, (
            f"numerical: under {heating_reduced.NUMERICAL:.0e}: the compiled Dormand-Prince "
            "integration at rtol 1e-8 moves by under 1e-6 at rtol 1e-10, the thin-shell "
            "start and the tables by at most 2.4e-6 (tests/test_heating_slow.py)")),
        "interfacial_length_range": Part(None, (
            "interfacial length: not separate: the reduced model is the sharp-interface "
            "limit; the truth's dependence on the bead's own interfacial length is inside "
            "the model-form part, measured at 50 um")),
        "model_form": Part(stated, (
            f"model form: {stated:.0%}, the reduced model's largest measured gap to the "
            f"truth in its region ({heating_reduced.TABLE_TEXT})")),
    }
    program = (f"the reduced model's T(t) (solver.heating.Program, T_ref = {req.t_end:g} K), "
               f"{MOBILITY_TEXT[mode.mobility]}")
    out = Outcome(heating_reduced.MODEL, choice.why, unc, stated,
                  f"{stated:.0%}: the reduced model's largest measured gap to the truth in "
                  "its region", None, scs[0].key(), program)
    return _answer(req, prot, untils, pieces, time, traj, out, tau_s)


def lattice_scenario(req: DoseRequest, settings: Any, target: float) -> Scenario:
    """The protocol's run under ``settings`` (the delayed-law lattice of an answer's
    envelope): its until-steps ended where the reduced model ends them, its program
    continuous in T(t) with the truth's mobility, stopping at ``target``."""
    resolved = resolve_untils(req, reduced_getter(req))
    assert not isinstance(resolved, Pending)
    pieces = resolved[0].program(_tau_seconds(req))
    return Scenario(req.gel, req.t_start, branch=req.branch, settings=settings,
                    program=program_spec(pieces, Mode().mobility, req.t_end), stop=target)


def _report(scs: list[Scenario], trajs: list[Any], a0: float, target: float) -> Any:
    """The runs' report at the dose radius; a run stopped at it by its terminal event may
    end a rounding short of it (1e-7), so then the report reads the crossing of a radius
    1e-9 relatively short of the target (the time moves by ~1e-9 / |d ln a / dt|)."""
    try:
        return validation_report(scs, trajs, a0, target, None)
    except ValueError:
        near = target * (1.0 + math.copysign(1e-9, a0 - target))
        try:
            return validation_report(scs, trajs, a0, near, None)
        except ValueError:
            near = target * (1.0 + math.copysign(1e-6, a0 - target))
            return validation_report(scs, trajs, a0, near, None)


def temperature_curve(pieces: list[Piece], t_start: float, times: np.ndarray) -> np.ndarray:
    """T(t) of the program (tau) at ``times``; after the last piece, its end temperature."""
    out = np.full(times.shape, np.nan)
    t0, cur = 0.0, t_start
    for p in pieces:
        d = p.duration
        if d is None:
            d = math.inf
        sel = (times >= t0) & (times <= t0 + d) & np.isnan(out)
        out[sel] = p.temperature(times[sel] - t0)
        cur = float(p.temperature(np.array([d if math.isfinite(d) else 1e300]))[0])
        t0 += d
    out[np.isnan(out)] = cur
    return out


def _answer(req: DoseRequest, prot: Protocol, untils: list[UntilResult], pieces: list[Piece],
            time: float, traj: Any, out: Outcome, tau_s: float | None) -> ProtocolDoseAnswer:
    dry = req.bead_dry_radius_um
    a0 = req.start_radius
    target = radius_after_dose(a0, req.fraction)
    ts = timescale(dry, req.t_end, req.constants) if dry is not None else None
    stored = req.jump.stored_volume
    vol = expelled_volume(a0, target)
    t = np.asarray(traj.t, dtype=float)
    span = min(max(1.5 * time, sum(p.duration or 0.0 for p in pieces)), float(t[-1]))
    tc = np.union1d(np.linspace(0.0, span, CURVE_POINTS), [time])
    ac = np.interp(tc, t, np.asarray(traj.radius, dtype=float))
    released = released_fraction(a0, ac)
    temps = temperature_curve(pieces, prot.t_start, tc)
    curve = {"time": tc.tolist(), "temperature_k": temps.tolist(),
             "released_fraction": released.tolist(),
             "seconds": (tc * tau_s).tolist() if tau_s is not None else []}
    t_dose = float(temperature_curve(pieces, prot.t_start, np.array([time]))[0])
    model_text = (heating_reduced.MODEL_TEXT if out.model == heating_reduced.MODEL
                  else "the full solver")
    return ProtocolDoseAnswer(
        model=out.model, truth=truth_text(req), protocol=prot.texts,
        protocol_steps=[s.to_dict() for s in prot.steps], t_start=prot.t_start,
        reference_temperature=req.t_end, reference=reference_text(req.t_end),
        time=float(time), seconds=None if tau_s is None else float(time * tau_s),
        timescale_seconds=tau_s, timescale_formula=None if ts is None else ts.formula,
        program=out.program, dose_fraction=req.fraction, start_radius=a0,
        final_radius=target, final_radius_um=None if dry is None else target * dry,
        expelled_volume=vol, expelled_volume_ul=None if dry is None else volume_to_ul(vol, dry),
        stored_volume_ul=None if dry is None else volume_to_ul(stored, dry),
        temperature_at_dose=t_dose, until_steps=untils,
        error_estimate=out.error, error_explanation=out.explain, uncertainty=out.uncertainty,
        validation=out.validation, scenario_key=out.key,
        interfacial_length=req.settings.interfacial_length, bead_dry_radius_um=dry,
        curve=curve,
        note="the time is from the protocol's start; after the last step the bead holds at "
             "the last temperature",
        model_reason=f"{model_text}: {out.why}")


# ----------------------------------------------------------------------------- planners
def blocking_getter(planner: Any) -> Getter:
    """Runs (cached) on the planner, waiting for them."""
    def get(scs: list[Scenario], target: float, after: float) -> list[Any]:
        return planner._trajectories(scs, None, 0.0)
    return get


def queue_getter(planner: Any, fraction: float, start_radius: float) -> Getter:
    """Cached runs now, else the missing ones queued as one validation (``Pending``)."""
    def get(scs: list[Scenario], target: float, after: float) -> list[Any] | Pending:
        trajs: list[Any] = []
        for sc in scs:
            traj = planner.cached(sc)
            if traj is None and planner.jobs.state(sc.key()) == "failed":
                exc = planner.jobs.get(sc.key()).exception()
                traj = exc or SolverError("a full-solver run was cancelled")
            trajs.append(traj)
        if all(t is not None for t in trajs):
            return trajs
        keys = [sc.key() for sc in scs]
        vid = hashlib.sha256(json.dumps([keys, round(target, 12)]).encode()).hexdigest()[:24]
        # the poll reports the runs done; a run's own crossing is read when the dose is
        # asked again (its tail may fall short and be extended), so the record's target
        # is the start radius, which every run reaches at t = 0
        record = {"scenarios": [sc.to_dict() for sc in scs], "keys": keys,
                  "start_radius": start_radius, "target_radius": start_radius,
                  "fraction": fraction, "front_time": None, "kind": "protocol runs"}
        planner._advance(record, vid)
        if planner.cache.get_validation(vid) is None:
            planner.cache.put_validation(vid, record)
        return Pending(vid)
    return get


def _choice(planner: Any, req: DoseRequest, validate: bool, mode: Mode, model: str
            ) -> Verdict:
    if model not in ("auto", "full"):
        raise ParameterError("model", model, "'auto' or 'full'")
    if model == "full":
        return Verdict(False, "the full solver was asked for")
    if not mode.continuous:
        return Verdict(False, "the planner runs a stand-in solver (the "
                                      "reduced model answers on the real solver only)")
    pieces = req.heating.program(_tau_seconds(req))
    return heating_reduced.choose(req, pieces, validate)


def _reduced_or_why(planner: Any, req: DoseRequest, validate: bool, model: str
                    ) -> tuple[ProtocolDoseAnswer | None, Mode, str]:
    """(the reduced model's answer or None, the run mode, why the full solver answers):
    the reduced model inside its region; where it cannot answer (no front, a level that
    does not converge) the full solver, saying why."""
    mode = mode_for(planner, req)
    choice = _choice(planner, req, validate, mode, model)
    if not choice.applies:
        return None, mode, choice.why
    try:
        return reduced_dose(req, mode, choice), mode, ""
    except (NotApplicableError, SolverError) as exc:
        return None, mode, f"the reduced model could not answer ({exc})"


def dose(planner: Any, req: DoseRequest, validate: bool = False, model: str = "auto"
         ) -> ProtocolDoseAnswer:
    """The dose under a protocol: the reduced model inside its region (milliseconds), else
    blocking on the planner's full-solver runs (cached); ``model='full'`` always the full
    solver."""
    fast, mode, why = _reduced_or_why(planner, req, validate, model)
    if fast is not None:
        return fast
    out = protocol_dose(req, blocking_getter(planner), validate, mode, why)
    assert not isinstance(out, Pending)
    return out


def answer(planner: Any, req: DoseRequest, validate: bool = False, model: str = "auto"
           ) -> ProtocolDoseAnswer | Pending:
    """The dose under a protocol now: the reduced model inside its region, else from the
    cache, else Pending (its full-solver runs queued); ``model='full'`` as :func:`dose`."""
    fast, mode, why = _reduced_or_why(planner, req, validate, model)
    if fast is not None:
        return fast
    return protocol_dose(req, queue_getter(planner, req.fraction, req.start_radius),
                         validate, mode, why)
