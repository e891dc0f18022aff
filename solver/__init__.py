"""thermogel physics: gel model, equilibria, phase map, full PDE solver, front model.

Everything here is dimensionless as in Butler & Montenegro-Johnson (lengths by the dry
radius, time by tau of eq. timescale, stresses by k_B T / Omega_p); temperatures in K.
"""

from __future__ import annotations

import sys
import types
from typing import TYPE_CHECKING, Any

from .errors import NotApplicableError, ParameterError, SolverError
from .gel import ANB, HHT, PRESETS, Gel, Permeability, as_gel, check_temperature, preset
from .lazy import lazy_names

if TYPE_CHECKING:
    from .equilibrium import (
        Equilibrium,
        Fold,
        equilibria,
        equilibrium,
        equilibrium_curve,
        folds,
    )
    from .phase import JumpClass, classify_jump, coexistence_curve, spinodal_curve

# imported on first use (PEP 562): scipy.optimize and numba load only when a caller needs
# an equilibrium or the phase map, not with ``solver.errors`` or ``solver.gel``
_LAZY = {**dict.fromkeys(("Equilibrium", "Fold", "equilibria", "equilibrium",
                          "equilibrium_curve", "folds"), ".equilibrium"),
         **dict.fromkeys(("JumpClass", "classify_jump", "coexistence_curve",
                          "spinodal_curve"), ".phase")}


class _Package(types.ModuleType):
    """This package's module type: the import system binds a submodule on its package once
    loaded, and the function ``equilibrium`` has always shadowed its module here."""

    def __setattr__(self, name: str, value: Any) -> None:
        if name in _LAZY and isinstance(value, types.ModuleType):
            value = getattr(value, name)
        super().__setattr__(name, value)


sys.modules[__name__].__class__ = _Package


__getattr__ = lazy_names(__name__, _LAZY, globals())

__all__ = [
    "ANB", "HHT", "PRESETS", "Equilibrium", "Fold", "Gel", "JumpClass", "NotApplicableError",
    "ParameterError", "Permeability", "SolverError", "as_gel", "check_temperature", "classify_jump",
    "coexistence_curve", "equilibria", "equilibrium", "equilibrium_curve", "folds", "preset",
    "spinodal_curve",
]
