"""A passive solute (the drug) carried by the pore fluid of the gel.

Concentration per fluid volume on the Lagrangian cells of a full-solver run: advected with
the fluid (fluxes from continuity, exactly conservative), diffusing with a hindered
diffusivity D0 f(phi) (``hindrance``), partition K at the edge, released into a perfect sink
or a well-mixed volume; Crank's series for the tests (``crank``).
"""

from .crank import crank_sphere, crank_sphere_finite
from .hindrance import LAWS, Hindrance
from .result import ReleaseResult
from .transport import Solute, SoluteStart, node_volumes, release, simulate_release

__all__ = ["LAWS", "Hindrance", "ReleaseResult", "Solute", "SoluteStart", "crank_sphere",
           "crank_sphere_finite", "node_volumes", "release", "simulate_release"]
