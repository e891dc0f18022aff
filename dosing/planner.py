"""The dose planner: model choice, actuation times, validation against the full solver.

Procedure of sec. Application: a(0) is the equilibrium stretch at T_start (eq. EqlEqn);
a dose f of the stored fluid leaves a^3 = a0^3 - f (a0^3 - 1) (eq. FluidVolExpelled);
the answer is the time a(t) falls to that radius, times tau (eq. timescale) for seconds.
The front model answers in milliseconds where the jump classifier says "front"; the
full solver answers (blocking, cached) otherwise.  A validation runs the full solver on
both of its grids: in the front regime the paper's model is ill-posed and the two grids
disagree, so the error estimate includes their spread.
"""

from __future__ import annotations

import functools
import hashlib
import json
import math
import threading
from collections import OrderedDict
from concurrent.futures import Executor, Future, ThreadPoolExecutor, wait
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np

from solver.errors import NotApplicableError, SolverError
from solver.gel import Gel
from solver.phase import JumpClass, classify_jump

from .cache import ValidationCache
from .jobs import JobRunner
from .request import DoseRequest, ScheduleRequest
from .scenario import GRIDS, Scenario, Trajectory, run_scenario
from .units import (
    SYMBOLIC_FORMULA,
    expelled_volume,
    radius_after_dose,
    stored_volume,
    timescale,
    volume_to_ul,
)

DEFAULT_HORIZON = 1.0  # first simulated time of a jump (extended x4 when a dose needs more)
# Prior relative error |t_front - t_full| / t_front of an unvalidated front-model time, by
# dose fraction: the largest gap to either full-solver grid (N = 400) over ANB 302->308 K
# and HHT 304->308 K, rounded up (printed by `python -m dosing.calibrate`; the HHT
# Lagrangian grid dominates, and small doses are worst: the full model's shell takes time
# to form, the front model's starts at once).
PRIOR_FRACTIONS = (0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9)
PRIOR_GAPS = (4.4, 2.9, 2.2, 1.8, 1.5, 1.2, 1.0, 0.8, 0.6)
PRIOR_NOTE = "doses of 10-90 % for ANB 302->308 K and HHT 304->308 K"


def front_prior(fraction: float) -> float:
    """The prior error of a front-model time for a dose fraction (interpolated, clamped)."""
    return float(np.interp(fraction, PRIOR_FRACTIONS, PRIOR_GAPS))


class UnknownValidationError(KeyError):
    """A validation id this planner's cache has never seen."""


@functools.lru_cache(maxsize=256)
def jump_class(gel: Gel, t_start: float, t_end: float, branch: str) -> JumpClass:
    """The jump classifier's verdict (memoised)."""
    return classify_jump(gel, t_start, t_end, branch)


@functools.lru_cache(maxsize=256)
def choose_model(gel: Gel, t_start: float, t_end: float, branch: str) -> tuple[str, str]:
    """('front' | 'full', reason): the front model where the classifier says front."""
    jc = jump_class(gel, t_start, t_end, branch)
    if jc.behaviour != "front":
        return "full", f"this jump is '{jc.behaviour}' ({jc.reason}), not a front"
    from solver.front import front_applicability

    ok, reason = front_applicability(gel, t_start, t_end, branch)
    return ("front" if ok else "full"), reason


@functools.lru_cache(maxsize=256)
def front_run(gel: Gel, t_start: float, t_end: float, branch: str, correction: bool) -> Any:
    """The front model's whole trajectory from the initial equilibrium (memoised)."""
    from solver.front import front_trajectory

    return front_trajectory(gel, t_start, t_end, branch=branch, correction=correction)


@dataclass
class DoseAnswer:
    """How long to heat: dimensionless and in seconds, with the model and its error."""

    model: str
    time: float
    seconds: float | None
    timescale_seconds: float | None
    timescale_formula: str
    start_radius: float
    final_radius: float
    final_radius_um: float | None
    expelled_volume: float
    expelled_volume_ul: float | None
    stored_volume: float
    stored_volume_ul: float | None
    dose_fraction: float
    error_estimate: float
    error_explanation: str
    validation: dict[str, Any] | None
    scenario_key: str
    behaviour: str
    note: str

    def to_dict(self) -> dict[str, Any]:
        """Plain-data form (JSON-ready)."""
        return asdict(self)


@dataclass
class ValidationStatus:
    """A validation's state; ``result`` when done, ``error`` when failed."""

    id: str
    status: str
    result: dict[str, Any] | None = None
    error: str | None = None

    def to_dict(self) -> dict[str, Any]:
        """Plain-data form."""
        return asdict(self)


def _rel(a: float, b: float) -> float:
    return abs(a - b) / abs(b)


class Planner:
    """Plans doses and schedules; keeps full-solver validations in a persistent cache.

    ``executor`` is any ``concurrent.futures.Executor`` (default: a process pool); full
    solver runs are deduplicated by scenario key and at most ``max_pending`` are queued.
    """

    def __init__(self, cache_path: str | None = None, executor: Executor | None = None,
                 max_pending: int = 64, front_correction: bool = False,
                 horizon: float = DEFAULT_HORIZON) -> None:
        self.cache = ValidationCache(cache_path)
        self.jobs = JobRunner(executor, max_pending)
        self.front_correction = bool(front_correction)
        self.horizon = float(horizon)
        self._mem: OrderedDict[str, Trajectory] = OrderedDict()
        self._mem_lock = threading.Lock()

    # ------------------------------------------------------------------ trajectories
    def scenarios(self, req: DoseRequest | ScheduleRequest) -> list[Scenario]:
        """The jump's validation scenarios: the truth grid first, then the other grid."""
        grids = [req.settings.grid] + [g for g in GRIDS if g != req.settings.grid]
        return [Scenario(req.gel, req.t_start, req.t_end, branch=req.branch,
                         settings=req.settings.on_grid(g)) for g in grids]

    def cached(self, sc: Scenario, need_radius: float | None = None,
               need_time: float = 0.0) -> Trajectory | None:
        """The stored trajectory if it covers the need (no computation), else None."""
        key = sc.key()
        with self._mem_lock:
            traj = self._mem.get(key)
        if traj is None or not _covers(traj, sc, need_radius, need_time):
            traj = self.cache.get(key)
            if traj is None:
                return None
            with self._mem_lock:
                self._mem[key] = traj
                self._mem.move_to_end(key)
                while len(self._mem) > 64:
                    self._mem.popitem(last=False)
        return traj if _covers(traj, sc, need_radius, need_time) else None

    def _store(self, fut: Future) -> None:
        meta, blob = fut.result()
        self.cache.put_if_longer(meta["key"], meta, blob)

    def submit(self, sc: Scenario, need_radius: float | None = None,
               need_time: float = 0.0) -> Future:
        """Queue the full-solver run for ``sc`` (deduplicated by key); returns its future."""
        meta = self.cache.meta(sc.key())
        horizon = self.horizon if meta is None else 4.0 * float(meta.get("horizon", 0.0))
        return self.jobs.submit(sc.key(), run_scenario, sc.to_dict(), max(horizon, self.horizon),
                                need_radius, need_time, on_done=self._store)

    def trajectory(self, sc: Scenario, need_radius: float | None = None,
                   need_time: float = 0.0) -> Trajectory:
        """The full-solver trajectory for ``sc`` covering the need (blocking, cached)."""
        for _ in range(6):
            traj = self.cached(sc, need_radius, need_time)
            if traj is not None:
                return traj
            meta, blob = self.submit(sc, need_radius, need_time).result()
            traj = Trajectory.from_npz(blob, meta)
            if _covers(traj, sc, need_radius, need_time):
                return traj
        raise SolverError("the full-solver run does not cover the dose", {"key": sc.key()})

    def _trajectories(self, scs: list[Scenario], need_radius: float,
                      need_time: float) -> dict[str, Trajectory | Exception]:
        """Both grids' trajectories, run concurrently; a failure is returned, not raised."""
        with ThreadPoolExecutor(len(scs)) as pool:
            futs = {sc.settings.grid: pool.submit(self.trajectory, sc, need_radius, need_time)
                    for sc in scs}
            wait(list(futs.values()))
        return {g: (f.exception() or f.result()) for g, f in futs.items()}

    # ------------------------------------------------------------------ doses
    def _front_time(self, req: DoseRequest, radius: float) -> float:
        fr = front_run(req.gel, req.t_start, req.t_end, req.branch, self.front_correction)
        return float(fr.time_to_radius(radius))

    def _model_answer(self, req: DoseRequest) -> tuple[float, str, str, float | None]:
        """(target radius, model, why, front-model time or None) for a dose request: the
        front model where the classifier allows and it reaches the dose, else the full one."""
        radius = radius_after_dose(req.start_radius, req.fraction)
        model, why = choose_model(req.gel, req.t_start, req.t_end, req.branch)
        t_front = None
        if model == "front":
            try:
                t_front = self._front_time(req, radius)
            except (ValueError, NotApplicableError, SolverError) as exc:
                model, why = "full", f"the front model cannot give this dose ({exc})"
        return radius, model, why, t_front

    def dose(self, req: DoseRequest, validate: bool = False) -> DoseAnswer:
        """The actuation time for one dose (front model, or the full solver where needed)."""
        a0, f = req.start_radius, req.fraction
        radius, model, why, t_front = self._model_answer(req)
        scs = self.scenarios(req)
        need_time = 0.0 if t_front is None else t_front
        if model == "full" or validate:
            trajs: dict[str, Any] = self._trajectories(scs, radius, need_time)
            truth = trajs[scs[0].settings.grid]
            if isinstance(truth, Exception):
                raise truth
        else:
            trajs = {sc.settings.grid: self.cached(sc, radius, need_time) for sc in scs}
            if any(t is None for t in trajs.values()):
                trajs = {}
        time = t_front if model == "front" else trajs[scs[0].settings.grid].time_to_radius(radius)
        validation = (validation_report(scs, trajs, a0, radius, t_front) if trajs else None)
        est, explain = error_estimate(model, time, validation, scs[0], f)
        return self._answer(req, model, time, radius, est, explain, validation, scs[0].key(),
                            why)

    def _answer(self, req: DoseRequest, model: str, time: float, radius: float, est: float,
                explain: str, validation: dict[str, Any] | None, key: str,
                why: str) -> DoseAnswer:
        a0 = req.start_radius
        dry = req.bead_dry_radius_um
        tau = timescale(dry, req.t_end, req.constants) if dry is not None else None
        dv, sv = expelled_volume(a0, radius), stored_volume(a0)
        behaviour = jump_class(req.gel, req.t_start, req.t_end, req.branch).behaviour
        note = (f"{'front model' if model == 'front' else 'full solver'}: {why}. "
                + ("front model started from the initial equilibrium alone. "
                   if model == "front" else "")
                + ("" if validation else "No full-solver validation yet for this scenario.")
                + "".join(f" The full solver on the {g} grid reports: {e['warning']}."
                          for g, e in (validation or {}).get("grids", {}).items()
                          if e.get("warning"))
                + ("" if dry else " Give a bead size (dry_radius_um or swollen_radius_um) "
                   "for seconds and microlitres."))
        return DoseAnswer(
            model=model, time=float(time),
            seconds=None if tau is None else float(time) * tau.seconds,
            timescale_seconds=None if tau is None else tau.seconds,
            timescale_formula=SYMBOLIC_FORMULA if tau is None else tau.formula,
            start_radius=a0, final_radius=radius,
            final_radius_um=None if dry is None else radius * dry,
            expelled_volume=dv, expelled_volume_ul=None if dry is None else volume_to_ul(dv, dry),
            stored_volume=sv, stored_volume_ul=None if dry is None else volume_to_ul(sv, dry),
            dose_fraction=req.fraction, error_estimate=est, error_explanation=explain,
            validation=validation, scenario_key=key, behaviour=behaviour, note=note.strip())

    # ------------------------------------------------------------------ validations
    def submit_validation(self, req: DoseRequest) -> str:
        """Queue the full-solver check of this dose on both grids; returns an id at once."""
        a0, f = req.start_radius, req.fraction
        radius, _, _, t_front = self._model_answer(req)
        scs = self.scenarios(req)
        keys = [sc.key() for sc in scs]
        vid = hashlib.sha256(json.dumps([keys, round(f, 12)]).encode()).hexdigest()[:24]
        record = {"scenarios": [sc.to_dict() for sc in scs], "keys": keys, "start_radius": a0,
                  "target_radius": radius, "fraction": f, "front_time": t_front}
        if self.cache.get_validation(vid) is None:
            self.cache.put_validation(vid, record)
        self._advance(record)
        return vid

    def _advance(self, record: dict[str, Any]) -> tuple[dict[str, Any], list[str]]:
        """Per grid: a covering trajectory, an exception, or the job state (submitting)."""
        need_r, need_t = record["target_radius"], record["front_time"] or 0.0
        out: dict[str, Any] = {}
        states = []
        for scd in record["scenarios"]:
            sc = Scenario.from_dict(scd)
            grid = sc.settings.grid
            traj = self.cached(sc, need_r, need_t)
            if traj is not None:
                out[grid] = traj
                continue
            fut = self.jobs.get(sc.key())
            state = self.jobs.state(sc.key())
            if state == "failed":
                out[grid] = fut.exception() or RuntimeError("cancelled")
                continue
            if state in ("pending", "running"):
                states.append(state)
                continue
            self.submit(sc, need_r, need_t)  # never run here, or finished short of the dose
            states.append(self.jobs.state(sc.key()) or "pending")
        return out, states

    def validation(self, vid: str) -> ValidationStatus:
        """The state of a validation (its result when done); unknown ids raise KeyError."""
        record = self.cache.get_validation(vid)
        if record is None:
            raise UnknownValidationError(vid)
        trajs, states = self._advance(record)
        if states:
            return ValidationStatus(vid, "running" if "running" in states else "pending")
        scs = [Scenario.from_dict(d) for d in record["scenarios"]]
        truth = trajs[scs[0].settings.grid]
        if isinstance(truth, Exception):
            return ValidationStatus(vid, "failed", error=f"{type(truth).__name__}: {truth}")
        rep = validation_report(scs, trajs, record["start_radius"], record["target_radius"],
                                record["front_time"])
        return ValidationStatus(vid, "done", result=rep)

    # ------------------------------------------------------------------ schedules
    def schedule(self, req: ScheduleRequest) -> Any:
        """Plan a multi-dose schedule (hold assumption, protocol check, shooting)."""
        from .schedule import plan_schedule_with

        return plan_schedule_with(self, req)

    def close(self) -> None:
        """Shut down an owned executor and close the cache."""
        self.jobs.shutdown(wait=False)
        self.cache.close()

    def __enter__(self) -> Planner:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def _covers(traj: Trajectory, sc: Scenario, need_radius: float | None, need_time: float) -> bool:
    if sc.protocol is not None:
        return True
    if need_radius is not None and traj.radius.min() > need_radius:
        return False
    return traj.horizon >= need_time


def validation_report(scs: list[Scenario], trajs: dict[str, Any], start_radius: float,
                      radius: float, t_front: float | None) -> dict[str, Any]:
    """The full solver's time for the dose on each grid, and the front model's errors.

    The volume error is what the full solver expels by the front model's time, against
    the dose: (V_full(t_front) - V) / V.
    """
    target = expelled_volume(start_radius, radius)
    grids: dict[str, Any] = {}
    for sc in scs:
        g, traj = sc.settings.grid, trajs.get(sc.settings.grid)
        entry: dict[str, Any] = {"n": sc.settings.n, "scenario_key": sc.key()}
        if isinstance(traj, Trajectory):
            entry["time"] = traj.time_to_radius(radius)
            entry["wall_seconds"] = traj.meta.get("wall_seconds")
            diag = traj.meta.get("diagnostics", {})
            if diag.get("spinodal"):
                entry["warning"] = diag.get("message") or "spinodal collapse (not converged)"
            if t_front is not None:
                got = expelled_volume(start_radius, traj.radius_at(t_front))
                entry["front_time_error"] = (t_front - entry["time"]) / entry["time"]
                entry["front_volume_error"] = (got - target) / target
        else:
            entry["error"] = f"{type(traj).__name__}: {traj}"
        grids[g] = entry
    first = grids[scs[0].settings.grid]
    times = [e["time"] for e in grids.values() if "time" in e]
    spread = (max(times) - min(times)) / first["time"] if len(times) > 1 and "time" in first \
        else None
    rep: dict[str, Any] = {
        "time": first.get("time"), "truth_grid": scs[0].settings.grid,
        "settings": scs[0].settings.to_dict(), "grids": grids, "grid_spread": spread,
        "front_time": t_front,
        "front_time_error": first.get("front_time_error"),
        "front_volume_error": first.get("front_volume_error")}
    return rep


def _pct(x: float) -> str:
    return f"{100 * x:.2g}%" if x < 0.1 else f"{100 * x:.0f}%"


def error_estimate(model: str, time: float, validation: dict[str, Any] | None,
                   truth: Scenario, fraction: float) -> tuple[float, str]:
    """(relative error of the answer's time, the reason in plain words)."""
    s = truth.settings
    if validation is None:
        prior = front_prior(fraction)
        return prior, (
            f"Not yet checked against the full solver for this scenario (ask for a "
            f"validation). For {PRIOR_NOTE}, the front model's time was within "
            f"{_pct(prior)} of the full model's answers on both of its grids at this dose "
            f"(small doses are worst: in the full model the shrunken shell takes time to "
            f"form). Much of that gap is the full model's own uncertainty in this regime: "
            "without an interfacial energy the speed of a sharp front is not fixed by the "
            "model, and different discretizations pick different speeds.")
    times = {g: e["time"] for g, e in validation["grids"].items() if "time" in e}
    failed = [g for g, e in validation["grids"].items() if "error" in e]
    gaps = [_rel(t, time) for t in times.values()]  # relative to the answer's time
    spread = validation["grid_spread"]
    lo, hi = min([time, *times.values()]), max([time, *times.values()])
    if model == "front":
        est = max(gaps)
        listing = ", ".join(f"{t:.4g} on the {g} grid" for g, t in times.items())
        text = (f"The front model (a fast reduced model) gives {time:.4g}; the full model gives "
                f"{listing} (N = {s.n}). ")
    else:
        est = max([s.rtol, *gaps])
        listing = ", ".join(f"{t:.6g} on the {g} grid" for g, t in times.items()
                            if g != s.grid) or "no answer"
        text = (f"Answered by the full solver: {time:.6g} on the {s.grid} grid (N = {s.n}); "
                f"its second, independent discretization gives {listing}. ")
    if spread is not None and spread > 0.01:
        text += (f"The two grids disagree by {_pct(spread)}: here a sharp front forms and the "
                 "paper's model, which has no interfacial energy, does not fix its speed, so "
                 "each discretization picks its own. ")
    elif spread is not None:
        text += f"The two grids agree to {_pct(max(spread, 1e-6))}. "
    if failed:
        text += f"The {', '.join(failed)} grid failed to run, so it is not in the estimate. "
    text += (f"The estimate ({_pct(est)}) is the largest gap between this answer and the full "
             f"model's answers; treat the true time as somewhere between {lo:.4g} and "
             f"{hi:.4g}.")
    if math.isnan(est):
        est = front_prior(fraction)
    return est, text
