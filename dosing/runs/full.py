"""The full solver as dosing/ reaches it: ``solver.full.simulate`` (eqs. PDE_Dimless to
Boundary_Dimless), imported on first use so that a front-model answer loads no kernels.

The one import of the full solver in dosing/ (tests/test_architecture.py).  A planner's runs
take the store's ``solver`` (this one by default); the run functions a pool worker imports by
name, and a fit's dose time, have no planner and take it from here (docs/architecture.md)."""

from __future__ import annotations

from typing import Any


def full_solver() -> Any:
    """``solver.full.simulate``."""
    from solver.full import simulate

    return simulate


def is_full_solver(solver: Any) -> bool:
    """True when ``solver`` is the full solver itself, not a stand-in (asking loads no
    kernels unless it may be)."""
    return getattr(solver, "__module__", None) == "solver.full.run" and solver is full_solver()
