"""The registry of grids: one name -> its kernels, geometry and whether it moves.

``simulate(grid=...)`` looks names up here (and nowhere else in solver/full): a grid is a
kernel code (the numba dispatch of ``system.py``: Eulerian or Lagrangian kernels), a
module with the Python-side geometry and state conversions, and a flag for the moving
grid, whose geometry rows change in place when it is rezoned (``moving.Rezoner``).  To add
a grid: give it a module with ``geometry``-like rows the kernels understand and an entry
here.
"""

from __future__ import annotations

from dataclasses import dataclass
from types import ModuleType

from ..errors import ParameterError
from . import ale, eulerian, lagrangian
from .system import EULERIAN, LAGRANGIAN, MOVING


@dataclass(frozen=True)
class GridSpec:
    """One grid: name, kernel code, its module, whether it is rezoned, and a description."""

    name: str
    code: int
    module: ModuleType
    moving: bool
    description: str


GRIDS: dict[str, GridSpec] = {
    "eulerian": GridSpec("eulerian", EULERIAN, eulerian, False,
                         "the paper's grid: uniform cells in R = r/a (appendix Numerical scheme)"),
    "lagrangian": GridSpec("lagrangian", LAGRANGIAN, lagrangian, False,
                           "uniform cells in the dry coordinate rho"),
    "moving": GridSpec("moving", MOVING, ale, True,
                       "non-uniform cells in the dry coordinate, adapted to the interface by "
                       "rezoning (solver/full/moving.py)"),
}


def grid_spec(name: object) -> GridSpec:
    """The registered grid called ``name``; ParameterError naming the valid ones."""
    if not isinstance(name, str) or name not in GRIDS:
        raise ParameterError("grid", name, " or ".join(repr(g) for g in GRIDS))
    return GRIDS[name]
