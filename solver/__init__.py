"""thermogel physics: gel model, equilibria, phase map, full PDE solver, front model.

Everything here is dimensionless as in Butler & Montenegro-Johnson (lengths by the dry
radius, time by tau of eq. timescale, stresses by k_B T / Omega_p); temperatures in K.
"""

from .equilibrium import Equilibrium, Fold, equilibria, equilibrium, equilibrium_curve, folds
from .errors import NotApplicableError, ParameterError, SolverError
from .gel import ANB, HHT, PRESETS, Gel, Permeability, as_gel, check_temperature, preset
from .phase import JumpClass, classify_jump, coexistence_curve, spinodal_curve

__all__ = [
    "ANB", "HHT", "PRESETS", "Equilibrium", "Fold", "Gel", "JumpClass", "NotApplicableError",
    "ParameterError", "Permeability", "SolverError", "as_gel", "check_temperature", "classify_jump",
    "coexistence_curve", "equilibria", "equilibrium", "equilibrium_curve", "folds", "preset",
    "spinodal_curve",
]
