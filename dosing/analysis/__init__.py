"""Release data as a pharmaceutics lab analyses it (issue 38, docs/release_analysis.md):
profiles read and checked (``profiles``), the empirical model zoo (``empirical``), f1/f2
with the FDA rules and Shah's bootstrap (``similarity``)."""

from .empirical import MODELS, EmpiricalModel, EmpiricalResult, ModelFit, fit_empirical
from .profiles import Profile, from_arrays, read_profile
from .similarity import Comparison
from .similarity import compare as compare_profiles

__all__ = ["MODELS", "Comparison", "EmpiricalModel", "EmpiricalResult", "ModelFit", "Profile",
           "compare_profiles", "fit_empirical", "from_arrays", "read_profile"]
