"""The Lagrangian grid: dry coordinate rho in [0, 1], unknown radii r at the nodes.

Nodes rho_k = k/n (k = 0..n, r_0 = 0) carry the solid; cell c between nodes c and c+1
holds the fixed dry volume w_c = rho_{c+1}^3 - rho_c^3, so its volume ratio is exact,
J_c = (r_{c+1}^3 - r_c^3)/w_c, and the solid is conserved identically.  Stretches at the
cell's volume midpoint: lambda_theta = r/rho, lambda_r = J/lambda_theta^2
(eqs. Strain_Dimless).  Volume conservation with Darcy flow (eqs. Darcy, VolConservation)
moves the solid with velocity dr/dt = k(phi) dmu/dr at fixed rho; at rho = 1 the edge
porosity solves eq. Boundary_Dimless with lambda_theta = a = r_n.  The Jacobian is
tridiagonal.  With the interfacial energy (ell > 0, docs/interfacial.md) the Korteweg
pressure q = ell^2 Lap_rho J joins the osmotic pressure, the edge takes dJ/drho = 0 and
sigma'_r - Pi - q = 0, and the Jacobian is pentadiagonal.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from .kernels import (
    cell_stress,
    cell_stress_partials,
    edge_phi,
    edge_terms,
    korteweg,
    permeability,
    permeability_slope,
    scale_rate,
)

LOWER, UPPER, BORDER = 1, 1, 0
W_PHI, W_JAC, W_LAMT, W_MU, W_X, W_D, W_RC = 0, 1, 2, 3, 4, 5, 6
W_DX, W_DD, W_DPHI, W_DRC = 7, 9, 11, 13  # partials w.r.t. (r_lo, r_hi): two rows each
W_Q, W_DQ = 15, 16  # Korteweg pressure; its partials w.r.t. r at nodes c-1..c+2 (4 rows)
WORK_ROWS = 20


def structure(interfacial: bool) -> tuple[int, int, int]:
    """(lower, upper, border) of the Jacobian: tridiagonal, pentadiagonal with the
    interfacial term (q_c couples the cells c-1..c+1)."""
    return (2, 2, 0) if interfacial else (LOWER, UPPER, BORDER)


def geometry(n: int) -> np.ndarray:
    """Grid rows: nodes rho_k, cell volume midpoints rho_c, dry shell volumes w_c."""
    geo = np.zeros((4, n + 1))
    nodes = np.arange(n + 1) / n
    geo[0] = nodes
    geo[1, :n] = np.cbrt(0.5 * (nodes[:-1] ** 3 + nodes[1:] ** 3))
    geo[2, :n] = np.diff(nodes**3)
    return geo


@njit(cache=True)
def cell_state(y, geo, work):
    """Porosity, J, hoop stretch and midpoint radius of every cell; False if unphysical."""
    n = geo.shape[1] - 1
    prev3 = 0.0
    for c in range(n):
        r = y[c]
        r3 = r * r * r
        v = r3 - prev3
        if not (v > geo[2, c]) or not (r > 0.0):
            return False
        jac = v / geo[2, c]
        work[W_JAC, c] = jac
        work[W_PHI, c] = 1.0 - 1.0 / jac
        rc = np.cbrt(0.5 * (prev3 + r3))
        work[W_RC, c] = rc
        work[W_LAMT, c] = rc / geo[1, c]
        prev3 = r3
    return True


@njit(cache=True)
def mu_gradient(y, phi_b, geo, omega, chi0, chi1, ell2, work):
    """dmu/dr at the interior nodes (work[W_MU, 1..n-1]) and at the edge (returned).

    eq. ChemPotential_Dimless with differences between cell midpoints, node averages of
    the hoop term and a one-sided difference at the edge.  The single place where stress
    terms enter: with ell > 0 the Korteweg pressure q joins Pi (X = sigma'_r - Pi - q) and
    the edge value of X is 0 (sigma'_r - Pi - q = 0 at rho = 1, docs/interfacial.md).
    """
    n = geo.shape[1] - 1
    for c in range(n):
        work[W_X, c], work[W_D, c] = cell_stress(work[W_LAMT, c], work[W_JAC, c],
                                                 work[W_PHI, c], omega, chi0, chi1)
    if ell2 > 0.0:
        korteweg(work[W_JAC], geo[0], geo[1], geo[2], ell2, n, work[W_Q])
        for c in range(n):
            work[W_X, c] -= work[W_Q, c]
    for k in range(1, n):
        work[W_MU, k] = ((work[W_X, k] - work[W_X, k - 1]) / (work[W_RC, k] - work[W_RC, k - 1])
                         + (work[W_D, k - 1] + work[W_D, k]) / y[k - 1])
    a = y[n - 1]
    x_b, d_b = cell_stress(a, 1.0 / (1.0 - phi_b), phi_b, omega, chi0, chi1)
    if ell2 > 0.0:
        x_b = 0.0
    return (x_b - work[W_X, n - 1]) / (a - work[W_RC, n - 1]) + 2.0 * d_b / a


@njit(cache=True)
def _rhs(y, par, geo, out, work):
    """dr_k/dt = k(phi) dmu/dr at every node k = 1..n; False for an unphysical state."""
    n = geo.shape[1] - 1
    omega, chi0, chi1, ell2 = par.omega, par.chi0, par.chi1, par.ell2
    code, beta = par.perm_code, par.perm_beta
    if not cell_state(y, geo, work):
        return False
    phi_b = edge_phi(y[n - 1], work[W_PHI, n - 1], omega, chi0, chi1, ell2)
    if not (0.0 < phi_b < 1.0):
        return False
    mu_edge = mu_gradient(y, phi_b, geo, omega, chi0, chi1, ell2, work)
    for k in range(1, n):
        phf = 0.5 * (work[W_PHI, k - 1] + work[W_PHI, k])
        out[k - 1] = permeability(phf, code, beta) * work[W_MU, k]
    out[n - 1] = permeability(phi_b, code, beta) * mu_edge
    return np.isfinite(out[n - 1])


@njit(cache=True)
def _jacobian(y, par, geo, work, upper, jband, jc, jd, je, out):
    """Analytic Jacobian of :func:`rhs` (band layout: tridiagonal, pentadiagonal with the
    interfacial term), and rhs into ``out``; False if unphysical."""
    n = geo.shape[1] - 1
    omega, chi0, chi1, ell2 = par.omega, par.chi0, par.chi1, par.ell2
    code, beta = par.perm_code, par.perm_beta
    if not cell_state(y, geo, work):
        return False
    a = y[n - 1]
    phi_b = edge_phi(a, work[W_PHI, n - 1], omega, chi0, chi1, ell2)
    if not (0.0 < phi_b < 1.0):
        return False
    mu_edge = mu_gradient(y, phi_b, geo, omega, chi0, chi1, ell2, work)
    jband[:, :] = 0.0
    r_lo = 0.0
    for c in range(n):
        r_hi = y[c]
        jac_c, lam, phi, rc = work[W_JAC, c], work[W_LAMT, c], work[W_PHI, c], work[W_RC, c]
        dj0, dj1 = -3.0 * r_lo * r_lo / geo[2, c], 3.0 * r_hi * r_hi / geo[2, c]
        drc0, drc1 = r_lo * r_lo / (2.0 * rc * rc), r_hi * r_hi / (2.0 * rc * rc)
        dl0, dl1 = drc0 / geo[1, c], drc1 / geo[1, c]
        x_j, x_l, d_j, d_l = cell_stress_partials(lam, jac_c, phi, omega, chi0, chi1)
        work[W_DX, c], work[W_DX + 1, c] = x_j * dj0 + x_l * dl0, x_j * dj1 + x_l * dl1
        work[W_DD, c], work[W_DD + 1, c] = d_j * dj0 + d_l * dl0, d_j * dj1 + d_l * dl1
        work[W_DPHI, c], work[W_DPHI + 1, c] = dj0 / (jac_c * jac_c), dj1 / (jac_c * jac_c)
        work[W_DRC, c], work[W_DRC + 1, c] = drc0, drc1
        r_lo = r_hi
    for k in range(1, n):
        row = k - 1
        lc, rcell = k - 1, k
        rk = y[k - 1]
        gap = work[W_RC, rcell] - work[W_RC, lc]
        num = work[W_X, rcell] - work[W_X, lc]
        dsum = work[W_D, lc] + work[W_D, rcell]
        mu = work[W_MU, k]
        phf = 0.5 * (work[W_PHI, lc] + work[W_PHI, rcell])
        kf = permeability(phf, code, beta)
        kfp = permeability_slope(phf, code, beta)
        out[row] = kf * mu
        # r_{k-1}: lower node of the left cell
        if k >= 2:
            dmu = (-work[W_DX, lc] / gap + num * work[W_DRC, lc] / (gap * gap)
                   + work[W_DD, lc] / rk)
            dph = 0.5 * work[W_DPHI, lc]
            jband[upper + 1, k - 2] += kfp * dph * mu + kf * dmu
        # r_k: shared node, also the explicit 1/r_k of the hoop term
        dgap = work[W_DRC, rcell] - work[W_DRC + 1, lc]
        dmu = ((work[W_DX, rcell] - work[W_DX + 1, lc]) / gap - num * dgap / (gap * gap)
               + (work[W_DD + 1, lc] + work[W_DD, rcell]) / rk - dsum / (rk * rk))
        dph = 0.5 * (work[W_DPHI + 1, lc] + work[W_DPHI, rcell])
        jband[upper, k - 1] += kfp * dph * mu + kf * dmu
        # r_{k+1}: upper node of the right cell
        dmu = (work[W_DX + 1, rcell] / gap - num * work[W_DRC + 1, rcell] / (gap * gap)
               + work[W_DD + 1, rcell] / rk)
        dph = 0.5 * work[W_DPHI + 1, rcell]
        jband[upper - 1, k] += kfp * dph * mu + kf * dmu
    if ell2 > 0.0:
        _korteweg_jacobian(y, geo, ell2, code, beta, work, upper, jband)
        _edge_jacobian_interfacial(y, geo, omega, chi0, chi1, code, beta, work, upper, jband,
                                   out, mu_edge)
        return True
    # edge node: mu_e = -X_{n-1} / (a - rc_{n-1}) + 2 B(a) / a
    c = n - 1
    gap = a - work[W_RC, c]
    xl = work[W_X, c]
    b, db, dphib = edge_terms(a, phi_b, omega, chi0, chi1)
    kb = permeability(phi_b, code, beta)
    out[n - 1] = kb * mu_edge
    if n >= 2:
        dmu = -work[W_DX, c] / gap - xl * work[W_DRC, c] / (gap * gap)
        jband[upper + 1, n - 2] += kb * dmu
    dmu = (-work[W_DX + 1, c] / gap + xl * (1.0 - work[W_DRC + 1, c]) / (gap * gap)
           + 2.0 * db / a - 2.0 * b / (a * a))
    jband[upper, n - 1] += permeability_slope(phi_b, code, beta) * dphib * mu_edge + kb * dmu
    return True


@njit(cache=True)
def _korteweg_partials(y, geo, ell2, work):
    """dq_c/dr at the nodes c-1, c, c+1, c+2 (y indices c-2..c+1) into work[W_DQ + i, c].

    On this grid q_c = (G_{c+1} (J_{c+1} - J_c) - G_c (J_c - J_{c-1})) / w_c with constant
    G_k = 3 ell^2 rho_k^2 / (rho_mid_k - rho_mid_{k-1}) (G_0 = G_n = 0): linear in J.
    """
    n = geo.shape[1] - 1
    for c in range(n):
        g_lo = 0.0
        g_hi = 0.0
        if c > 0:
            g_lo = 3.0 * ell2 * geo[0, c] ** 2 / (geo[1, c] - geo[1, c - 1])
        if c < n - 1:
            g_hi = 3.0 * ell2 * geo[0, c + 1] ** 2 / (geo[1, c + 1] - geo[1, c])
        w = geo[2, c]
        coef = (g_lo / w, -(g_lo + g_hi) / w, g_hi / w)
        for i in range(4):
            work[W_DQ + i, c] = 0.0
        for m in range(3):  # cells c-1, c, c+1
            cell = c - 1 + m
            if cell < 0 or cell > n - 1 or coef[m] == 0.0:
                continue
            r_hi = y[cell]
            if cell >= 1:  # lower node of the cell (y index cell-1 = column offset m)
                r_lo = y[cell - 1]
                work[W_DQ + m, c] += coef[m] * (-3.0 * r_lo * r_lo / geo[2, cell])
            work[W_DQ + m + 1, c] += coef[m] * (3.0 * r_hi * r_hi / geo[2, cell])


@njit(cache=True)
def _korteweg_jacobian(y, geo, ell2, code, beta, work, upper, jband):
    """Add the Korteweg terms k_f (q_{k-1} - q_k) / gap_k of the interior rows' dmu/dr (the
    gap and local-stress partials are already in, through X which includes -q)."""
    n = geo.shape[1] - 1
    m = jband.shape[1]
    _korteweg_partials(y, geo, ell2, work)
    for k in range(1, n):
        row = k - 1
        phf = 0.5 * (work[W_PHI, k - 1] + work[W_PHI, k])
        scale = permeability(phf, code, beta) / (work[W_RC, k] - work[W_RC, k - 1])
        for i in range(4):
            col = k - 2 + i  # q_k depends on y[k-2..k+1]
            if 0 <= col < m:
                jband[upper + row - col, col] -= scale * work[W_DQ + i, k]
            col = k - 3 + i  # q_{k-1} depends on y[k-3..k]
            if 0 <= col < m:
                jband[upper + row - col, col] += scale * work[W_DQ + i, k - 1]


@njit(cache=True)
def _edge_jacobian_interfacial(y, geo, omega, chi0, chi1, code, beta, work, upper,
                               jband, out, mu_edge):
    """Edge row with the interfacial term: mu_e = -X_{n-1} / (a - rc_{n-1}) + 2 B / a with
    X including -q_{n-1}, and B = J/a^4 - a^2/J at the edge porosity phi_b = phi_{n-1}."""
    n = geo.shape[1] - 1
    c = n - 1
    a = y[n - 1]
    gap = a - work[W_RC, c]
    xl = work[W_X, c]
    jb = work[W_JAC, c]
    phi_b = work[W_PHI, c]
    a4 = a * a * a * a
    b = jb / a4 - a * a / jb
    db_j = 1.0 / a4 + a * a / (jb * jb)
    db_a = -4.0 * jb / (a4 * a) - 2.0 * a / jb
    kb = permeability(phi_b, code, beta)
    kbp = permeability_slope(phi_b, code, beta)
    out[n - 1] = kb * mu_edge
    r_lo = y[n - 2] if n >= 2 else 0.0
    dj0, dj1 = -3.0 * r_lo * r_lo / geo[2, c], 3.0 * y[n - 1] * y[n - 1] / geo[2, c]
    # the lower node r_{n-1} (y index n-2)
    if n >= 2:
        dmu = (-work[W_DX, c] / gap - xl * work[W_DRC, c] / (gap * gap)
               + 2.0 * db_j * dj0 / a)
        jband[upper + 1, n - 2] += kbp * work[W_DPHI, c] * mu_edge + kb * dmu
    # the edge node a (y index n-1)
    dmu = (-work[W_DX + 1, c] / gap + xl * (1.0 - work[W_DRC + 1, c]) / (gap * gap)
           + 2.0 * (db_j * dj1 + db_a) / a - 2.0 * b / (a * a))
    jband[upper, n - 1] += kbp * work[W_DPHI + 1, c] * mu_edge + kb * dmu
    # the Korteweg pressure of the last cell (y indices n-3..n-1): -X includes +q
    for i in range(3):
        col = n - 3 + i
        if col >= 0:
            jband[upper + (n - 1) - col, col] += kb * work[W_DQ + i, c] / gap


@njit(cache=True)
def fd_scale(y, geo, out):
    """Finite-difference increments: 1e-8 of the smaller adjacent cell width."""
    n = geo.shape[1] - 1
    prev = 0.0
    for k in range(n):
        width = y[k] - prev
        if k + 1 < n:
            width = min(width, y[k + 1] - y[k])
        out[k] = 1e-8 * width
        prev = y[k]


@njit(cache=True)
def error_norm(y, ynew, err, geo, rtol, atol, work):
    """Volume-weighted RMS of the porosity error (the fluid volume error), max with the
    radius error.

    e_J = 3 (r_{c+1}^2 e_{c+1} - r_c^2 e_c)/w_c and e_phi = e_J / J^2.
    """
    n = geo.shape[1] - 1
    prev_r = 0.0
    prev_e = 0.0
    acc = 0.0
    for c in range(n):
        r = ynew[c]
        jac = (r * r * r - prev_r * prev_r * prev_r) / geo[2, c]
        e_j = 3.0 * (r * r * err[c] - prev_r * prev_r * prev_e) / geo[2, c]
        phi = 1.0 - 1.0 / jac
        share = n * (r * r * r - prev_r * prev_r * prev_r) / (ynew[n - 1] ** 3)
        acc += share * (e_j / (jac * jac) / (atol + rtol * abs(phi))) ** 2
        prev_r = r
        prev_e = err[c]
    rms = np.sqrt(acc / n)
    a = ynew[n - 1]
    ra = abs(err[n - 1]) / (atol + rtol * max(abs(a), abs(y[n - 1])))
    return max(rms, ra)


@njit(cache=True)
def porosity(y, geo, out):
    """Cell porosities from the node radii (no validity check); returns a."""
    n = geo.shape[1] - 1
    prev3 = 0.0
    for c in range(n):
        r3 = y[c] * y[c] * y[c]
        out[c] = 1.0 - geo[2, c] / (r3 - prev3)
        prev3 = r3
    return y[n - 1]


def state_from_profile(radius: float, phi: np.ndarray) -> np.ndarray:
    """Node radii from cell porosities: r_k^3 = sum_{c<k} w_c / (1 - phi_c)."""
    n = phi.size
    w = np.diff((np.arange(n + 1) / n) ** 3)
    return np.cbrt(np.cumsum(w / (1.0 - phi)))


def dry_profile(y: np.ndarray, geo: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(r, s) at every node: the dry volume s = rho^3 enclosed by radius r."""
    return np.concatenate([[0.0], y]), geo[0] ** 3


def state_from_dry(r: np.ndarray, s: np.ndarray, n: int) -> np.ndarray:
    """Node radii on n cells from a dry profile; exact for piecewise-uniform source cells."""
    targets = (np.arange(1, n + 1) / n) ** 3
    return np.cbrt(np.interp(targets, s, r**3))


def solid_volume(y: np.ndarray, geo: np.ndarray) -> float:
    """Dry volume sum (r_{c+1}^3 - r_c^3)(1 - phi_c) (should be 1), from the porosities."""
    phi = np.empty(geo.shape[1] - 1)
    porosity(y, geo, phi)
    shells = np.diff(np.concatenate([[0.0], y]) ** 3)
    return float(np.sum(shells * (1.0 - phi)))


def cell_radii(y: np.ndarray, geo: np.ndarray) -> np.ndarray:
    """Cell volume-midpoint radii."""
    r3 = np.concatenate([[0.0], y]) ** 3
    return np.cbrt(0.5 * (r3[:-1] + r3[1:]))


def radius(y: np.ndarray) -> float:
    """The sphere radius a = r_n."""
    return float(y[-1])


@njit(cache=True)
def rhs(y, par, geo, out, work):
    """The rates of :func:`_rhs` times the mobility ``par.mobility`` (docs/heating.md)."""
    ok = _rhs(y, par, geo, out, work)
    if par.mobility != 1.0:
        out *= par.mobility
    return ok


@njit(cache=True)
def jacobian(y, par, geo, work, upper, jband, jc, jd, je, out):
    """:func:`_jacobian` times the mobility ``par.mobility`` (docs/heating.md)."""
    ok = _jacobian(y, par, geo, work, upper, jband, jc, jd, je, out)
    if ok:
        scale_rate(par.mobility, out, jband, jc, jd, je)
    return ok
