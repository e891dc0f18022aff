"""The full poro-elastic PDE solver (eqs. PDE_Dimless to Boundary_Dimless).

Three grids (the paper's Eulerian grid in R = r/a, a uniform Lagrangian grid in the dry
coordinate, and a moving Lagrangian grid whose cells follow the interface; registry in
grids.py), an explicit forward Euler reference and an adaptive implicit Rosenbrock
integrator (RODASP), front tracking and a plain-data result object; ``simulate`` takes its
discretisation as a ``SolverOptions`` (or its fields as keywords).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from ..lazy import lazy_names
from .numba_cache import refresh as _refresh_cache

_refresh_cache()

if TYPE_CHECKING:
    from .grids import GRIDS
    from .moving import MeshOptions
    from .options import SolverOptions
    from .result import FullResult
    from .run import simulate

# imported on first use (PEP 562): reading a stored run (``result``) loads no kernels
_LAZY = {"GRIDS": ".grids", "MeshOptions": ".moving", "SolverOptions": ".options",
         "FullResult": ".result", "simulate": ".run"}


__getattr__ = lazy_names(__name__, _LAZY, globals())

__all__ = ["GRIDS", "FullResult", "MeshOptions", "SolverOptions", "simulate"]
