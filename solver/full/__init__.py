"""The full poro-elastic PDE solver (eqs. PDE_Dimless to Boundary_Dimless).

Three grids (the paper's Eulerian grid in R = r/a, a uniform Lagrangian grid in the dry
coordinate, and a moving Lagrangian grid whose cells follow the interface; registry in
grids.py), an explicit forward Euler reference and an adaptive implicit Rosenbrock
integrator (RODASP), front tracking and a plain-data result object; ``simulate`` takes its
discretisation as a ``SolverOptions`` (or its fields as keywords).
"""

from .numba_cache import refresh as _refresh_cache

_refresh_cache()

from .grids import GRIDS  # noqa: E402
from .moving import MeshOptions  # noqa: E402
from .options import SolverOptions  # noqa: E402
from .result import FullResult  # noqa: E402
from .run import simulate  # noqa: E402

__all__ = ["GRIDS", "FullResult", "MeshOptions", "SolverOptions", "simulate"]
