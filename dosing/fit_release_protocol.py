"""The release model of a release-curve fit under a heating protocol (issue 27).

Under a protocol the bead shrinks while the drug diffuses: the released fraction is the
solute transport (``solver.solute.release``: advection with the pore fluid, hindered
diffusion, a perfect sink) on the full solver's mechanics of the protocol.  The solute is
passive, so the mechanics do not depend on the drug's D0: one mechanics run (the continuous
program ``solver.heating.Program`` of the protocol, eqs. PDE_Dimless to Boundary_Dimless, at
the bead's own interfacial length on the moving grid, as every answer's truth) serves every
trial D0 of the fit; each trial costs one solute run on its samples (~0.1-0.2 s; the
mechanics ~2 s at n = 100, rtol 1e-4, and about a minute at the truth's n = 400,
rtol 1e-5).  Mechanics runs are kept in memory (``MEMO_SIZE``, keyed by the scenario).

D0 is the drug's diffusivity in water at the protocol's hottest temperature (tau's
reference, eq. timescale), where the solute's dimensionless D0 / D_gel is taken, as for
the planner's drug answers (``dosing.drug.DrugModel.solute``).
"""

from __future__ import annotations

import json
import threading
import time
from dataclasses import dataclass
from typing import Any

import numpy as np

from solver.equilibrium import equilibrium
from solver.errors import ParameterError

from .drug import DrugModel, drug_settings
from .heating import Protocol
from .heating_program import program_spec, solver_program
from .request import bead_settings
from .runs.lru import ByteLRU
from .runs.scenario import SolverSettings, run_budget
from .units import PhysicalConstants, timescale

SAMPLES = 600  # mechanics outputs over the horizon (the solute's steps adapt within them)
HORIZON_MARGIN = 1.02  # the run goes this far past the last measured time
MEMO_SIZE = 8
MEMO_BYTES = 128e6  # mechanics (with profiles) kept, bytes


@dataclass(frozen=True)
class ReleaseMechanics:
    """One mechanics run of a protocol for release fits: the run (dimensionless), tau in
    seconds at ``t_ref`` (the protocol's hottest), the start stretch, its settings and cost."""

    result: Any
    tau_s: float
    t_ref: float
    start_radius: float
    settings: SolverSettings
    seconds: float
    protocol: tuple[str, ...]


_MEMO: ByteLRU = ByteLRU(MEMO_BYTES, max_items=MEMO_SIZE)  # bytes, not only entries
_LOCK = threading.Lock()


def parse_protocol(t_start: float, protocol: Any) -> Protocol:
    """The protocol (texts, dicts or a Protocol); until-steps are refused (a release fit
    needs the steps' durations, not a dose that ends them)."""
    prot = Protocol.parse(t_start, [protocol] if isinstance(protocol, str) else protocol)
    if prot.until_steps:
        i = prot.until_steps[0]
        raise ParameterError(f"protocol[{i}].until", prot.texts[i], "a step with a duration "
                             "('for 5 min'): a release fit runs the protocol as it was run")
    return prot


def protocol_mechanics(gel: Any, prot: Protocol, dry_radius_um: float, horizon_s: float,
                       constants: PhysicalConstants,
                       settings: SolverSettings | None = None) -> ReleaseMechanics:
    """The mechanics of ``prot`` up to ``horizon_s`` (memoised; module doc)."""
    t_ref = prot.hottest
    tau = timescale(dry_radius_um, t_ref, constants).seconds
    s, _ = bead_settings(settings or SolverSettings(), constants, dry_radius_um)
    s = drug_settings(s)
    mobility = "water" if constants.viscosity_pa_s == "water" else "kT"
    spec = program_spec(prot.program(tau), mobility, t_ref)
    horizon = HORIZON_MARGIN * horizon_s / tau
    key = json.dumps({"gel": gel.to_dict(), "t_start": prot.t_start, "program": spec,
                      "horizon": horizon, "settings": repr(s), "samples": SAMPLES},
                     sort_keys=True, default=str)
    with _LOCK:
        hit = _MEMO.get(key)
        if hit is not None:
            _MEMO.move_to_end(key)
            return hit
    from .runs.full import full_solver

    simulate = full_solver()

    started = time.process_time()
    res = simulate(gel, prot.t_start, protocol=solver_program(spec), until=horizon,
                   every=horizon / SAMPLES, grid=s.grid, n=s.n, integrator=s.integrator,
                   rtol=s.rtol, branch="swollen", interfacial_length=s.interfacial_length,
                   max_seconds=run_budget())
    mech = ReleaseMechanics(res, tau, t_ref, equilibrium(gel, prot.t_start, "swollen").stretch,
                            s, time.process_time() - started, tuple(prot.texts))
    with _LOCK:
        _MEMO[key] = mech
        while len(_MEMO) > MEMO_SIZE:
            _MEMO.popitem(last=False)
    return mech


def released_under(mech: ReleaseMechanics, drug: DrugModel, d0: float,
                   constants: PhysicalConstants, dry_radius_um: float,
                   times_s: np.ndarray) -> np.ndarray:
    """The released fraction at ``times_s`` for a drug of free diffusivity ``d0`` (cm^2/s in
    water at ``mech.t_ref``) on the mechanics run (solver.solute.release)."""
    from dataclasses import replace

    from solver.solute import release

    trial = replace(drug, diffusivity_cm2_s=d0, reference_temperature_k=mech.t_ref)
    rel = release(mech.result, trial.solute(mech.start_radius, mech.t_ref, constants,
                                            dry_radius_um), profiles=2)
    return np.interp(np.asarray(times_s, dtype=float) / mech.tau_s, rel.t,
                     rel.released_fraction)


def squeezed_under(mech: ReleaseMechanics, times_s: np.ndarray) -> np.ndarray:
    """The release of the fluid's motion alone (D0 = 0, no sieving) at ``times_s``: what the
    protocol squeezes out whatever the drug (a floor no D0 goes below)."""
    from solver.solute import Solute, release

    rel = release(mech.result, Solute(0.0), profiles=2)
    return np.interp(np.asarray(times_s, dtype=float) / mech.tau_s, rel.t,
                     rel.released_fraction)


def model_text(mech: ReleaseMechanics) -> str:
    """The model in words, with its settings, scale and cost."""
    s = mech.settings
    return (f"release under the protocol {'; '.join(mech.protocol)}: the full solver's "
            f"mechanics ({s.grid} grid, N = {s.n}, rtol {s.rtol:g}, interfacial length "
            f"{s.interfacial_length:g}, tau = {mech.tau_s:.4g} s at {mech.t_ref:g} K) with the "
            "drug advected by the pore fluid and diffusing with D0 H(phi) into a perfect sink "
            f"(solver.solute.release); D0 in water at {mech.t_ref:g} K")


def cost(mech: ReleaseMechanics, evaluations: int, solute_seconds: float) -> dict[str, Any]:
    """What the fit cost: one mechanics run (memoised) and one solute run per evaluation."""
    return {"mechanics_cpu_seconds": mech.seconds, "solute_runs": evaluations,
            "solute_cpu_seconds": solute_seconds,
            "note": "one mechanics run serves every trial D0 (the solute is passive); each "
                    "evaluation is one solute run on its samples"}
