"""Mechanics runs a drug's release reads without a stored record: a protocol's continuous
program for release fits, drug doses and batches under heating steps
(:func:`protocol_mechanics`, profiles kept, memoised in bytes), and a jump's run for a
drug batch's bands (:func:`jump_mechanics`).  The solute is passive, so one mechanics
run serves every drug on it (eqs. PDE_Dimless to Boundary_Dimless; the solver from
``dosing.runs.full``)."""

from __future__ import annotations

import functools
import json
import threading
import time
from dataclasses import dataclass
from typing import Any

from solver.equilibrium import equilibrium

from ..heating.grammar import Protocol
from ..heating.program import program_spec, solver_program
from ..request import bead_settings
from ..units import PhysicalConstants, timescale
from .full import full_solver
from .lru import ByteLRU
from .scenario import SolverSettings, run_budget
from .solute import drug_settings

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


def protocol_mechanics(gel: Any, prot: Protocol, dry_radius_um: float, horizon_s: float,
                       constants: PhysicalConstants,
                       settings: SolverSettings | None = None) -> ReleaseMechanics:
    """The mechanics of ``prot`` up to ``horizon_s`` seconds (memoised; module doc): its
    program at ``settings`` (the bead's own ell unless given), SAMPLES outputs."""
    t_ref = prot.hottest
    tau = timescale(dry_radius_um, t_ref, constants).seconds
    s, _ = bead_settings(settings or SolverSettings(), constants, dry_radius_um)
    s = drug_settings(s)
    spec = program_spec(prot.program(tau), constants.mobility, t_ref)
    horizon = HORIZON_MARGIN * horizon_s / tau
    key = json.dumps({"gel": gel.to_dict(), "t_start": prot.t_start, "program": spec,
                      "horizon": horizon, "settings": repr(s), "samples": SAMPLES},
                     sort_keys=True, default=str)
    with _LOCK:
        hit = _MEMO.get(key)
        if hit is not None:
            _MEMO.move_to_end(key)
            return hit
    simulate = full_solver()

    started = time.process_time()
    res = simulate(gel, prot.t_start, protocol=solver_program(spec), until=horizon,
                   every=horizon / SAMPLES, grid=s.grid, n=s.n, integrator=s.integrator,
                   rtol=s.rtol, branch="swollen", interfacial_length=s.interfacial_length,
                   max_seconds=run_budget())
    mech = ReleaseMechanics(res, tau, t_ref, equilibrium(gel, prot.t_start, "swollen").stretch,
                            s, time.process_time() - started, tuple(prot.texts))
    _MEMO[key] = mech  # the ByteLRU evicts past MEMO_BYTES or MEMO_SIZE itself
    return mech


@functools.lru_cache(maxsize=8)
def jump_mechanics(gel: Any, t_start: float, t_end: float, branch: str | None,
                   settings: Any, horizon: float) -> Any:
    """A drug run's mechanics of the jump to ``t_end`` held for ``horizon`` tau (a batch's
    reference bead, every class resting after its end; memoised, a FullResult)."""
    from .solute import simulate_protocol

    return simulate_protocol(gel, t_start, [(horizon, t_end)], branch or "swollen", settings)
