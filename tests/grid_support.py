"""The solver's grid registry (solver.full.grids.GRIDS) as test parameters.

A generic full-solver test runs on every registered grid, the default moving grid
included, through ``every_grid()``: (name, settings) pairs, the settings being what a small
run needs on that grid.  The moving grid places its cells by the interfacial length, so it
runs the regularized model (at ell = 0 it has nothing to place them by: ANB 302 -> 312 K
fails with a step-size underflow at t = 3e-5) at ell = 0.02, which 40-100 cells resolve
(4 cells per ell at the edge, MeshOptions.edge_cells).  A grid
added to the registry without an entry in SETTINGS fails at collection, naming it.

A test that is truly grid-specific says so in its docstring and takes ``fixed_grids()``
(the registry's grids that do not move: the paper's model at ell = 0, the explicit
integrator, uniform-grid convergence in N) or an explicit list.
"""

from __future__ import annotations

import pytest

from solver.full.grids import GRIDS

MOVING_ELL = 0.02
SETTINGS: dict[str, dict[str, float]] = {"eulerian": {}, "lagrangian": {},
                                         "moving": {"interfacial_length": MOVING_ELL}}


def every_grid() -> list:
    """pytest parameters (grid, settings) for every registered grid."""
    missing = [name for name in GRIDS if name not in SETTINGS]
    if missing:
        raise KeyError(f"grid(s) {missing} of solver.full.grids.GRIDS have no test settings "
                       "in tests/grid_support.py")
    return [pytest.param(name, SETTINGS[name], id=name) for name in GRIDS]


def fixed_grids() -> list[str]:
    """The registered grids that do not move (uniform cells, any ell, both integrators)."""
    return [name for name, spec in GRIDS.items() if not spec.moving]
