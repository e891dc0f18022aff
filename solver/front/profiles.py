"""Leading-order profiles of the step-function front, for plots against the full solver.

Paper figs. 11-12.  Core (r < R_f): uniform phi_-, isotropic stretch (1-phi_-)^(-1/3), no
flux.  Shell (R_f < r <= a): phi_+ + phi1_+(r) / Omega, stretches eq. Front_Strain_theta and
lambda_r = f^2 / (1-phi_+), Terzaghi stresses to eq. Front_Stress_r, and dmu/dr = A / r^2
(eq. ChemPotential_Const).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .flux import flux_from_levels, phi1_plus_from_levels, shell_f
from .levels import FrontLevels


@dataclass(frozen=True)
class FrontProfiles:
    """Radial profiles at one instant: r and the fields on it (arrays of the same shape)."""

    r: np.ndarray
    porosity: np.ndarray          # phi_-, or phi_+ + phi1_+ / Omega in the shell
    porosity_leading: np.ndarray  # the step function phi_- / phi_+
    phi1: np.ndarray              # phi1_+ in the shell, 0 in the core
    stretch_theta: np.ndarray
    stretch_r: np.ndarray
    stress_theta: np.ndarray      # Terzaghi stresses, eq. Stress_Dimless at leading order
    stress_r: np.ndarray
    dmu_dr: np.ndarray


def leading_profiles(levels: FrontLevels, radius: float, front: float,
                     r: np.ndarray | None = None, n: int = 400) -> FrontProfiles:
    """Profiles on ``r`` (default n points on [0, a]) for a front at R_f inside radius a."""
    r = np.linspace(0.0, radius, n) if r is None else np.asarray(r, dtype=float)
    sm, sp = levels.s_minus, levels.s_plus
    shell = r > front
    rs = np.where(shell, r, radius)  # evaluate shell formulas only on shell points
    f = shell_f(levels, front, rs)
    lam_core = sm ** (-1.0 / 3.0)
    stress_core = sm ** (1.0 / 3.0) - sm
    phi1 = np.where(shell, phi1_plus_from_levels(levels, radius, front, rs), 0.0)
    amp = flux_from_levels(levels, radius, front)
    return FrontProfiles(
        r=r,
        porosity=np.where(shell, levels.phi_plus + phi1 / levels.omega, levels.phi_minus),
        porosity_leading=np.where(shell, levels.phi_plus, levels.phi_minus),
        phi1=phi1,
        stretch_theta=np.where(shell, 1.0 / f, lam_core),
        stretch_r=np.where(shell, f * f / sp, lam_core),
        stress_theta=np.where(shell, sp * (f**-2 - 1.0), stress_core),
        stress_r=np.where(shell, (f**4 - sp * sp) / sp, stress_core),
        dmu_dr=np.where(shell, amp / np.where(shell, rs, 1.0) ** 2, 0.0),
    )
