"""SolverOptions: how a full run is discretised and integrated, validated in one place.

The scipy ``solve_ivp`` pattern: ``simulate(gel, t_start, t_end, until=..., **options)``
takes these fields as keyword arguments (or one ``options=SolverOptions(...)``), and every
check of a grid name, a cell count, a tolerance or an interfacial length lives here, so
``dosing`` and ``api`` can validate a request with the same rules before it runs.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, fields, replace
from typing import Any

import numpy as np

from ..errors import ParameterError
from ..limits import SOLVER_ELL_MAX, SOLVER_N_RANGE
from .grids import GRIDS, grid_spec
from .moving import MeshOptions

N_RANGE = SOLVER_N_RANGE
ELL_MAX = SOLVER_ELL_MAX
INTEGRATORS = ("implicit", "explicit")
JACOBIANS = ("analytic", "fd")
DEFAULT_MAX_STEPS = {"implicit": 500_000, "explicit": 20_000_000}


def _choice(field: str, value: Any, options: tuple[str, ...]) -> str:
    if value not in options:
        raise ParameterError(field, value, " or ".join(repr(o) for o in options))
    return str(value)


def check_interfacial_length(value: Any, field: str = "interfacial_length") -> float:
    """A validated interfacial length ell in dry radii: 0 (the paper's model) to ELL_MAX."""
    try:
        ell = float(value)
    except (TypeError, ValueError):
        ell = math.nan
    if isinstance(value, bool) or not (math.isfinite(ell) and 0.0 <= ell <= ELL_MAX):
        raise ParameterError(field, value, f"0 <= ell <= {ELL_MAX} (dry radii)")
    return ell


def check_cells(value: Any, field: str = "n") -> int:
    """A validated cell count N_RANGE[0]..N_RANGE[1]."""
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or not (
            N_RANGE[0] <= value <= N_RANGE[1]):
        raise ParameterError(field, value, f"an integer {N_RANGE[0]}-{N_RANGE[1]}")
    return int(value)


@dataclass(frozen=True)
class SolverOptions:
    """Discretisation and integration of a full run (eqs. PDE_Dimless to Boundary_Dimless).

    ``grid``: a name of ``solver.full.grids.GRIDS`` ('eulerian', the paper's; 'lagrangian',
    uniform in the dry coordinate; 'moving', cells that follow the interface, options
    ``mesh``); ``n`` cells; ``integrator`` 'implicit' (adaptive RODASP, ``rtol``/``atol``
    on porosity and radius, ``jacobian`` 'analytic' or 'fd') or 'explicit' (the paper's
    forward Euler, largest step ``dt``); ``interfacial_length`` ell in dry radii (0: the
    paper's model); budgets ``max_steps`` and ``max_seconds`` (wall clock).
    """

    grid: str = "eulerian"
    n: int = 400
    integrator: str = "implicit"
    rtol: float = 1e-6
    atol: float = 1e-9
    jacobian: str = "analytic"
    interfacial_length: float = 0.0
    dt: float | None = None
    max_steps: int | None = None
    max_seconds: float | None = None
    mesh: MeshOptions | None = None

    def __post_init__(self) -> None:
        spec = grid_spec(self.grid)
        mesh = MeshOptions() if self.mesh is None else self.mesh
        if not isinstance(mesh, MeshOptions):
            raise ParameterError("mesh", mesh, "None or a solver.full.moving.MeshOptions")
        integrator = _choice("integrator", self.integrator, INTEGRATORS)
        _choice("jacobian", self.jacobian, JACOBIANS)
        ell = check_interfacial_length(self.interfacial_length)
        n = check_cells(self.n)
        if not (isinstance(self.rtol, (int, float)) and 1e-13 <= self.rtol <= 0.1):
            raise ParameterError("rtol", self.rtol, "1e-13 <= rtol <= 0.1")
        if not (isinstance(self.atol, (int, float)) and 0.0 < self.atol <= 1.0):
            raise ParameterError("atol", self.atol, "0 < atol <= 1")
        if self.dt is not None:
            if integrator != "explicit":
                raise ParameterError("dt", self.dt, "None for the implicit integrator "
                                     "(explicit only)")
            if not (isinstance(self.dt, (int, float)) and math.isfinite(self.dt)
                    and 0.0 < self.dt < 1.0):
                raise ParameterError("dt", self.dt, "0 < dt < 1")
        max_steps = (DEFAULT_MAX_STEPS[integrator] if self.max_steps is None
                     else self.max_steps)
        if isinstance(max_steps, bool) or not isinstance(max_steps, (int, np.integer)) or (
                max_steps < 1):
            raise ParameterError("max_steps", max_steps, "a positive integer")
        if self.max_seconds is not None and not (
                isinstance(self.max_seconds, (int, float)) and math.isfinite(self.max_seconds)
                and self.max_seconds >= 0.0):
            raise ParameterError("max_seconds", self.max_seconds,
                                 "None or a finite number >= 0 (s)")
        if spec.moving and integrator != "implicit":
            raise ParameterError("integrator", integrator, "'implicit' on the moving grid")
        if spec.moving and mesh.nodes is not None and len(mesh.nodes) != n + 1:
            raise ParameterError("mesh.nodes", len(mesh.nodes) - 1, f"n = {n} cells")
        for name, value in (("mesh", mesh), ("interfacial_length", ell), ("n", n),
                            ("rtol", float(self.rtol)), ("atol", float(self.atol))):
            object.__setattr__(self, name, value)

    @property
    def step_budget(self) -> int:
        """``max_steps``, or the integrator's default budget."""
        return int(DEFAULT_MAX_STEPS[self.integrator] if self.max_steps is None
                   else self.max_steps)

    @classmethod
    def build(cls, options: SolverOptions | None = None, **fields_: Any) -> SolverOptions:
        """``options`` (default: the defaults) with ``fields_`` replaced; an unknown field is
        a ParameterError naming it."""
        base = cls() if options is None else options
        if not isinstance(base, cls):
            raise ParameterError("options", base, "None or a solver.full.SolverOptions")
        known = {f.name for f in fields(cls)}
        unknown = sorted(set(fields_) - known)
        if unknown:
            raise ParameterError(unknown[0], fields_[unknown[0]],
                                 "a keyword of simulate: " + ", ".join(sorted(known)))
        return replace(base, **fields_) if fields_ else base

    def to_dict(self) -> dict[str, Any]:
        """Plain-data form (the mesh as its options)."""
        out = asdict(self)
        out["mesh"] = self.mesh.to_dict() if self.mesh is not None else None
        return out


GRID_NAMES = tuple(GRIDS)
