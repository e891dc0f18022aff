"""Fitting the model to measurements: equilibrium swelling (eq. EqlEqn) and shrinking kinetics.

Dimensionless as the rest of ``solver`` (sizes in the data's own unit, times by tau);
CSV files, units and the store of fitted gels live in ``dosing.fit``.
"""

from .equilibrium import PARAMS, SwellingData, curve_band, fit_equilibrium, fit_gel, transitions
from .result import FitResult

__all__ = ["PARAMS", "FitResult", "SwellingData", "curve_band", "fit_equilibrium", "fit_gel",
           "transitions"]
