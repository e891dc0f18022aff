"""Which model answers a dose, and the answer it makes: the jump classifier's verdict, the
front model where it applies (its whole trajectory memoised per jump), else the full solver;
:func:`build_answer` turns a model's time into a DoseAnswer (radii, volumes, seconds, truth).
A leaf below the planner (imports no planner module), so the planner, fits, sweeps and the
page share one model choice without import cycles (docs/architecture.md, dosing/)."""

from __future__ import annotations

import functools
from typing import Any

from solver.errors import NotApplicableError, SolverError
from solver.front import front_applicability, front_trajectory
from solver.front.sharp import sharp_front_trajectory
from solver.gel import Gel
from solver.phase import JumpClass, classify_jump

from .answers import DoseAnswer, ModelChoice, ValidationReport
from .request import DoseRequest
from .runs.scenario import Scenario, SolverSettings
from .truth import Uncertainty, truth_text
from .units import (
    SYMBOLIC_FORMULA,
    expelled_volume,
    radius_after_dose,
    stored_volume,
    timescale,
    volume_to_ul,
)
from .validation import error_estimate


def jump_class(gel: Gel, t_start: float, t_end: float, branch: str) -> JumpClass:
    """The jump classifier's verdict (memoised in ``solver.phase``)."""
    return classify_jump(gel, t_start, t_end, branch)


def choose_model(gel: Gel, t_start: float, t_end: float, branch: str) -> tuple[str, str]:
    """('front' | 'full', reason): the front model where the classifier says front."""
    return _choose(jump_class(gel, t_start, t_end, branch), gel, t_start, t_end, branch)


def _choose(jc: JumpClass, gel: Gel, t_start: float, t_end: float,
            branch: str) -> tuple[str, str]:
    if jc.behaviour != "front":
        return "full", f"this jump is '{jc.behaviour}' ({jc.reason}), not a front"
    ok, reason = front_applicability(gel, t_start, t_end, branch)
    return ("front" if ok else "full"), reason


@functools.lru_cache(maxsize=256)
def front_run(gel: Gel, t_start: float, t_end: float, branch: str, sharp: bool) -> Any:
    """The front model's whole trajectory from the initial equilibrium (memoised: one
    trajectory serves every dose and bead size of a jump, in sweeps, fits and the page):
    the sharp-interface model for the regularized truth, the paper's for the paper's."""
    if sharp:
        return sharp_front_trajectory(gel, t_start, t_end, branch=branch)
    return front_trajectory(gel, t_start, t_end, branch=branch)


MODEL_NAMES = {"front": "the paper's step-function front model",
               "front-sharp": "the step-function front model with the sharp-interface front "
                              "condition (docs/interfacial.md, sec. 8)",
               "full": "the full solver"}


def front_model_name(settings: SolverSettings) -> str:
    """'front-sharp' for the regularized truth, 'front' (the paper's) otherwise."""
    return "front-sharp" if settings.regularized else "front"


def front_time(req: DoseRequest, radius: float) -> float:
    """The front model's time to ``radius`` (raises where it does not apply)."""
    fr = front_run(req.gel, req.t_start, req.t_end, req.branch, req.settings.regularized)
    return float(fr.time_to_radius(radius))


def model_answer(req: DoseRequest) -> ModelChoice:
    """The model for a dose request: the front model where the classifier allows and it
    reaches the dose (its time with it), else the full solver."""
    radius = radius_after_dose(req.start_radius, req.fraction)
    jc = jump_class(req.gel, req.t_start, req.t_end, req.branch)
    model, why = _choose(jc, req.gel, req.t_start, req.t_end, req.branch)
    t_front = None
    if model == "front":
        model = front_model_name(req.settings)
        try:
            t_front = front_time(req, radius)
        except (ValueError, NotApplicableError, SolverError) as exc:
            model, why = "full", f"the front model cannot give this dose ({exc})"
    return ModelChoice(radius, model, why, t_front, jc.behaviour)


def build_answer(req: DoseRequest, choice: ModelChoice, time: float, est: float, explain: str,
                 validation: ValidationReport | None, key: str) -> DoseAnswer:
    """The answer from the model's time: radii, volumes, seconds, the truth and a note."""
    a0, radius, model = req.start_radius, choice.radius, choice.model
    dry = req.bead_dry_radius_um
    tau = timescale(dry, req.t_end, req.constants) if dry is not None else None
    dv, sv = expelled_volume(a0, radius), stored_volume(a0)
    s = req.settings
    truth = truth_text(req)
    note = (f"{MODEL_NAMES[model]}: {choice.why}. "
            + ("Started from the initial equilibrium alone. " if model != "full" else "")
            + f"Truth: {truth}. "
            + ("" if validation else "No full-solver validation yet for this scenario.")
            + "".join(f" The full solver ({e['grid']} grid, N = {e['n']}, ell = "
                      f"{e['interfacial_length']:g}) reports: {e['warning']}."
                      for e in (validation.runs if validation else []) if e.get("warning"))
            + ("" if dry else " Give a bead size (dry_radius_um or swollen_radius_um) "
               "for seconds and microlitres."))
    return DoseAnswer(
        model=model, interfacial_length=s.interfacial_length, truth=truth,
        time=float(time),
        seconds=None if tau is None else float(time) * tau.seconds,
        timescale_seconds=None if tau is None else tau.seconds,
        timescale_formula=SYMBOLIC_FORMULA if tau is None else tau.formula,
        start_radius=a0, final_radius=radius,
        final_radius_um=None if dry is None else radius * dry,
        expelled_volume=dv, expelled_volume_ul=None if dry is None else volume_to_ul(dv, dry),
        stored_volume=sv, stored_volume_ul=None if dry is None else volume_to_ul(sv, dry),
        dose_fraction=req.fraction, error_estimate=est, error_explanation=explain,
        validation=validation, scenario_key=key, behaviour=choice.behaviour,
        note=note.strip(), method=s.method if s.regularized else "paper",
        bead_dry_radius_um=dry,
        uncertainty=Uncertainty.from_dict(validation.uncertainty if validation else None))


def front_answer(req: DoseRequest) -> DoseAnswer:
    """The front model's answer alone, with its prior error estimate: no cache and no full
    solver (a sweep point).  NotApplicableError where only the full solver answers."""
    choice = model_answer(req)
    if choice.front_time is None:
        raise NotApplicableError(f"needs the full solver: {choice.why}")
    est, explain = error_estimate(choice.model, choice.front_time, None, req.fraction, req.gel,
                                  req.settings.method)
    # the truth run's key (request_scenarios(req)[0]: every method's first rung is the
    # settings themselves), without building the other runs
    truth = Scenario(req.gel, req.t_start, req.t_end, branch=req.branch, settings=req.settings)
    return build_answer(req, choice, choice.front_time, est, explain, None, truth.key())
