"""Evolution of the radius a(t) and the front R_f(t) (eqs. SphereEvolve_Dimless, FrontEvolve).

The two ODEs a^2 da/dt = k(phi_+) A and dR_f/dt = (1-phi_+) a^2 (da/dt) / ((phi_- - phi_+) R_f^2)
conserve the solid volume Q = (1-phi_+) a^3 - (phi_- - phi_+) R_f^3 (in units of 4 pi / 3; Q = 1
for the dry bead).  So a is an explicit function of R_f, and time is one quadrature in R_f:

    t(R_f) = t_0 + int_{R_f}^{R_f0} g(x) dx,   g = (phi_- - phi_+) x^2 / ((1-phi_+) k(phi_+) |A|).

With A = N a x / (a - x) (module flux), g = (phi_- - phi_+) x (a - x) / ((1-phi_+) k |N| a) is
smooth on the whole range: it vanishes linearly both at a thin shell (x -> a, where A ~ 1/d and
d grows like sqrt(t)) and at the centre (x -> 0, where A ~ x).  So neither the start from the
bare equilibrium nor the front reaching the centre needs special treatment: a Chebyshev
interpolant of g, integrated exactly, gives t(R_f) to round-off (its tail is checked).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.polynomial import Chebyshev

from ..errors import NotApplicableError, SolverError
from ..jit import kernel
from .flux import flux_numerator
from .levels import FrontLevels

Array = np.ndarray
CHEB_DEGREES = (48, 96, 192, 384)
CHEB_TAIL = 1e-13
NEWTON_STEPS = 60


def radius_of_front(levels: FrontLevels, solid: float, front: Array | float) -> Array | float:
    """a(R_f) from solid conservation (1-phi_+) a^3 - (phi_- - phi_+) R_f^3 = Q (FrontEvolve)."""
    return np.cbrt((solid + levels.jump * np.asarray(front) ** 3) / levels.s_plus)


def front_of_radius(levels: FrontLevels, solid: float, radius: Array | float) -> Array | float:
    """R_f(a), the inverse of :func:`radius_of_front`."""
    return np.cbrt((levels.s_plus * np.asarray(radius) ** 3 - solid) / levels.jump)


@kernel
def _clenshaw(coef, lo, hi, x):
    """Chebyshev series with domain [lo, hi] at scalar x (Clenshaw recurrence)."""
    y = (2.0 * x - lo - hi) / (hi - lo)
    b1 = 0.0
    b2 = 0.0
    for k in range(coef.size - 1, 0, -1):
        b1, b2 = coef[k] + 2.0 * y * b1 - b2, b1
    return coef[0] + y * b1 - b2


@kernel
def _invert_decreasing(cf, cd, lo, hi, targets, tol, steps):
    """Solve F(x) = y on [lo, hi] for each target, F decreasing with F' = -D (Chebyshev
    series cf, cd on [lo, hi]): bracketed Newton, bisection when a step leaves the bracket."""
    out = np.empty(targets.size)
    f_lo = _clenshaw(cf, lo, hi, lo)
    f_hi = _clenshaw(cf, lo, hi, hi)
    for i in range(targets.size):
        y = min(max(targets[i], f_hi), f_lo)
        a, b = lo, hi
        x = lo + (f_lo - y) / (f_lo - f_hi) * (hi - lo) if f_lo > f_hi else lo
        for _ in range(steps):
            r = _clenshaw(cf, lo, hi, x) - y
            if abs(r) <= tol:
                break
            if r > 0.0:
                a = x
            else:
                b = x
            d = -_clenshaw(cd, lo, hi, x)
            step = x - r / d if d != 0.0 else a - 1.0
            x = step if a < step < b else 0.5 * (a + b)
        out[i] = x
    return out


@dataclass
class FrontCurve:
    """One front trajectory in the front position x = R_f: a(x), A(x), t(x) and inverses.

    ``radius(x)``/``front(a)`` map between R_f and a (solid conservation), ``rate`` is the
    Chebyshev interpolant of g = -dt/dR_f on [0, x_start]; ``t_centre`` is t(R_f = 0).
    """

    levels: FrontLevels
    solid: float
    t_start: float
    x_start: float
    radius: Callable[[Array], Array]
    front: Callable[[Array], Array]
    flux: Callable[[Array], Array]
    rate: Chebyshev

    def __post_init__(self) -> None:
        self._integral = self.rate.integ(lbnd=self.x_start)
        self.t_centre = float(self.time_of_front(0.0))

    def time_of_front(self, x: Array | float) -> Array | float:
        """t when the front is at R_f = x."""
        if np.ndim(x) == 0:
            c = self._integral.coef
            return self.t_start - _clenshaw(c, 0.0, self.x_start, float(x))
        return self.t_start - self._integral(x)

    def front_at(self, t: Array | float) -> Array:
        """R_f(t) on [t_start, t_centre] (bracketed Newton on t(R_f); clipped to the range)."""
        tol = 1e-14 * max(1.0, abs(self.t_centre))
        cf = -self._integral.coef.copy()
        cf[0] += self.t_start
        y = np.atleast_1d(np.asarray(t, dtype=float))
        return _invert_decreasing(cf, self.rate.coef, 0.0, self.x_start, y, tol, NEWTON_STEPS)


def chebyshev_rate(g: Callable[[Array], Array], x_start: float) -> Chebyshev:
    """Chebyshev interpolant of g on [0, x_start], degree doubled until its last coefficients
    are round-off (CHEB_TAIL relative to the largest)."""
    for deg in CHEB_DEGREES:
        cheb = Chebyshev.interpolate(g, deg, domain=[0.0, x_start])
        scale = np.max(np.abs(cheb.coef))
        if not np.all(np.isfinite(cheb.coef)):
            break
        if np.max(np.abs(cheb.coef[-3:])) <= CHEB_TAIL * scale:
            return cheb
    raise SolverError("front model: the time quadrature did not converge",
                      {"degree": deg, "tail": float(np.max(np.abs(cheb.coef[-3:]))),
                       "x_start": x_start})


def check_expels(levels: FrontLevels, radius: Callable[[Array], Array], x_start: float) -> None:
    """NotApplicableError unless the flux expels fluid (N < 0, A < 0) for 0 <= R_f <= x_start."""
    nodes = x_start * 0.5 * (1.0 + np.cos(np.linspace(0.0, np.pi, 65)))
    numer = flux_numerator(levels, radius(nodes), nodes)
    if not np.all(numer < 0.0):
        x_bad = float(nodes[np.argmax(numer)])
        raise NotApplicableError(
            f"front model not applicable: the leading-order flux does not expel fluid at "
            f"R_f={x_bad:.4g} (A >= 0), so the front stalls before the centre")


def shell_flux(levels: FrontLevels, radius: Callable[[Array], Array]) -> Callable[[Array], Array]:
    """x -> A(a(x), x), the flux constant along a trajectory (-inf for a zero-thickness shell)."""

    def flux(x: Array) -> Array:
        a = radius(x)
        with np.errstate(divide="ignore"):
            return flux_numerator(levels, a, x) * a * x / (a - x)

    return flux


def leading_curve(levels: FrontLevels, t_start: float, x_start: float,
                  solid: float = 1.0) -> FrontCurve:
    """The leading-order step-function trajectory from R_f = x_start at t_start to the centre."""
    sp, c, k = levels.s_plus, levels.jump, levels.k_plus

    def radius(x: Array) -> Array:
        return radius_of_front(levels, solid, x)

    check_expels(levels, radius, x_start)

    def g(x: Array) -> Array:
        a = radius(x)
        return c * x * (a - x) / (sp * k * (-flux_numerator(levels, a, x)) * a)

    return FrontCurve(levels=levels, solid=solid, t_start=t_start, x_start=x_start,
                      radius=radius, front=lambda a: front_of_radius(levels, solid, a),
                      flux=shell_flux(levels, radius), rate=chebyshev_rate(g, x_start))
