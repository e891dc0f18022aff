"""The flux constant A and the shell perturbation phi1_+ in closed form (eqs. BVP_Front-BCFront).

Eq. BVP_Front is linear in phi1_+ and its forcing is an exact derivative: with
f(r)^3 = s_+ - (s_+ - s_-)(R_f/r)^3 (s = 1 - phi), substituting w = f^3 gives

    int_{R_f}^{r} -2 (phi_+ - phi_-)^2 R_f^6 / ((1-phi_+) f^2 x^7) dx = -[h(f)]_{f(R_f)}^{f(r)},
    h(f) = 2 f - f^4 / (2 (1 - phi_+)).

So P'(phi_+) phi1_+(r) = F - [h]_{f_-}^{f(r)} - A (1/R_f - 1/r) with F the front condition
(eq. BVP_Front_BCFront, with the core's osmotic pressure Omega P(phi_-)), and the edge condition
(eq. BVP_Front_BCEdge, value E) fixes A = (F - E - [h]_{f_-}^{f(a)}) a R_f / (a - R_f).
Everything here is vectorised numpy; scipy's solve_bvp cross-checks it in the tests.
"""

from __future__ import annotations

import numpy as np

from ..gel import Gel
from ..thermo import osmotic_dp, osmotic_p
from .levels import FrontLevels


def _h(f: np.ndarray | float, s_plus: float) -> np.ndarray | float:
    """Antiderivative of the Terzaghi forcing of eq. BVP_Front in the variable f (module doc)."""
    return 2.0 * f - f**4 / (2.0 * s_plus)


def shell_f(levels: FrontLevels, front: np.ndarray | float,
            r: np.ndarray | float) -> np.ndarray | float:
    """f(r) = [(1-phi_+) + (phi_+ - phi_-)(R_f/r)^3]^(1/3), the cube root of the mean solid
    fraction inside r (sec. FrontSoln)."""
    return np.cbrt(levels.s_plus - levels.jump * (front / r) ** 3)


def front_value(levels: FrontLevels) -> float:
    """P'(phi_+) phi1_+ at r = R_f (eq. BVP_Front_BCFront, last term Omega P(phi_-))."""
    sm, sp = levels.s_minus, levels.s_plus
    return sm ** (4.0 / 3.0) * (1.0 / sp - 1.0 / sm) + (sm - sp) + levels.omega_p_minus


def edge_value(levels: FrontLevels, radius: np.ndarray | float) -> np.ndarray | float:
    """P'(phi_+) phi1_+ at r = a (eq. BVP_Front_BCEdge)."""
    sp = levels.s_plus
    return 1.0 / (radius**4 * sp) - sp


def flux_numerator(levels: FrontLevels, radius: np.ndarray | float,
                   front: np.ndarray | float) -> np.ndarray | float:
    """N = A (1/R_f - 1/a): the driving stress difference across the shell (module doc)."""
    sp = levels.s_plus
    fa = shell_f(levels, front, radius)
    fm = np.cbrt(levels.s_minus)
    return front_value(levels) - edge_value(levels, radius) - (_h(fa, sp) - _h(fm, sp))


def flux_from_levels(levels: FrontLevels, radius: np.ndarray | float,
                     front: np.ndarray | float) -> np.ndarray | float:
    """The flux constant A of eq. ChemPotential_Const, dmu/dr = A / r^2 in the shell."""
    return flux_numerator(levels, radius, front) * radius * front / (radius - front)


def phi1_plus_from_levels(levels: FrontLevels, radius: float, front: float,
                          r: np.ndarray | float) -> np.ndarray | float:
    """The shell porosity perturbation phi1_+(r) solving eqs. BVP_Front-BVP_Front_BCFront."""
    sp = levels.s_plus
    amp = flux_from_levels(levels, radius, front)
    hr = _h(shell_f(levels, front, r), sp) - _h(np.cbrt(levels.s_minus), sp)
    return (front_value(levels) - hr - amp * (1.0 / front - 1.0 / r)) / levels.dp_plus


def levels_at(gel: Gel, temperature: float, phi_minus: float, phi_plus: float) -> FrontLevels:
    """FrontLevels for explicit porosities at T_end (no classification; a0 from phi_-)."""
    chi0, chi1 = gel.chi0(temperature), gel.chi1(temperature)
    return FrontLevels(
        t_start=float("nan"), t_end=float(temperature), branch="swollen",
        a0=float((1.0 - phi_minus) ** (-1.0 / 3.0)), phi_minus=float(phi_minus),
        phi_plus=float(phi_plus), omega=gel.omega,
        omega_p_minus=gel.omega * float(osmotic_p(phi_minus, chi0, chi1)),
        dp_plus=float(osmotic_dp(phi_plus, chi0, chi1)),
        k_plus=float(gel.permeability(phi_plus)), behaviour="front",
        permeability=gel.permeability)


def flux_constant(radius: float, front: float, phi_minus: float, phi_plus: float, gel: Gel,
                  temperature: float) -> float:
    """A(a, R_f; phi_-, phi_+) at T_end from the closed form (eqs. BVP_Front-BVP_Front_BCFront).

    With dmu/dr = A / r^2, A = a^2 da/dt / k(phi_+) (eq. SphereEvolve_Dimless).  Requires
    0 < R_f < a.
    """
    _check_shell(radius, front)
    return float(flux_from_levels(levels_at(gel, temperature, phi_minus, phi_plus),
                                  float(radius), float(front)))


def phi1_plus(r: np.ndarray | float, radius: float, front: float, phi_minus: float,
              phi_plus: float, gel: Gel, temperature: float) -> np.ndarray | float:
    """phi1_+(r) on R_f <= r <= a, the O(1/Omega) shell porosity (eq. BVP_Front), closed form."""
    _check_shell(radius, front)
    lev = levels_at(gel, temperature, phi_minus, phi_plus)
    return phi1_plus_from_levels(lev, float(radius), float(front), np.asarray(r, dtype=float))


def _check_shell(radius: float, front: float) -> None:
    from ..errors import ParameterError

    if not (np.isfinite(radius) and radius > 0):
        raise ParameterError("radius", radius, "a finite number > 0")
    if not (np.isfinite(front) and 0.0 < front < radius):
        raise ParameterError("front", front, f"0 < R_f < a = {radius:g}")
