"""A dose of drug (not of fluid): the actuation time that releases a drug mass.

The bead, loaded uniformly in equilibrium at T_start, may sit in the release medium at
T_start for ``wait`` before heating (it leaks by diffusion meanwhile), then is heated at
T_end until the drug released during the heating reaches the dose.  Without diffusion
(D0 = 0) a single heating of a uniformly loaded bead releases drug in proportion to
fluid, exactly (every expelled parcel carries the loaded concentration), so the planner's
fluid answer is the drug answer (the reduced model, milliseconds).  With diffusion the
reduced drug model answers where its measured error holds (``dosing.payload.reduced``:
the drug on the front model's bead, milliseconds), else, or when asked to ``validate``,
the full solver (a drug run, cached).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field, replace
from typing import Any, ClassVar

import numpy as np

from solver.errors import ParameterError, SolverError, require_finite_positive
from solver.limits import DRUG_STEP_MAX

from ..fits.release_steps import parse_protocol, squeezed_under
from ..question.shooting import READ_OFF_FLOOR, Reach, Short, read_off, windows
from ..request import Case, _resolve_protocol, at_start, resolve_case
from ..runs.mechanics import protocol_mechanics
from ..runs.scenario import SolverSettings, Step
from ..runs.solute import DrugRuns, DrugScenario, drug_settings, runs_for
from ..truth import Part, Uncertainty, truth_text
from ..units import timescale, volume_to_ul
from .drug import DrugModel, StatedTruth, carried_by_fluid, leak_time

MAX_HORIZON = DRUG_STEP_MAX  # tau: one simulate step holds at most 100000 samples
FIRST_HEATING = 0.5  # tau: the first drug run's heating (read_off grows it x GROWTH)
# under heating steps (the section below)
STEPS_MODEL = "full+solute"
STEPS_FIRST_HORIZON = 1e-3  # tau: the first run's horizon, x GROWTH while the dose is short,
GROWTH = 4.0  # so the dose falls in the last 3/4 of its run's samples (>= 150 before it)
SPLIT = ("Squeezed out: the release of the same mechanics with D0 = 0 (the fluid's motion "
         "alone, sieved by the mesh); diffused: the rest (the extra release diffusion makes).")


def resolve_drug_amount(name_fraction: str, fraction: float | None, name_mass: str,
                        mass: float | None, load_ug: float | None) -> float:
    """A dose as a fraction of the load: given, or a drug mass over the load; 0 < f < 1."""
    if (fraction is None) == (mass is None):
        raise ParameterError(name_fraction, fraction,
                             f"exactly one of {name_fraction} (of the load) or {name_mass}")
    if mass is not None:
        m = require_finite_positive(name_mass, mass)
        if load_ug is None:
            raise ParameterError("drug.load_ug", None, f"a finite number > 0 (ug per bead; or "
                                 f"drug.loading_concentration_ug_per_ul with a bead size) to "
                                 f"turn {name_mass} into a fraction of the load")
        if not m < load_ug:
            raise ParameterError(name_mass, mass, f"0 < {name_mass} < {load_ug:.4g} ug",
                                 "the dose must be smaller than the drug loaded in the bead")
        return m / load_ug
    f = require_finite_positive(name_fraction, fraction)
    if not f < 1.0:
        raise ParameterError(name_fraction, fraction, "0 < fraction < 1 of the loaded drug",
                             "the dose must be smaller than the drug loaded in the bead")
    return f


@dataclass(frozen=True)
class DrugCase(Case):
    """A case with a drug as its payload: ``drug`` (a DrugModel or a dict of its fields)
    dissolved in the pore fluid, ``wait`` (tau) or ``wait_seconds`` in the medium at T_start
    before the first heating.  Resolved: the load in ug (None when unknown) and the wait in
    tau (``lead``).  Drug dose and schedule requests compose it as fluid ones compose Case."""

    drug: DrugModel | dict[str, Any] | None = None
    wait: float | None = field(default=None, kw_only=True)
    wait_seconds: float | None = field(default=None, kw_only=True)
    load_ug: float | None = field(init=False, repr=False, compare=False)
    lead: float = field(init=False, repr=False, compare=False)
    rest_max: ClassVar[float] = DRUG_STEP_MAX  # tau: a drug run's step (solver.limits)

    def resolve_drug(self) -> float | None:
        """Resolve the case, the drug, its load and the wait (in place); the dry radius."""
        jump, dry = resolve_case(self)
        if self.drug is None:
            raise ParameterError("drug", None, "a DrugModel or a dict of its fields")
        drug = DrugModel.from_any(self.drug)
        object.__setattr__(self, "drug", drug)
        stored_ul = None if dry is None else volume_to_ul(jump.stored_volume, dry)
        object.__setattr__(self, "load_ug", drug.load(stored_ul, jump.start_radius,
                                                      self.constants))
        object.__setattr__(self, "lead", at_start("wait", self.wait, self.wait_seconds, dry,
                                                  self.t_end, self.constants,
                                                  self.rest_max) or 0.0)
        return dry

    @property
    def solute(self) -> Any:
        """The dimensionless solute of this request (validates the release volume)."""
        return self.drug.solute(self.start_radius, self.t_end, self.constants,
                                self.bead_dry_radius_um)


@dataclass(frozen=True)
class DrugDoseRequest(DrugCase):
    """One drug dose: ``dose_fraction`` of the loaded drug, or ``drug_mass_ug`` (needs the
    load); the :class:`DrugCase` fields (the wait) and the :class:`Case` fields."""

    dose_fraction: float | None = None
    drug_mass_ug: float | None = None
    fraction: float = field(init=False, repr=False, compare=False)
    # a heating protocol in place of t_end (dosing.heating.grammar; the dose: answer_fields)
    protocol: Any = field(default=None, kw_only=True)
    heating: Any = field(init=False, repr=False, compare=False, default=None)

    def __post_init__(self) -> None:
        _resolve_protocol(self)
        self.resolve_drug()
        if self.heating is not None:  # refused at once, naming the field (no job for it)
            check_protocol(self)
        object.__setattr__(self, "fraction", resolve_drug_amount(
            "dose_fraction", self.dose_fraction, "drug_mass_ug", self.drug_mass_ug,
            self.load_ug))
        self.solute  # noqa: B018 - validates the release volume against the bead


class DrugHeatings:
    """A drug case's heatings (:class:`dosing.question.shooting.Heatings`): the wait at T_start,
    then heat at T_end / rest at T_start; ``targets`` fractions of the loaded drug; each run the
    full solver with the drug on its cells (cached by ``runs``, counted)."""

    max_horizon = MAX_HORIZON

    def __init__(self, req: DrugCase, runs: DrugRuns, targets: Sequence[float],
                 settings: SolverSettings | None = None) -> None:
        self.req, self.runs, self.targets = req, runs, tuple(targets)
        self.tolerance = float(getattr(req, "tolerance", 0.0))
        self.rests = tuple(getattr(req, "rests", None) or ())
        self.settings = settings or drug_settings(req.settings)
        self.solute = req.solute
        self.count = 0
        dry = req.bead_dry_radius_um
        self.tau_s = None if dry is None else timescale(dry, req.t_end, req.constants).seconds

    def steps(self, durations: Sequence[float]) -> tuple[Step, ...]:
        """The protocol's (duration, temperature) steps, the wait first; each heating a jump
        to T_end, or a schedule's heating protocol (its staircase:
        ``dosing.heating.cycles.cycle_steps``)."""
        from ..heating.cycles import cycle_steps

        r = self.req
        lead = ((r.lead, r.t_start),) if r.lead > 0.0 else ()
        return (*lead, *cycle_steps(r, durations, self.rests, self.tau_s))

    def scenario(self, durations: Sequence[float]) -> DrugScenario:
        """The drug run of these actuation times."""
        r = self.req
        return DrugScenario(r.gel, r.t_start, self.steps(durations), self.solute, r.branch,
                            self.settings)

    def run(self, durations: Sequence[float]) -> Any:
        """The drug run (a ReleaseResult) of these actuation times."""
        self.count += 1
        return self.runs.run(self.scenario(durations))

    def windows(self, durations: Sequence[float]) -> list[tuple[float, float]]:
        """(start, end) of each heating, after the wait."""
        return [(a + self.req.lead, b + self.req.lead) for a, b in windows(durations,
                                                                            self.rests)]

    def delivered(self, rel: Any, durations: Sequence[float]) -> list[float]:
        """The drug each heating releases, fractions of the load."""
        return [rel.released_at(e) - rel.released_at(s) for s, e in self.windows(durations)]

    def released_within(self, rel: Any, durations: Sequence[float], k: int,
                        x: float) -> float:
        """What heating k has released ``x`` after its start, fractions of the load."""
        start = self.windows(durations)[k][0]
        return rel.released_at(start + x) - rel.released_at(start)

    def reach(self, rel: Any, durations: Sequence[float], k: int) -> Reach:
        """Where heating k releases dose k; else the most it releases and its late part (a
        drug the collapsed shell holds releases ever more slowly)."""
        start = self.windows(durations)[k][0]
        try:
            return Reach(rel.time_to_release(self.targets[k], after=start) - start)
        except ValueError:
            end = float(rel.released_fraction[-1])
            return Reach(None, end - rel.released_at(start),
                         end - rel.released_at(start + durations[k] / 2.0))


def first_heating(req: DrugCase, fraction: float | None = None) -> tuple[float, float]:
    """(guess, floor) of the read-off heating of a drug dose, ``fraction`` of the load
    (default the request's; :func:`dosing.question.shooting.read_off` runs to twice the guess, at
    least guess + floor): the reduced drug model's time to the dose (the drug on the
    front model's bead, milliseconds; a guess wherever it runs, its measured error
    aside), so the full solver's drug run stops soon after the dose instead
    of running to FIRST_HEATING (24x past an ANB 50 % dose of a 1e-7 cm^2/s drug); else
    (a wait first, no front regime, not reached) FIRST_HEATING."""
    if req.lead == 0.0:
        from solver.errors import SolverError

        from ..model_choice import choose_model
        from .reduced import reduced_release

        try:
            if choose_model(req.gel, req.t_start, req.t_end, req.branch)[0] == "front":
                return float(reduced_release(req, fraction)[1]), 0.0
        except (ValueError, SolverError):
            pass
    return FIRST_HEATING / 2.0, READ_OFF_FLOOR


@dataclass
class DrugDoseAnswer(StatedTruth):
    """How long to heat for a drug dose, what leaked before, and how it came out."""

    model: str
    time: float
    seconds: float | None
    dose_fraction: float
    dose_ug: float | None
    load_ug: float | None
    wait: float
    leaked_before_heating: float
    leaked_before_heating_ug: float | None
    leak_time_10pct: float
    leak_time_10pct_seconds: float | None
    squeezed_fraction: float
    diffused_fraction: float
    mechanism: str
    fluid_fraction: float
    medium_concentration_ug_per_ul: float | None
    effective_diffusivity_cm2_s: float
    drug_diffusivity_cm2_s: float
    mass_balance_error: float
    timescale_seconds: float | None
    fluid_answer: dict[str, Any] | None
    scenario_key: str | None
    note: str
    uncertainty: Uncertainty | None = None
    peclet: float | None = None
    split: str = ""
    mesh: str = ""
    permeability_law: str = "none: k0 independent of temperature at fixed porosity"
    protocol: Any = None  # under a heating protocol: ProtocolDrugDose


def mechanism(squeezed: float, diffused: float) -> str:
    """'squeezed out' or 'diffused' (the larger share), with the split in words; squeezed is
    the D0 = 0 twin's release, so ``diffused`` < 0 when diffusion holds drug back."""
    total = squeezed + diffused
    if total <= 0.0:
        return "none"
    if diffused < 0.0:
        return (f"squeezed out (the fluid's motion alone would release {squeezed / total:.0%} "
                f"of it; back-diffusion into the core holds {-diffused / total:.0%} back)")
    share = squeezed / total
    return (f"squeezed out ({share:.0%} with the expelled fluid)" if share >= 0.5
            else f"diffused ({1 - share:.0%} by diffusion through the edge)")


def _reduced_answer(req: DrugDoseRequest, red: Any, model: str,
                    common: dict[str, Any]) -> DrugDoseAnswer:
    """The drug answer of the reduced drug model's dose (``dosing.payload.reduced.ReducedDose``)."""
    tau = common["timescale_seconds"]
    pe = red.peclet
    return DrugDoseAnswer(
        model=model, time=red.time, seconds=None if tau is None else red.time * tau,
        leaked_before_heating=0.0, leaked_before_heating_ug=0.0 if common["load_ug"]
        is not None else None, squeezed_fraction=red.squeezed,
        diffused_fraction=req.fraction - red.squeezed,
        mechanism=mechanism(red.squeezed, req.fraction - red.squeezed),
        fluid_fraction=red.fluid_fraction,
        medium_concentration_ug_per_ul=_conc(req, req.fraction, red.radius),
        mass_balance_error=red.mass_balance_error, fluid_answer=None, scenario_key=None,
        uncertainty=red.uncertainty, peclet=pe,
        split=SPLIT + ("" if pe is None else f" Peclet number of the heating {pe:.3g}."),
        note=red.note, **common)


def plan_drug_dose(planner: Any, req: DrugDoseRequest, runs: DrugRuns | None = None,
                   validate: bool = False) -> DrugDoseAnswer:
    """The actuation time for a drug dose (see the module docstring); ``validate`` asks
    for the full solver's drug run where the reduced drug model would answer.  Under a
    heating protocol (``req.heating``) the full solver's mechanics of the protocol with the
    drug on them answer (:func:`answer_fields`, model 'full+solute')."""
    if req.heating is not None:  # the drug dose's model choice: under a protocol
        got = answer_fields(req)  # the truth's whatever ``validate`` says
        return DrugDoseAnswer(**got, split=SPLIT, mechanism=mechanism(
            got["squeezed_fraction"], got["diffused_fraction"]))
    solute = req.solute
    settings = drug_settings(req.settings)  # the fluid answers' truth (issue 12)
    dry = req.bead_dry_radius_um
    tau = timescale(dry, req.t_end, req.constants).seconds if dry is not None else None
    common = _fields(req, tau, settings)
    load = req.load_ug

    def ug(x: float) -> float | None:
        return None if load is None else x * load

    # the drug dose's model choice: D0 = 0 -> the fluid answer (exact on one heating);
    # else the full solver with the drug on its cells
    if carried_by_fluid(solute):
        fluid = planner.dose(req.dose_request(req.fraction))
        return DrugDoseAnswer(
            model=fluid.model, time=fluid.time, seconds=fluid.seconds,
            leaked_before_heating=0.0, leaked_before_heating_ug=ug(0.0),
            squeezed_fraction=req.fraction, diffused_fraction=0.0,
            mechanism=mechanism(1.0, 0.0), fluid_fraction=req.fraction,
            medium_concentration_ug_per_ul=_conc(req, req.fraction, fluid.final_radius),
            mass_balance_error=0.0, fluid_answer=fluid.to_dict(), scenario_key=None,
            uncertainty=fluid.uncertainty, peclet=0.0,
            split=SPLIT + " Without diffusion and sieving all of it is squeezed out.",
            note=("No diffusion (D0 = 0): a uniformly loaded bead releases drug in proportion "
                  "to fluid on one heating, exactly, so this is the fluid answer "
                  f"({fluid.model}) for the same fraction; nothing leaks while it waits at "
                  "T_start. " + fluid.note), **common)
    if not validate:  # the reduced drug model, where its measured error holds (issue 23)
        from .reduced import MODEL, reduced_dose

        red = reduced_dose(req, settings)
        if red is not None:
            return _reduced_answer(req, red, MODEL, common)
    runs = runs or runs_for(planner)
    heat = DrugHeatings(req, runs, [req.fraction], settings)
    got = read_off(heat, [], 0, *first_heating(req))
    if isinstance(got, Short):
        name = "dose_fraction" if req.drug_mass_ug is None else "drug_mass_ug"
        raise ParameterError(
            name, getattr(req, name), f"below {got.most:.4f} of the load"
            + (f" ({got.most * load:.4g} ug)" if load else ""),
            f"after waiting {req.lead:.4g} tau, heating for {got.horizon:g} tau releases at "
            "most that" + ("" if got.capped else f" (and at its late rate not more by "
                                                 f"{MAX_HORIZON:g} tau: the collapsed shell "
                                                 "holds the rest)"))
    rel, sc = got.result, heat.scenario(got.trial)  # the run it was read off
    t_hit = req.lead + got.duration
    unc = drug_uncertainty(planner, req, runs, sc, t_hit, _fluid_fraction(req, rel, t_hit))
    before = rel.released_at(req.lead)
    squeezed = rel.squeezed_at(t_hit) - rel.squeezed_at(req.lead)
    pe = rel.peclet(req.lead, t_hit)
    fluid = _fluid_fraction(req, rel, t_hit)
    time = t_hit - req.lead
    conc = _conc(req, rel.released_at(t_hit), _a3_at(rel, t_hit) ** (1.0 / 3.0))
    s = settings
    return DrugDoseAnswer(
        model="full", time=time, seconds=None if tau is None else time * tau,
        leaked_before_heating=before, leaked_before_heating_ug=ug(before),
        squeezed_fraction=squeezed, diffused_fraction=req.fraction - squeezed,
        mechanism=mechanism(squeezed, req.fraction - squeezed), fluid_fraction=fluid,
        medium_concentration_ug_per_ul=conc, mass_balance_error=rel.mass_balance_error,
        fluid_answer=None, scenario_key=sc.key(), uncertainty=unc, peclet=pe,
        split=SPLIT + (f" Peclet number of the heating {pe:.3g} (mean shrinking speed x "
                       "swollen radius / D0 f(phi0)): "
                       + ("the fluid's motion outruns diffusion." if pe is not None and pe > 1
                          else "diffusion keeps up with the fluid's motion.")
                       if pe is not None else ""),
        note=(f"Full solver ({s.grid} grid, N = {s.n}, interfacial length "
              f"{s.interfacial_length:g}) with the drug on its cells: D0 = "
              f"{common['drug_diffusivity_cm2_s']:.3g} cm^2/s ({solute.diffusivity:.3g} x the "
              f"gel's {req.constants.diffusivity(req.t_end) * 1e4:.3g}), hindered by "
              f"{solute.hindrance.law} (r_s / xi_dry {solute.hindrance.mesh_ratio:.3g}, "
              f"r_s / r_f {solute.hindrance.fiber_ratio:.3g}, Y {solute.hindrance.y:g}) to "
              f"{common['effective_diffusivity_cm2_s']:.3g} cm^2/s in the start state; partition "
              f"{solute.partition:g}; "
              + ("a perfect sink" if solute.release_volume is None else "a well-mixed medium")
              + f". At T_start the bead leaks 10% of its load in {common['leak_time_10pct']:.3g} "
              "tau. D0 is "
              f"{req.drug.reference_temperature_k:g} K's value carried to T_end by "
              "Stokes-Einstein with water's viscosity. The permeability does not depend on "
              "temperature at fixed porosity (k0 as given: a k0 calibrated at one T_end may "
              "not carry to another, Tokita & Tanaka 1991)."), **common)


class RunNotCached(LookupError):
    """A drug run an answer needs is not in the cache (:class:`CachedRuns`)."""


class CachedRuns:
    """A planner's drug runs, cached ones only: a missing run raises RunNotCached instead
    of computing it."""

    def __init__(self, runs: DrugRuns) -> None:
        self.runs = runs

    def run(self, sc: DrugScenario) -> Any:
        """The cached run for ``sc``, or RunNotCached."""
        hit = self.runs.cached(sc)
        if hit is None:
            raise RunNotCached(sc.key())
        return hit


def drug_dose_now(planner: Any, req: DrugDoseRequest,
                  validate: bool = False) -> DrugDoseAnswer | None:
    """The drug dose's answer when nothing needs a new run (no diffusion, the reduced drug
    model, or every drug run cached), else None: the service then queues it as a job (no
    HTTP thread waits).  ``validate`` as in :func:`plan_drug_dose`.  Under a protocol:
    None (its mechanics are memoised in the process, not cached: always a job)."""
    if req.heating is not None:
        return None
    try:
        return plan_drug_dose(planner, req, runs=CachedRuns(runs_for(planner)),
                              validate=validate)
    except RunNotCached:
        return None


def _fields(req: Any, tau: float | None, settings: SolverSettings) -> dict[str, Any]:
    """The fields every drug dose's answer shares: the dose and load, the wait and the leak
    at T_start, the drug's diffusivities (D0 at T_end, hindered in the start state), tau, the
    truth and the mesh."""
    solute, c, load = req.solute, req.constants, req.load_ug
    d0 = req.drug.d0_cm2_s(req.t_end, c)
    t10 = leak_time(solute, req.start_radius)
    return dict(dose_fraction=req.fraction, dose_ug=None if load is None else req.fraction * load,
                load_ug=load, wait=req.lead, leak_time_10pct=t10,
                leak_time_10pct_seconds=None if tau is None or math.isinf(t10) else t10 * tau,
                effective_diffusivity_cm2_s=d0 * float(solute.hindrance.factor(
                    1.0 - 1.0 / req.start_radius**3)),
                drug_diffusivity_cm2_s=d0, timescale_seconds=tau,
                interfacial_length=settings.interfacial_length,
                bead_dry_radius_um=req.bead_dry_radius_um, truth=truth_text(req),
                mesh=req.drug.mesh_note(req.start_radius, c))


def _fluid_fraction(req: DrugDoseRequest, rel: Any, t: float) -> float:
    """The fraction of the stored fluid expelled by ``t`` in a drug run (eq. FluidVolExpelled)."""
    return (float(rel.radius[0]) ** 3 - _a3_at(rel, t)) / (req.start_radius**3 - 1.0)


def drug_uncertainty(planner: Any, req: DrugDoseRequest, runs: DrugRuns, sc: DrugScenario,
                     t_hit: float, fluid_fraction: float) -> Uncertainty:
    """The drug answer's uncertainty in the fluid answers' three parts (dosing.truth).

    Numerical: the drug run again with n / 2 cells (mechanics and solute), the relative gap
    of the dose time.  Interfacial length and model form are the mechanics' parts: taken
    from the fluid validation of the same bead and jump at the fluid fraction expelled by
    then where that validation is cached (none is run here), else not measured, with how to
    measure them."""
    time = t_hit - req.lead
    s = sc.settings
    check = replace(sc, settings=s.check())
    try:
        t_check = runs.run(check).time_to_release(req.fraction, after=req.lead) - req.lead
        gap = abs(t_check - time) / time if time > 0 else 0.0
        numerical = Part(gap, f"numerical: {gap:.2%}, the gap between the drug run on "
                              f"{s.n} cells ({time:.6g}) and on {check.settings.n} cells "
                              f"({t_check:.6g}) at ell = {s.interfacial_length:.3g}")
    except ValueError as exc:
        numerical = Part(None, f"numerical: the check run on {check.settings.n} cells does not "
                               f"reach the dose ({exc})")
    fluid = None
    if 0.0 < fluid_fraction < 1.0:
        try:
            fluid = planner.answer_now(req.dose_request(fluid_fraction))
        except ParameterError:  # the bead had shrunk to its final state: no fluid dose there
            fluid = None
    u = fluid.uncertainty if fluid is not None else None
    if u is None:
        how = (f"not measured for this drug answer: validate the fluid dose (no drug) of the "
               f"same bead and jump at dose_fraction = {fluid_fraction:.3g} (the fluid expelled "
               "by then; HTTP validate_full, CLI --validate), then ask again")
        return Uncertainty(numerical, Part(None, f"interfacial length (the mechanics'): {how}"),
                           Part(None, f"model form (the mechanics'): {how}"))
    src = (f" (the mechanics' part, from the fluid validation at the {fluid_fraction:.1%} of "
           "the fluid expelled by the drug dose)")
    return replace(u, numerical=numerical,
                   interfacial_length_range=Part(u.interfacial_length_range.relative,
                                                 u.interfacial_length_range.text + src),
                   model_form=Part(u.model_form.relative, u.model_form.text + src))


def _a3_at(rel: Any, t: float) -> float:
    return float(np.interp(t, rel.t, rel.radius**3))


def _conc(req: DrugDoseRequest, released: float, radius: float) -> float | None:
    """Concentration in a finite release volume (ug/uL) once ``released`` of the load is out
    (the medium volume grows by the expelled fluid)."""
    v = req.drug.release_volume_ul
    if v is None or req.load_ug is None or req.bead_dry_radius_um is None:
        return None
    dry = req.bead_dry_radius_um
    grown = volume_to_ul(4.0 * math.pi / 3.0 * (req.start_radius**3 - radius**3), dry)
    return released * req.load_ug / (v + grown)




# ------------------------------------------------------------------ under heating steps
# A drug dose under a heating protocol (issue 24): the time from the protocol's start at
# which the released drug reaches the dose.
#
# The mechanics are the full solver's run of the protocol's continuous program (eqs.
# PDE_Dimless to Boundary_Dimless with T(t) in the kernels, at the bead's own interfacial
# length on the moving grid: the truth's settings), the one the release fits under a
# protocol use (``dosing.runs.mechanics.protocol_mechanics``, memoised); the drug is
# the passive solute on those mechanics (``solver.solute.release``: advection with the pore
# fluid, hindered diffusion D0 H(phi), the drug's partition, a perfect sink or a well-mixed
# medium).  The run's horizon starts at ``FIRST_HORIZON`` tau and grows x ``GROWTH`` (up
# to ``MAX_HORIZON`` tau past the protocol, held at its last temperature) while the dose
# is not reached, so that the run's uniform samples resolve the dose's time.  Time and tau
# are at the protocol's hottest temperature (eq. timescale).
#
# D0 under a changing temperature: the drug's D0 is given at its reference temperature and
# carried by Stokes-Einstein (k_B T over water's viscosity) to the protocol's hottest
# temperature, as every drug answer carries it to T_end; the solute's D0 / D_gel is then held
# through the protocol (the solute transport takes one diffusivity).  While the bead is
# cooler the true D0 is lower: over 302 -> 308 K by at most 13 % (T / eta(T) of water), and
# the answer says so.  The numerical part is the n / 2 check (mechanics and solute on half the
# cells); the model-form part bounds what holding D0 costs (the same mechanics with D0 at
# T_start: D0(T(t)) lies between); the interfacial-length part is not measured under a
# protocol.


@dataclass
class ProtocolDrugDose:
    """The protocol fields of a drug dose under a protocol (``DrugDoseAnswer.protocol``)."""

    steps: list[str] = field(default_factory=list)
    t_start: float = 0.0
    reference_temperature: float = 0.0
    temperature_at_dose: float = 0.0
    mechanics_cpu_seconds: float = 0.0
    diffusivity_temperature: str = ""
    curve: dict[str, list[float]] = field(default_factory=dict)


def _pieces_seconds(prot: Any, tau_s: float) -> tuple[list[Any], float]:
    pieces = prot.program(tau_s)
    return pieces, sum(p.duration or 0.0 for p in pieces if math.isfinite(p.duration or 0.0))


def _mechanics(req: Any, prot: Any, tau_s: float, settings: Any) -> tuple[Any, Any, float]:
    """The mechanics run reaching the dose and its solute run, and the dose time (tau)."""
    from solver.solute import release

    _, total = _pieces_seconds(prot, tau_s)
    horizon = STEPS_FIRST_HORIZON
    while True:
        mech = protocol_mechanics(req.gel, prot, req.bead_dry_radius_um, horizon * tau_s,
                                  req.constants, settings)
        rel = release(mech.result, req.solute, profiles=2)
        try:
            return mech, rel, rel.time_to_release(req.fraction)
        except ValueError:
            if horizon >= total + MAX_HORIZON:
                most = float(rel.released_fraction[-1])
                name = "dose_fraction" if req.drug_mass_ug is None else "drug_mass_ug"
                raise ParameterError(
                    name, getattr(req, name), f"below {most:.4f} of the load",
                    f"the protocol and {MAX_HORIZON:g} tau at its last temperature release "
                    "at most that (the collapsed shell holds the rest)") from None
            horizon = min(GROWTH * horizon, total + MAX_HORIZON)


def _numerical(req: Any, prot: Any, tau_s: float, settings: Any, time: float) -> Part:
    """The n / 2 check: mechanics and solute on half the cells, the dose time's gap."""
    check = settings.check()
    try:
        _, _, t_check = _mechanics(req, prot, tau_s, check)
    except (ParameterError, SolverError) as exc:
        return Part(None, f"numerical: the check run on {check.n} cells does not reach the "
                          f"dose ({exc})")
    gap = abs(t_check - time) / time if time > 0 else 0.0
    return Part(gap, f"numerical: {gap:.2%}, the gap between the protocol's mechanics and "
                     f"drug on {settings.n} cells ({time:.6g} tau) and on {check.n} cells "
                     f"({t_check:.6g} tau) at ell = {settings.interfacial_length:.3g}")


def _held_d0(req: Any, mech: Any, time: float, constants: Any) -> Part:
    """The model-form part: D0 is held at the hottest temperature's value (module doc).  The
    true D0(T(t)) lies between that and its value at the coolest, T_start, so the same
    mechanics with the drug's D0 at T_start bound what holding it costs (one solute run)."""
    from dataclasses import replace

    from solver.solute import release

    hot = req.drug.d0_cm2_s(req.t_end, constants)
    cold = req.drug.d0_cm2_s(req.t_start, constants)
    if hot <= 0.0 or cold == hot:
        return Part(0.0, "model form: D0 does not change with the temperature here (0 %)")
    solute = replace(req.solute, diffusivity=req.solute.diffusivity * cold / hot)
    try:
        t_cold = release(mech.result, solute, profiles=2).time_to_release(req.fraction)
    except ValueError:
        return Part(None, f"model form: not measured: with D0 at T_start {req.t_start:g} K "
                          f"({cold:.3g} cm^2/s) the run does not reach the dose by "
                          f"{float(mech.result.t[-1]):.4g} tau")
    gap = abs(t_cold - time) / time if time > 0 else 0.0
    return Part(gap, f"model form: {gap:.2%}, what holding D0 at the hottest temperature "
                     f"({hot:.3g} cm^2/s) can cost: with D0 at T_start {req.t_start:g} K "
                     f"({cold:.3g} cm^2/s) on the same mechanics the dose comes at "
                     f"{t_cold:.6g} tau, and D0(T(t)) lies between the two; the mechanics "
                     "are the truth's (the regularized model at the run's ell)")


def check_protocol(req: Any) -> Any:
    """The request's protocol, refusing (naming the field) what a drug dose under a
    protocol does not take: until-steps, a wait, no bead size."""
    prot = parse_protocol(req.t_start, req.heating)  # until-steps refused, naming the step
    if req.bead_dry_radius_um is None:
        raise ParameterError("dry_radius_um", None, "a finite number > 0 (um; or "
                             "swollen_radius_um): a protocol's steps are in seconds")
    if req.lead > 0.0:
        raise ParameterError("wait", req.lead, "0 with a protocol (begin the protocol with "
                             "'Rest at <T_start> K for ...' instead)")
    return prot


def answer_fields(req: Any) -> dict[str, Any]:
    """The drug dose under ``req.heating`` (module doc): the fields of a ``DrugDoseAnswer``
    with model 'full+solute' and its ``protocol`` fields, but the mechanism's words
    (``dosing.payload.release.plan_drug_dose`` adds them: it is the one way in)."""
    prot = check_protocol(req)
    dry = req.bead_dry_radius_um
    c = req.constants
    settings = drug_settings(req.settings)
    tau_s = timescale(dry, req.t_end, c).seconds
    mech, rel, t_hit = _mechanics(req, prot, tau_s, settings)
    unc = Uncertainty(
        _numerical(req, prot, tau_s, settings, t_hit),
        Part(None, "interfacial length: not measured under a protocol (the run is at ell = "
                   f"{settings.interfacial_length:.3g}, the truth's: the bead's own unless "
                   "given); the fluid validation of the jump to the protocol's hottest "
                   "temperature measures it for the jump"),
        _held_d0(req, mech, t_hit, c))
    solute, load = req.solute, req.load_ug
    d0 = req.drug.d0_cm2_s(req.t_end, c)
    d_start = req.drug.d0_cm2_s(req.t_start, c)
    squeezed = float(squeezed_under(mech, np.array([t_hit * tau_s]))[0])
    a3 = float(np.interp(t_hit, mech.result.t, np.asarray(mech.result.radius) ** 3))
    a0 = req.start_radius
    fluid = (a0**3 - a3) / (a0**3 - 1.0)
    pe = rel.peclet(0.0, t_hit)
    from ..heating.response import temperature_curve

    pieces, _ = _pieces_seconds(prot, tau_s)
    tc = np.union1d(np.linspace(0.0, min(1.5 * t_hit, float(rel.t[-1])), 200), [t_hit])
    drop = d_start / d0 - 1.0 if d0 > 0 else 0.0
    d_text = (f"D0 {req.drug.diffusivity_cm2_s:.3g} cm^2/s at "
              f"{req.drug.reference_temperature_k:g} K carried by Stokes-Einstein with "
              f"water's viscosity to the protocol's hottest {req.t_end:g} K ({d0:.3g} "
              f"cm^2/s) and held there through the protocol; at T_start {req.t_start:g} K "
              f"it is {d_start:.3g} cm^2/s ({drop:+.1%}), so while the bead is cooler the "
              "run overstates the drug's diffusion by up to that")
    extra = ProtocolDrugDose(
        steps=prot.texts, t_start=prot.t_start, reference_temperature=req.t_end,
        temperature_at_dose=float(temperature_curve(pieces, prot.t_start,
                                                    np.array([t_hit]))[0]),
        mechanics_cpu_seconds=mech.seconds, diffusivity_temperature=d_text,
        curve={"time": tc.tolist(), "seconds": (tc * tau_s).tolist(),
               "temperature_k": temperature_curve(pieces, prot.t_start, tc).tolist(),
               "released_fraction": np.interp(tc, rel.t, rel.released_fraction).tolist()})
    s = mech.settings
    return dict(
        _fields(req, tau_s, s), model=STEPS_MODEL, time=t_hit, seconds=t_hit * tau_s,
        leaked_before_heating=0.0, leaked_before_heating_ug=None if load is None else 0.0,
        squeezed_fraction=squeezed, diffused_fraction=req.fraction - squeezed,
        fluid_fraction=fluid, medium_concentration_ug_per_ul=_conc(req, req.fraction, a3 ** (
            1.0 / 3.0)), mass_balance_error=rel.mass_balance_error, fluid_answer=None,
        scenario_key=None, uncertainty=unc, peclet=pe, protocol=extra,
        note=(f"Full solver's mechanics of the protocol {'; '.join(prot.texts)} ({s.grid} "
              f"grid, N = {s.n}, rtol {s.rtol:g}, interfacial length "
              f"{s.interfacial_length:g}, T(t) in the kernels, tau = {tau_s:.4g} s at "
              f"{req.t_end:g} K) with the drug on them (solver.solute.release, partition "
              f"{solute.partition:g}, hindered by {solute.hindrance.law}; "
              + ("a perfect sink" if solute.release_volume is None else "a well-mixed medium")
              + f"). The time is from the protocol's start. {d_text}."))


__all__ = ["DrugCase", "DrugDoseAnswer", "DrugDoseRequest", "DrugHeatings", "ProtocolDrugDose",
           "answer_fields", "check_protocol", "plan_drug_dose"]
