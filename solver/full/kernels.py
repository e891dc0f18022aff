"""Numba kernels shared by both grids: permeability and the edge condition.

The edge condition (eq. Boundary_Dimless) sets the edge porosity from the edge radius a:
sigma'_r = Pi with lambda_theta = a, i.e. g(J) = J/a^4 - 1/J - Omega P(1 - 1/J) = 0.
It is the normal stress balance dW/dlambda_n(lambda_n; a, a) = 0, so its roots with
dg/dJ > 0 are the local minima of W in the normal stretch.  Where several exist (e.g. ANB
302 -> 306 K at the start), the edge takes the minimum whose basin holds the adjacent
cell's porosity: it continues the interior state, and jumps to the other branch only when
that minimum disappears (the paper's delayed front).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import njit

from .. import thermo

# numba kernels call the dispatchers (solver.jit)
osmotic_p = thermo.osmotic_p.compiled
osmotic_dp = thermo.osmotic_dp.compiled


class KernelParams(NamedTuple):
    """The constants of one protocol segment, by name, as every grid's kernels read them.

    ``omega`` and ``chi0``, ``chi1`` at the segment's temperature (eq. FloryParam), the
    permeability law ``perm_code`` with its exponent ``perm_beta`` (eq. Darcy), ``ell2``,
    the square of the interfacial length (0: the paper's model; docs/interfacial.md), and
    ``mobility`` m(T), the rate factor of the temperature's mobility relative to the
    reference temperature of tau (1: the paper's choice; docs/heating.md): every grid's
    material velocity k(phi) dmu/dr is multiplied by it.  A NamedTuple is a numba tuple
    type: fields cost no more than a float array's entries.
    """

    omega: float
    chi0: float
    chi1: float
    perm_code: int
    perm_beta: float
    ell2: float
    mobility: float = 1.0


@njit(cache=True)
def scale_rate(m, out, jband, jc, jd, je):
    """Multiply a rate vector and its Jacobian blocks by the mobility m (in place)."""
    if m == 1.0:
        return
    out *= m
    jband *= m
    jc *= m
    jd *= m
    je *= m


EDGE_MAX_STEP = 0.05  # largest march step in log J while bracketing the edge root


@njit(cache=True)
def permeability(phi, code, beta):
    """k(phi): 1 (code 0) or phi / (1 - phi)^beta (code 1, eq. Permeability)."""
    if code == 0:
        return 1.0
    return phi / (1.0 - phi) ** beta


@njit(cache=True)
def _edge_g(z, a4, omega, chi0, chi1):
    """g at J = e^z and its z-derivative (eq. Boundary_Dimless)."""
    jac = np.exp(z)
    phi = -np.expm1(-z)
    g = jac / a4 - 1.0 / jac - omega * osmotic_p(phi, chi0, chi1)
    dg = jac / a4 + 1.0 / jac - omega * osmotic_dp(phi, chi0, chi1) / jac
    return g, dg


@njit(cache=True)
def edge_porosity(a, phi_adj, omega, chi0, chi1):
    """Edge porosity phi_b solving eq. Boundary_Dimless for edge radius ``a``.

    Marches in z = log J from the adjacent cell's porosity downhill in energy until g
    changes sign, then polishes with safeguarded Newton.  Returns NaN if no root is found.
    """
    a4 = a * a * a * a
    p = min(max(phi_adj, 1e-12), 1.0 - 1e-12)
    z0 = -np.log1p(-p)
    g0, _ = _edge_g(z0, a4, omega, chi0, chi1)
    if g0 == 0.0:
        return p
    direction = -1.0 if g0 > 0.0 else 1.0
    step = 1e-3
    z1 = z0
    g1 = g0
    found = False
    for _ in range(4000):
        z1 = z0 + direction * step
        if z1 <= 0.0:
            z1 = 0.5 * z0
        g1, _ = _edge_g(z1, a4, omega, chi0, chi1)
        if (g1 > 0.0) != (g0 > 0.0) or g1 == 0.0:
            found = True
            break
        z0 = z1
        g0 = g1
        step = min(step * 1.6, EDGE_MAX_STEP)
    if not found:
        return np.nan
    lo, hi = (z0, z1) if z0 < z1 else (z1, z0)
    glo, _ = _edge_g(lo, a4, omega, chi0, chi1)
    z = 0.5 * (lo + hi)
    for _ in range(100):
        g, dg = _edge_g(z, a4, omega, chi0, chi1)
        if g == 0.0:
            break
        if (g > 0.0) == (glo > 0.0):
            lo = z
        else:
            hi = z
        znew = z - g / dg if dg != 0.0 else 0.5 * (lo + hi)
        if not (lo < znew < hi):
            znew = 0.5 * (lo + hi)
        if abs(znew - z) <= 4e-16 * max(1.0, abs(z)):
            z = znew
            break
        z = znew
    return -np.expm1(-z)


@njit(cache=True)
def permeability_slope(phi, code, beta):
    """dk/dphi of :func:`permeability`."""
    if code == 0:
        return 0.0
    return (1.0 - phi) ** (-beta) + beta * phi * (1.0 - phi) ** (-beta - 1.0)


@njit(cache=True)
def cell_stress(lam, jac, phi, omega, chi0, chi1):
    """(X, D) = (sigma'_r - Pi, sigma'_r - sigma'_theta) of a cell (eqs. Stress_Dimless,
    Osmotic_Dimless) with hoop stretch lam, lambda_r = J / lam^2 and phi = 1 - 1/J."""
    l4 = lam * lam * lam * lam
    sr = jac / l4 - 1.0 / jac
    return sr - omega * osmotic_p(phi, chi0, chi1), sr - (lam * lam - 1.0) / jac


@njit(cache=True)
def cell_stress_partials(lam, jac, phi, omega, chi0, chi1):
    """(dX/dJ, dX/dlam, dD/dJ, dD/dlam) of :func:`cell_stress` (phi follows J)."""
    l4 = lam * lam * lam * lam
    j2 = jac * jac
    x_j = 1.0 / l4 + 1.0 / j2 - omega * osmotic_dp(phi, chi0, chi1) / j2
    x_l = -4.0 * jac / (l4 * lam)
    d_j = 1.0 / l4 + lam * lam / j2
    d_l = x_l - 2.0 * lam / jac
    return x_j, x_l, d_j, d_l


@njit(cache=True)
def edge_terms(a, phi_b, omega, chi0, chi1):
    """Edge values for dmu/dr at r = a: B = sigma'_r - sigma'_theta, dB/da and dphi_b/da.

    X_b = sigma'_r - Pi vanishes on the edge root (eq. Boundary_Dimless), so only the hoop
    term B(a) = J_b/a^4 - a^2/J_b and the root's slope (implicit function theorem) enter.
    """
    jb = 1.0 / (1.0 - phi_b)
    a4 = a * a * a * a
    g_phi = jb * jb / a4 + 1.0 - omega * osmotic_dp(phi_b, chi0, chi1)
    g_a = -4.0 * jb / (a4 * a)
    dphi = -g_a / g_phi
    b = jb / a4 - a * a / jb
    db = -4.0 * jb / (a4 * a) - 2.0 * a / jb + (1.0 / a4 + a * a / (jb * jb)) * jb * jb * dphi
    return b, db, dphi


@njit(cache=True)
def edge_phi(a, phi_adj, omega, chi0, chi1, ell2):
    """Edge porosity: the root of eq. Boundary_Dimless (ell = 0), or, with the interfacial
    term, the adjacent cell's value (dJ/drho = 0 at rho = 1 makes J(1) - J_{n-1} = O(h^2);
    the stress condition sigma'_r - Pi - q = 0 then fixes q at the edge, docs/interfacial.md)."""
    if ell2 > 0.0:
        return phi_adj
    return edge_porosity(a, phi_adj, omega, chi0, chi1)


@njit(cache=True)
def korteweg(jac, rho_face, rho_mid, dry, ell2, n, q):
    """Korteweg pressure q = ell^2 rho^-2 d/drho (rho^2 dJ/drho) of every cell (finite volume
    on the dry coordinate, docs/interfacial.md).

    ``rho_face[k]`` is the dry radius of the face between cells k-1 and k, ``rho_mid`` the
    cells' dry volume midpoints, ``dry[c]`` = rho_{c+1}^3 - rho_c^3; the flux rho^2 dJ/drho
    vanishes at the centre and at the edge (natural condition dJ/drho = 0).
    """
    lower = 0.0
    for c in range(n):
        upper = 0.0
        if c < n - 1:
            rf = rho_face[c + 1]
            upper = rf * rf * (jac[c + 1] - jac[c]) / (rho_mid[c + 1] - rho_mid[c])
        q[c] = 3.0 * ell2 * (upper - lower) / dry[c]
        lower = upper
