"""Dimensionless thermodynamics of the gel: free energy, osmotic pressure, stresses.

Stresses are scaled by k_B T / Omega_p, so the neo-Hookean term has unit modulus and the
mixing term carries Omega (eqs. FreeEnergy-MixingEnergy, Stress_Dimless, Osmotic_Dimless).
The scalar kernels are numba functions (``solver.jit.kernel``) so the full solver's kernels
can call them; they also accept numpy arrays from Python.  ``x = 1 - phi = 1/J`` is the
solid fraction.
"""

from __future__ import annotations

import numpy as np

from .gel import Gel
from .jit import kernel


@kernel
def osmotic_p(phi, chi0, chi1):
    """P(phi), with Pi = Omega P(phi) (eq. Osmotic_Dimless, sec. FrontSoln)."""
    x = 1.0 - phi
    return -np.log1p(-x) - x - (chi0 - chi1) * x * x - 2.0 * chi1 * x * x * x


@kernel
def osmotic_dp(phi, chi0, chi1):
    """P'(phi) = dP/dphi (sec. FrontSoln)."""
    x = 1.0 - phi
    return -1.0 / phi + 1.0 + 2.0 * (chi0 - chi1) * x + 6.0 * chi1 * x * x


@kernel
def mixing_energy(jac, chi0, chi1):
    """W_mix / Omega per dry volume: J[phi log phi + chi phi (1-phi)] (eq. MixingEnergy)."""
    x = 1.0 / jac
    return (jac - 1.0) * np.log1p(-x) + (chi0 + chi1 * x) * (1.0 - x)


def osmotic_pressure(gel: Gel, temperature: float, jac: np.ndarray | float) -> np.ndarray | float:
    """Pi(J) = -dW_mix/dJ = Omega P(1 - 1/J) (eq. Osmotic_Dimless)."""
    return gel.omega * osmotic_p(1.0 - 1.0 / np.asarray(jac, dtype=float),
                                 gel.chi0(temperature), gel.chi1(temperature))


def pressure_p(gel: Gel, temperature: float, phi: np.ndarray | float) -> np.ndarray | float:
    """P(phi) at temperature T for this gel (sec. FrontSoln)."""
    return osmotic_p(np.asarray(phi, dtype=float), gel.chi0(temperature), gel.chi1(temperature))


def pressure_dp(gel: Gel, temperature: float, phi: np.ndarray | float) -> np.ndarray | float:
    """P'(phi) at temperature T for this gel (sec. FrontSoln)."""
    return osmotic_dp(np.asarray(phi, dtype=float), gel.chi0(temperature), gel.chi1(temperature))


def terzaghi_stress(stretch: np.ndarray | float, jac: np.ndarray | float) -> np.ndarray | float:
    """Terzaghi (elastic) stress (lambda_i^2 - 1)/J (eq. Stress_Dimless)."""
    lam = np.asarray(stretch, dtype=float)
    return (lam * lam - 1.0) / np.asarray(jac, dtype=float)


def free_energy(gel: Gel, temperature: float, l1: float, l2: float, l3: float) -> float:
    """Dimensionless W(lambda_1, lambda_2, lambda_3; T) (eqs. FreeEnergy-MixingEnergy)."""
    jac = l1 * l2 * l3
    elastic = 0.5 * (l1 * l1 + l2 * l2 + l3 * l3 - 3.0 - 2.0 * np.log(jac))
    return elastic + gel.omega * mixing_energy(jac, gel.chi0(temperature), gel.chi1(temperature))


def normal_energy(gel: Gel, temperature: float, ln: np.ndarray | float, lt: float) -> np.ndarray:
    """W(lambda_n, lambda_t, lambda_t; T) as a function of the normal stretch (eq. Coexistence)."""
    ln = np.asarray(ln, dtype=float)
    jac = ln * lt * lt
    elastic = 0.5 * (ln * ln + 2.0 * lt * lt - 3.0 - 2.0 * np.log(jac))
    return elastic + gel.omega * mixing_energy(jac, gel.chi0(temperature), gel.chi1(temperature))


def normal_stress(gel: Gel, temperature: float, ln: np.ndarray | float, lt: float) -> np.ndarray:
    """dW/dlambda_n at (lambda_n, lambda_t, lambda_t) (eq. Coexistence)."""
    ln = np.asarray(ln, dtype=float)
    jac = ln * lt * lt
    p = osmotic_p(1.0 - 1.0 / jac, gel.chi0(temperature), gel.chi1(temperature))
    return ln - 1.0 / ln - gel.omega * p * lt * lt


def normal_stiffness(gel: Gel, temperature: float, ln: np.ndarray | float, lt: float) -> np.ndarray:
    """d^2W/dlambda_n^2 at (lambda_n, lambda_t, lambda_t) (eq. Spinodal)."""
    ln = np.asarray(ln, dtype=float)
    jac = ln * lt * lt
    dp = osmotic_dp(1.0 - 1.0 / jac, gel.chi0(temperature), gel.chi1(temperature))
    return 1.0 + 1.0 / (ln * ln) - gel.omega * dp * lt**4 / (jac * jac)


def stretch_to_porosity(stretch: np.ndarray | float) -> np.ndarray | float:
    """Isotropic stretch to porosity: phi = 1 - 1/lambda^3 (eq. Jeqn)."""
    return 1.0 - 1.0 / np.asarray(stretch, dtype=float) ** 3


def porosity_to_stretch(phi: np.ndarray | float) -> np.ndarray | float:
    """Porosity to isotropic stretch: lambda = (1 - phi)^(-1/3) (eq. Jeqn)."""
    return (1.0 - np.asarray(phi, dtype=float)) ** (-1.0 / 3.0)
