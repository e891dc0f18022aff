"""The reduced step-function front model (sec. FrontSoln of the paper).

A swollen core at the initial porosity phi_- and a shrunken shell at phi_+ (P(phi_+) = 0) are
separated by a front R_f(t); the flux constant A follows in closed form from eqs. BVP_Front-
BVP_Front_BCFront and the radius and front evolve by eqs. SphereEvolve_Dimless and FrontEvolve.
"""

from .flux import flux_constant, phi1_plus
from .levels import FrontLevels, front_applicability, front_levels
from .profiles import leading_profiles
from .result import FrontResult, fraction_radius
from .trajectory import front_trajectory

__all__ = [
    "FrontLevels", "FrontResult", "flux_constant", "fraction_radius", "front_applicability",
    "front_levels",
    "front_trajectory", "leading_profiles", "phi1_plus",
]
