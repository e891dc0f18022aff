"""A passive solute (the drug) carried by the pore fluid of the gel.

Concentration per fluid volume on the Lagrangian cells of a full-solver run: advected with
the fluid (fluxes from continuity, exactly conservative), diffusing with a hindered
diffusivity D0 f(phi) (``hindrance``), partition K at the edge, released into a perfect sink
or a well-mixed volume; a batch of sizes releasing into one shared medium (``medium``,
``coupled_release`` imported on first use); Crank's series for the tests (``crank``).
"""

from typing import TYPE_CHECKING

from ..lazy import lazy_names
from .crank import crank_sphere, crank_sphere_finite
from .hindrance import LAWS, Hindrance
from .result import MediumRelease, ReleaseResult
from .transport import Solute, SoluteStart, node_volumes, release, simulate_release

if TYPE_CHECKING:
    from .medium import coupled_release

__getattr__ = lazy_names(__name__, {"coupled_release": ".medium"}, globals())

__all__ = ["LAWS", "Hindrance", "MediumRelease", "ReleaseResult", "Solute", "SoluteStart",
           "coupled_release", "crank_sphere", "crank_sphere_finite", "node_volumes", "release",
           "simulate_release"]
