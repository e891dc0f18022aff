"""Free-swelling equilibria (eq. EqlEqn) on every branch, their stability, and the folds.

The residual of eq. EqlEqn, g(lambda; T) = (lambda^2-1)/lambda^3 - Omega P(1 - lambda^-3)
(= dW/dlambda / (3 lambda^2)), is affine in T because chi_0 and chi_1 are
(eq. FloryParam): g = c(lambda) + T d(lambda).  So the equilibrium curve is explicit,
T(lambda) = -c/d, its folds are the zeros of c'd - c d', and at a given T every root is
bracketed between consecutive critical points of g, where g is monotone.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass
from functools import lru_cache
from typing import Literal

import numpy as np

from .errors import ParameterError
from .gel import T_MAX, T_MIN, Gel, as_gel, check_temperature
from .roots import brentq
from .thermo import osmotic_p

LAMBDA_MIN = 1.0 + 1e-10
LAMBDA_MAX = 1.0e3
_GRID = np.exp(np.linspace(np.log(LAMBDA_MIN - 1.0), np.log(LAMBDA_MAX - 1.0), 6001)) + 1.0

Branch = Literal["swollen", "shrunken"]


@dataclass(frozen=True)
class Equilibrium:
    """One free-swelling equilibrium: isotropic stretch, porosity and linear stability."""

    temperature: float
    stretch: float
    porosity: float
    stable: bool

    def to_dict(self) -> dict[str, float | bool]:
        """Plain-data form."""
        return asdict(self)


@dataclass(frozen=True)
class Fold:
    """A fold (volume-phase transition) of the equilibrium curve.

    ``kind`` is ``"shrink"`` at a local maximum of T(lambda) (heating past it loses the
    swollen equilibria) and ``"swell"`` at a local minimum (cooling past it loses the
    shrunken ones).
    """

    temperature: float
    stretch: float
    kind: Literal["shrink", "swell"]

    def to_dict(self) -> dict[str, float | str]:
        """Plain-data form."""
        return asdict(self)


def _parts(gel: Gel, lam: np.ndarray | float) -> tuple:
    """c, d and their lambda-derivatives with g(lambda; T) = c + T d (eq. EqlEqn)."""
    lam = np.asarray(lam, dtype=float)
    x = lam**-3.0
    om = gel.omega
    da, db = gel.a0 - gel.a1, gel.b0 - gel.b1
    with np.errstate(invalid="ignore"):  # NaN below lambda = 1, as the compiled kernel
        p0 = osmotic_p(1.0 - x, 0.0, 0.0)
    elastic = (lam * lam - 1.0) / lam**3
    c = elastic - om * p0 + om * (da * x * x + 2.0 * gel.a1 * x**3)
    d = om * (db * x * x + 2.0 * gel.b1 * x**3)
    dx = -3.0 * x / lam
    dp0 = x / (1.0 - x) * dx
    dc = -1.0 / lam**2 + 3.0 / lam**4 - om * dp0 + om * (2.0 * da * x + 6.0 * gel.a1 * x * x) * dx
    dd = om * (2.0 * db * x + 6.0 * gel.b1 * x * x) * dx
    return c, d, dc, dd


def residual(gel: Gel, temperature: float, stretch: np.ndarray | float) -> np.ndarray | float:
    """Left side of eq. EqlEqn, (lambda^2-1)/lambda^3 - Omega P(phi)."""
    lam = np.asarray(stretch, dtype=float)
    phi = -np.expm1(-3.0 * np.log(lam))
    p = osmotic_p(phi, gel.chi0(temperature), gel.chi1(temperature))
    return (lam * lam - 1.0) / lam**3 - gel.omega * p


def residual_slope(gel: Gel, temperature: float, stretch: np.ndarray | float) -> np.ndarray | float:
    """d/dlambda of eq. EqlEqn's left side; > 0 at a root means a stable equilibrium."""
    _, _, dc, dd = _parts(gel, stretch)
    return dc + temperature * dd


def energy_slope(gel: Gel, temperature: float, stretch: np.ndarray | float) -> np.ndarray | float:
    """dW/dlambda of the free-swelling energy (eq. FreeSwellEnergy) = 3 lambda^2 g."""
    lam = np.asarray(stretch, dtype=float)
    return 3.0 * lam * lam * residual(gel, temperature, lam)


def _sign_change_roots(f, grid: np.ndarray, values: np.ndarray) -> list[float]:
    """Every root of f bracketed by a sign change of ``values`` on ``grid`` (brentq)."""
    roots: list[float] = []
    s = np.sign(values)
    for i in np.nonzero(s[:-1] * s[1:] <= 0)[0]:
        if s[i] == 0:
            roots.append(float(grid[i]))
            continue
        if s[i + 1] == 0:
            continue
        roots.append(brentq(f, grid[i], grid[i + 1], xtol=1e-15, rtol=1e-15, maxiter=200))
    return roots


def equilibria(gel: Gel, temperature: float) -> list[Equilibrium]:
    """All free-swelling equilibria at T, smallest stretch first (eq. EqlEqn).

    Roots are bracketed between the critical points of the residual (where it is
    monotone), then found with brentq; no Newton iteration from a guess.  Results are
    memoised per (gel, T): the gel is immutable and the planner asks the same often.
    """
    gel = as_gel(gel)
    return list(_equilibria(gel, check_temperature(temperature)))


@lru_cache(maxsize=4096)
def _equilibria(gel: Gel, t: float) -> tuple[Equilibrium, ...]:
    _, _, dc, dd = _parts(gel, _GRID)
    slope = dc + t * dd
    crit = _sign_change_roots(lambda lam: residual_slope(gel, t, lam), _GRID, slope)
    knots = np.array([_GRID[0], *crit, _GRID[-1]])
    vals = residual(gel, t, knots)
    roots = _sign_change_roots(lambda lam: residual(gel, t, lam), knots, vals)
    roots = sorted({round(r, 13): r for r in roots}.values())
    out = []
    for lam in roots:
        out.append(Equilibrium(temperature=t, stretch=float(lam),
                               porosity=float(1.0 - lam**-3.0),
                               stable=bool(residual_slope(gel, t, lam) > 0.0)))
    return tuple(out)


def equilibrium(gel: Gel, temperature: float, branch: Branch = "swollen") -> Equilibrium:
    """The stable equilibrium on the named branch: the most swollen or the most shrunken."""
    gel = as_gel(gel)
    if branch not in ("swollen", "shrunken"):
        raise ParameterError("branch", branch, "'swollen' or 'shrunken'")
    stable = _stable(gel, temperature)
    return stable[-1] if branch == "swollen" else stable[0]


def _stable(gel: Gel, temperature: float) -> list[Equilibrium]:
    """The stable equilibria at T; ParameterError when the gel has none (it is dry there)."""
    stable = [e for e in equilibria(gel, temperature) if e.stable]
    if not stable:
        raise ParameterError(
            "temperature", temperature,
            f"a temperature at which this gel holds fluid (porosity > {1 - LAMBDA_MIN**-3:.0e})",
            "the gel is dry at this temperature")
    return stable


def nearest_stable(gel: Gel, temperature: float, stretch: float) -> Equilibrium:
    """The stable equilibrium a uniform state at ``stretch`` relaxes to at T.

    dW/dlambda > 0 means the energy falls as the gel shrinks, so it goes to the nearest
    stable root below; otherwise to the nearest stable root above.
    """
    gel = as_gel(gel)
    eqs = _stable(gel, temperature)
    g = residual(gel, temperature, stretch)
    if g > 0:
        below = [e for e in eqs if e.stretch <= stretch]
        return below[-1] if below else eqs[0]
    above = [e for e in eqs if e.stretch >= stretch]
    return above[0] if above else eqs[-1]


def folds(gel: Gel, t_min: float = T_MIN, t_max: float = T_MAX) -> list[Fold]:
    """Fold temperatures of the equilibrium curve in [t_min, t_max], ascending in T."""
    gel = as_gel(gel)
    c, d, dc, dd = _parts(gel, _GRID)
    h = dc * d - c * dd

    def hfun(lam: float) -> float:
        ci, di, dci, ddi = _parts(gel, lam)
        return float(dci * di - ci * ddi)

    out = []
    for lam in _sign_change_roots(hfun, _GRID, h):
        ci, di, _, _ = _parts(gel, lam)
        if di == 0.0:
            continue
        t = float(-ci / di)
        if not (t_min <= t <= t_max):
            continue
        eps = 1e-6 * lam
        tl = float(-residual(gel, 0.0, lam - eps) / _parts(gel, lam - eps)[1])
        tr = float(-residual(gel, 0.0, lam + eps) / _parts(gel, lam + eps)[1])
        kind = "shrink" if t >= max(tl, tr) else "swell"
        out.append(Fold(temperature=t, stretch=float(lam), kind=kind))
    return sorted(out, key=lambda f: f.temperature)


@dataclass(frozen=True)
class EquilibriumCurve:
    """The whole equilibrium curve T(lambda) over a temperature window, with stability."""

    stretch: np.ndarray
    temperature: np.ndarray
    stable: np.ndarray


def equilibrium_curve(gel: Gel, t_min: float = T_MIN, t_max: float = T_MAX,
                      n: int = 4000, lambda_max: float = 10.0) -> EquilibriumCurve:
    """Every equilibrium (all branches) with T in [t_min, t_max], ordered by stretch."""
    gel = as_gel(gel)
    lam = np.exp(np.linspace(np.log(LAMBDA_MIN - 1.0), np.log(lambda_max - 1.0), n)) + 1.0
    c, d, dc, dd = _parts(gel, lam)
    with np.errstate(divide="ignore", invalid="ignore"):
        t = -c / d
    keep = np.isfinite(t) & (t >= t_min) & (t <= t_max)
    stable = (dc + t * dd) > 0
    return EquilibriumCurve(stretch=lam[keep], temperature=t[keep], stable=stable[keep])
