"""The step-function front model made consistent with the sharp-interface limit.

With an interfacial energy and ell -> 0 (docs/interfacial.md, sec. 5) the front carries one
more condition than the paper imposes: both sides sit at the coexisting (Maxwell) pair of
W(., lambda_t) at the front's tangential stretch (module maxwell).  In the shell this replaces
the front condition of eq. BVP_Front_BCFront, P'(phi_+) phi1_+ = F, by the Maxwell level,

    F_M = Omega P(phi_shell^M(lambda_t)),   lambda_t = (1 - phi_-)^(-1/3),

(the paper's F follows from [sigma_r] = [mu] = 0 with the core at phi_-, which the Maxwell
condition overrides).  The rest of the model is the paper's: the core at phi_-, the shell at
phi_+ (P(phi_+) = 0) to leading order, eqs. SphereEvolve_Dimless and FrontEvolve, started
from the initial equilibrium.  The paper's model stays in module trajectory.
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np

from ..equilibrium import Branch
from ..errors import NotApplicableError
from ..gel import Gel, as_gel
from ..thermo import osmotic_p
from .evolve import (
    Array,
    FrontCurve,
    chebyshev_rate,
    front_of_radius,
    radius_of_front,
)
from .flux import flux_numerator, front_value
from .levels import FrontLevels, front_applicability, front_levels
from .maxwell import maxwell_porosities
from .result import FrontResult
from .start import resolve_start
from .trajectory import sample_curve


@lru_cache(maxsize=256)
def sharp_front_value(gel: Gel, t_start: float, t_end: float,
                      branch: Branch | None = None) -> float:
    """F_M = Omega P(phi_shell^M) at the core's stretch (module doc); cached per jump."""
    levels = front_levels(gel, t_start, t_end, branch)
    phi_shell, _ = maxwell_porosities(gel, levels.t_end, levels.s_minus ** (-1.0 / 3.0))
    return gel.omega * float(osmotic_p(phi_shell, gel.chi0(levels.t_end), gel.chi1(levels.t_end)))


def sharp_curve(levels: FrontLevels, value: float, t_start: float, x_start: float,
                solid: float = 1.0) -> FrontCurve:
    """The trajectory with the shell's front condition F_M = ``value`` (module doc)."""
    sp, c, k = levels.s_plus, levels.jump, levels.k_plus
    shift = value - front_value(levels)

    def radius(x: Array) -> Array:
        return radius_of_front(levels, solid, x)

    def numer(x: Array) -> Array:
        return flux_numerator(levels, radius(x), x) + shift

    nodes = x_start * 0.5 * (1.0 + np.cos(np.linspace(0.0, np.pi, 65)))
    if not np.all(numer(nodes) < 0.0):
        raise NotApplicableError("sharp front model not applicable: the flux does not expel "
                                 "fluid everywhere on the way to the centre")

    def g(x: Array) -> Array:
        a = radius(x)
        return c * x * (a - x) / (sp * k * (-numer(x)) * a)

    def flux(x: Array) -> Array:
        a = radius(x)
        with np.errstate(divide="ignore"):
            return numer(x) * a * x / (a - x)

    return FrontCurve(levels=levels, solid=solid, t_start=t_start, x_start=x_start,
                      radius=radius, front=lambda a: front_of_radius(levels, solid, a),
                      flux=flux, rate=chebyshev_rate(g, x_start))


def sharp_front_trajectory(gel: Gel, t_start: float, t_end: float, *,
                           branch: Branch | None = None,
                           start: tuple[float, float, float] | None = None,
                           until: float | None = None, target_radius: float | None = None,
                           every: float | None = None, n: int = 201) -> FrontResult:
    """The sharp-interface-consistent front model after T_start -> T_end (module doc).

    Same inputs, stops and result as :func:`solver.front.front_trajectory` (conservative
    starts only); ``model`` is ``front-sharp``.
    """
    gel = as_gel(gel)
    levels = front_levels(gel, t_start, t_end, branch)
    value = sharp_front_value(gel, float(t_start), float(t_end), branch)
    st = resolve_start(levels, start, True)
    curve = sharp_curve(levels, value, st.t0, st.front, st.solid)
    return sample_curve(levels, st, curve, until, target_radius, every, n, "front-sharp",
                        {"applicability": front_applicability(gel, t_start, t_end, branch)[1],
                         "front_value": value, "paper_front_value": front_value(levels)})
