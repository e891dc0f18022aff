"""The full poro-elastic PDE solver (eqs. PDE_Dimless to Boundary_Dimless).

Three grids (the paper's Eulerian grid in R = r/a, a uniform Lagrangian grid in the dry
coordinate, and a moving Lagrangian grid whose cells follow the interface; registry in
grids.py), an explicit forward Euler reference and an adaptive implicit Rosenbrock
integrator (RODASP), front tracking and a plain-data result object; ``simulate`` takes its
discretisation as a ``SolverOptions`` (or its fields as keywords).
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

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


def __getattr__(name: str) -> Any:
    module = _LAZY.get(name)
    if module is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    value = getattr(importlib.import_module(module, __name__), name)
    globals()[name] = value
    return value

__all__ = ["GRIDS", "FullResult", "MeshOptions", "SolverOptions", "simulate"]
