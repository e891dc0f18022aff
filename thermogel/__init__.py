"""thermogel: plan drug release from thermo-responsive hydrogel beads.

The public facade over the three packages (``solver`` the physics, ``dosing`` the planner,
``api`` the ways in), so a script needs one import::

    import thermogel as tg
    ans = tg.plan_dose(tg.DoseRequest("ANB", 302, 308, dose_fraction=0.8, dry_radius_um=50))
    print(ans.model, ans.seconds)

Names are resolved on first use (PEP 562), so ``import thermogel`` costs nothing until a
name is used, and the HTTP client's dependencies (httpx, pydantic) load only with ``Client``.
"""

from __future__ import annotations

import importlib
from typing import Any

# name -> the module that defines it (the one definition; this is only a map)
_WHERE: dict[str, str] = {
    # the planner
    "DoseRequest": "dosing", "ScheduleRequest": "dosing", "PhysicalConstants": "dosing",
    "SolverSettings": "dosing", "Planner": "dosing", "plan_dose": "dosing",
    "plan_schedule": "dosing", "DoseAnswer": "dosing", "ScheduleAnswer": "dosing",
    "water_viscosity": "dosing", "timescale": "dosing",
    # the drug
    "DrugModel": "dosing.drug", "DrugDoseRequest": "dosing.drug_dose",
    "plan_drug_dose": "dosing.drug_dose", "DrugScheduleRequest": "dosing.drug_schedule",
    "plan_drug_schedule": "dosing.drug_schedule",
    # release data as a lab analyses it (docs/release_analysis.md)
    "read_profile": "dosing.analysis", "fit_empirical": "dosing.analysis",
    "compare_profiles": "dosing.analysis",
    # design: the heating that meets a target, the experiment that pins the model
    "HeatingTarget": "dosing.design", "design_heating": "dosing.design",
    "ExperimentAsk": "dosing.design", "design_experiment": "dosing.design",
    # units at the edges
    "to_unit": "dosing.quantity", "kelvin": "dosing.quantity", "seconds": "dosing.quantity",
    "micrometres": "dosing.quantity",
    # the physics
    "Gel": "solver", "ANB": "solver", "HHT": "solver", "preset": "solver",
    "equilibrium": "solver", "equilibria": "solver", "folds": "solver",
    "classify_jump": "solver", "ParameterError": "solver", "SolverError": "solver",
    "NotApplicableError": "solver", "simulate": "solver.full", "FullResult": "solver.full",
    "front_trajectory": "solver.front", "sharp_front_trajectory": "solver.front.sharp",
    # the HTTP client
    "Client": "api.client", "AsyncClient": "api.client", "ApiError": "api.client",
}

__all__ = sorted(_WHERE)


def __getattr__(name: str) -> Any:
    module = _WHERE.get(name)
    if module is None:
        raise AttributeError(f"module 'thermogel' has no attribute {name!r}")
    importlib.import_module("dosing")  # runs and fits get their tables (registered, lazy)
    value = getattr(importlib.import_module(module), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return __all__
