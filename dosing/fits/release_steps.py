"""The release model of a release-curve fit under a heating protocol (issue 27).

Under a protocol the bead shrinks while the drug diffuses: the released fraction is the
solute transport (``solver.solute.release``: advection with the pore fluid, hindered
diffusion, a perfect sink) on the full solver's mechanics of the protocol.  The solute is
passive, so the mechanics do not depend on the drug's D0: one mechanics run (the continuous
program ``solver.heating.Program`` of the protocol, eqs. PDE_Dimless to Boundary_Dimless, at
the bead's own interfacial length on the moving grid, as every answer's truth) serves every
trial D0 of the fit; each trial costs one solute run on its samples (~0.1-0.2 s; the
mechanics ~2 s at n = 100, rtol 1e-4, and about a minute at the truth's n = 400,
rtol 1e-5).  Mechanics runs are kept in memory (``dosing.runs.mechanics``).

D0 is the drug's diffusivity in water at the protocol's hottest temperature (tau's
reference, eq. timescale), where the solute's dimensionless D0 / D_gel is taken, as for
the planner's drug answers (``dosing.payload.drug.DrugModel.solute``).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from solver.errors import ParameterError

from ..heating.grammar import Protocol
from ..payload.drug import DrugModel
from ..runs.mechanics import ReleaseMechanics
from ..units import PhysicalConstants


def parse_protocol(t_start: float, protocol: Any) -> Protocol:
    """The protocol (texts, dicts or a Protocol); until-steps are refused (a release fit
    needs the steps' durations, not a dose that ends them)."""
    prot = Protocol.parse(t_start, [protocol] if isinstance(protocol, str) else protocol)
    if prot.until_steps:
        i = prot.until_steps[0]
        raise ParameterError(f"protocol[{i}].until", prot.texts[i], "a step with a duration "
                             "('for 5 min'): a release fit runs the protocol as it was run")
    return prot


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
