"""Where a front trajectory starts: the bare initial equilibrium, or a measured (t0, a, R_f).

From the equilibrium the front starts as a shell of zero thickness d = a - R_f at t = 0.  As
d -> 0 the flux constant behaves like A ~ B a^2 / d with B = Omega P(phi_-) + s_- - s_-^(1/3)
(eqs. BVP_Front_BCEdge, BVP_Front_BCFront at R_f = a, s = 1 - phi), so da/dt = k B / d and
solid conservation gives d(d)/dt = -(s_- / (phi_- - phi_+)) da/dt: the shell grows like
d = sqrt(D t), D = 2 k |B| s_- / (phi_- - phi_+).  The quadrature of module evolve contains this
limit exactly; :func:`thin_shell` states it explicitly (used as a check and for plots).

A measured start (e.g. from the full solver, as the paper does at t = 0.001 / 0.01) either keeps
the measured R_f and its solid volume (``conservative=False``: the paper's two ODEs, which
conserve whatever solid volume the measured pair implies) or takes R_f from solid conservation
of the dry bead given the measured radius (``conservative=True``, the product's choice).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import ParameterError, require_finite
from .evolve import front_of_radius
from .flux import edge_value, front_value
from .levels import FrontLevels


@dataclass(frozen=True)
class StartState:
    """The resolved start: time, solid volume Q (units 4 pi/3), front R_f and a label."""

    t0: float
    solid: float
    front: float
    label: str
    diagnostics: dict


def thin_shell_constant(levels: FrontLevels) -> float:
    """B = lim_{d -> 0} A d / a^2 = F - E at R_f = a = a0 (eqs. BVP_Front_BCEdge, BCFront)."""
    return float(front_value(levels) - edge_value(levels, levels.a0))


def thin_shell_rate(levels: FrontLevels) -> float:
    """D in d^2 = D t, the early-time growth of the shrunken shell from the equilibrium."""
    return 2.0 * levels.k_plus * abs(thin_shell_constant(levels)) * levels.s_minus / levels.jump


def thin_shell(levels: FrontLevels, t: np.ndarray | float) -> tuple[np.ndarray, np.ndarray]:
    """Early-time (a, R_f) from the equilibrium: d = sqrt(D t), a = a0 + 2 k B sqrt(t / D)."""
    t = np.asarray(t, dtype=float)
    rate = thin_shell_rate(levels)
    d = np.sqrt(rate * t)
    a = levels.a0 + 2.0 * levels.k_plus * thin_shell_constant(levels) * np.sqrt(t / rate)
    return a, a - d


def resolve_start(levels: FrontLevels, start: tuple[float, ...] | None,
                  conservative: bool = True) -> StartState:
    """The start state for ``start=None`` (equilibrium) or ``start=(t0, a, R_f)``."""
    s_plus, jump = levels.s_plus, levels.jump
    if start is None:
        return StartState(0.0, 1.0, levels.a0, "equilibrium", {})
    try:
        t0, a, rf = (float(v) for v in start)
    except (TypeError, ValueError):
        raise ParameterError("start", start, "None or a tuple (t0, a, R_f)") from None
    t0 = require_finite("start.t0", t0)
    if t0 < 0.0:
        raise ParameterError("start.t0", t0, "t0 >= 0")
    a_centre = (1.0 / s_plus) ** (1.0 / 3.0)
    measured_solid = s_plus * a**3 - jump * rf**3
    diag = {"front_given": rf, "radius_given": a, "solid_given": measured_solid}
    if conservative:
        if not (np.isfinite(a) and a_centre < a <= levels.a0 * (1.0 + 1e-12)):
            raise ParameterError("start.a", a, f"{a_centre:.6g} < a <= a0 = {levels.a0:.6g} "
                                 "(between the front at the centre and the initial radius)")
        a = min(a, levels.a0)
        x = float(front_of_radius(levels, 1.0, a))
        return StartState(t0, 1.0, x, f"full@{t0:g}", diag | {"front_used": x})
    if not (np.isfinite(a) and np.isfinite(rf) and 0.0 < rf < a):
        raise ParameterError("start.front", rf, "0 < R_f < a")
    if measured_solid <= 0.0:
        raise ParameterError("start", start, "a state with positive solid volume")
    return StartState(t0, measured_solid, rf, f"full@{t0:g}", diag | {"front_used": rf})
