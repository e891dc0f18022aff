"""A drug dose under a heating protocol (issue 24): the time from the protocol's start at
which the released drug reaches the dose.

The mechanics are the full solver's run of the protocol's continuous program (eqs.
PDE_Dimless to Boundary_Dimless with T(t) in the kernels, at the bead's own interfacial
length on the moving grid: the truth's settings), the one the release fits under a
protocol use (``dosing.fit_release_protocol.protocol_mechanics``, memoised); the drug is
the passive solute on those mechanics (``solver.solute.release``: advection with the pore
fluid, hindered diffusion D0 H(phi), the drug's partition, a perfect sink or a well-mixed
medium).  The run's horizon starts at ``FIRST_HORIZON`` tau and grows x ``GROWTH`` (up
to ``MAX_HORIZON`` tau past the protocol, held at its last temperature) while the dose
is not reached, so that the run's uniform samples resolve the dose's time.  Time and tau
are at the protocol's hottest temperature (eq. timescale).

D0 under a changing temperature: the drug's D0 is given at its reference temperature and
carried by Stokes-Einstein (k_B T over water's viscosity) to the protocol's hottest
temperature, as every drug answer carries it to T_end; the solute's D0 / D_gel is then held
through the protocol (the solute transport takes one diffusivity).  While the bead is
cooler the true D0 is lower: over 302 -> 308 K by at most 13 % (T / eta(T) of water), and
the answer says so.  The numerical part is the n / 2 check (mechanics and solute on half the
cells); the model-form part bounds what holding D0 costs (the same mechanics with D0 at
T_start: D0(T(t)) lies between); the interfacial-length part is not measured under a
protocol.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from solver.errors import ParameterError, SolverError
from solver.limits import DRUG_STEP_MAX

from .drug import drug_settings, leak_time
from .fit_release_protocol import parse_protocol, protocol_mechanics, squeezed_under
from .truth import Part, Uncertainty, truth_text
from .units import timescale, volume_to_ul

MODEL = "full+solute"
FIRST_HORIZON = 1e-3  # tau: the first run's horizon, x GROWTH while the dose is short, so
GROWTH = 4.0  # the dose falls in the last 3/4 of its run's SAMPLES (>= 150 samples before it)
MAX_HORIZON = DRUG_STEP_MAX  # tau past the protocol's end (solver.limits)


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
    horizon = FIRST_HORIZON
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
    (``dosing.drug_dose.plan_drug_dose`` adds them: it is the one way in)."""
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
    phi0 = 1.0 - 1.0 / req.start_radius**3
    d_eff = d0 * float(solute.hindrance.factor(phi0))
    squeezed = float(squeezed_under(mech, np.array([t_hit * tau_s]))[0])
    a3 = float(np.interp(t_hit, mech.result.t, np.asarray(mech.result.radius) ** 3))
    a0 = req.start_radius
    fluid = (a0**3 - a3) / (a0**3 - 1.0)
    pe = rel.peclet(0.0, t_hit)
    t10 = leak_time(solute, a0)
    from .protocol_dose import temperature_curve

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
    conc = None
    if req.drug.release_volume_ul is not None and load is not None:
        grown = volume_to_ul(4.0 * math.pi / 3.0 * (a0**3 - a3), dry)
        conc = req.fraction * load / (req.drug.release_volume_ul + grown)
    return dict(
        model=MODEL, time=t_hit, seconds=t_hit * tau_s, dose_fraction=req.fraction,
        dose_ug=None if load is None else req.fraction * load, load_ug=load, wait=0.0,
        leaked_before_heating=0.0, leaked_before_heating_ug=None if load is None else 0.0,
        leak_time_10pct=t10,
        leak_time_10pct_seconds=None if math.isinf(t10) else t10 * tau_s,
        squeezed_fraction=squeezed, diffused_fraction=req.fraction - squeezed,
        fluid_fraction=fluid,
        medium_concentration_ug_per_ul=conc, effective_diffusivity_cm2_s=d_eff,
        drug_diffusivity_cm2_s=d0, mass_balance_error=rel.mass_balance_error,
        timescale_seconds=tau_s, fluid_answer=None, scenario_key=None,
        uncertainty=unc, peclet=pe, mesh=req.drug.mesh_note(a0, c),
        interfacial_length=s.interfacial_length, bead_dry_radius_um=dry,
        truth=truth_text(req), protocol=extra,
        note=(f"Full solver's mechanics of the protocol {'; '.join(prot.texts)} ({s.grid} "
              f"grid, N = {s.n}, rtol {s.rtol:g}, interfacial length "
              f"{s.interfacial_length:g}, T(t) in the kernels, tau = {tau_s:.4g} s at "
              f"{req.t_end:g} K) with the drug on them (solver.solute.release, partition "
              f"{solute.partition:g}, hindered by {solute.hindrance.law}; "
              + ("a perfect sink" if solute.release_volume is None else "a well-mixed medium")
              + f"). The time is from the protocol's start. {d_text}."))


__all__ = ["MODEL", "ProtocolDrugDose", "answer_fields", "check_protocol"]
