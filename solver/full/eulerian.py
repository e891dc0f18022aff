"""The paper's Eulerian grid (appendix Numerical scheme), in conservative variables.

Cells i = 0..n-1 of the rescaled coordinate R = r/a have faces R_k = k/n and centres
R_i = (i + 1/2)/n (eq. NumericalPDE's staggered, volume-conserving cells).  The unknowns
are the dry (solid) volume s_k inside each interior face, in units of the dry sphere
volume (s_0 = 0, s_n = 1), and the radius a.  This is an exact linear change of variables
of the paper's cell fluid volumes a^3 phi_i: the solid is conserved identically, and the
hoop stretch lambda_theta = r / (dry radius inside r) (eq. Displacement_Dimless) is local
in s, so the Jacobian is tridiagonal plus two dense columns (s_{n-1} and a, through
da/dt in the frame velocity).  The solid flux through the moving face R_k is

    ds_k/dt = 3 r_k^2 (1 - phi_k) (R_k da/dt - k(phi_k) dmu/dr),   r_k = a R_k,

the solid counterpart of eq. NumericalFlux with its advective part a^2 (da/dt) R phi,
and da/dt = k(phi_b) dmu/dr at r = a (eq. SphereEvolve_Dimless).

With the interfacial energy (ell > 0, docs/interfacial.md) the Korteweg pressure
q = ell^2 Lap_rho J joins the osmotic pressure, on the dry radii rho = s^(1/3) of the faces
and cell midpoints; the edge takes dJ/drho = 0 and sigma'_r - Pi - q = 0.  da/dt then also
depends on s_{n-2} (q of the last cell), so the border grows to (s_{n-2}, s_{n-1}, a), the
band to pentadiagonal, and the Jacobian is the colored finite-difference one.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from .kernels import (
    cell_stress,
    cell_stress_partials,
    edge_phi,
    edge_porosity,
    edge_terms,
    korteweg,
    permeability,
    permeability_slope,
    scale_rate,
)

# Jacobian structure: band half-widths of the s_1..s_{n-2} block and border size.
LOWER, UPPER, BORDER = 1, 1, 2
# Rows of the work array used by the kernels.
W_PHI, W_JAC, W_LAMT, W_MU, W_X, W_D = 0, 1, 2, 3, 4, 5
W_DX, W_DD, W_DPHI = 6, 9, 12  # partials w.r.t. (s_lo, s_hi, a): three rows each
W_Q, W_RHOF, W_RHOC, W_DRY = 15, 16, 17, 18  # Korteweg pressure, dry radii, dry volumes
WORK_ROWS = 19


def structure(interfacial: bool) -> tuple[int, int, int]:
    """(lower, upper, border) of the Jacobian; the interfacial term widens the band to
    pentadiagonal and adds s_{n-2} to the border (module doc)."""
    return (2, 2, 3) if interfacial else (LOWER, UPPER, BORDER)


@njit(cache=True)
def dry_radii(y, geo, work):
    """Dry radii rho = s^(1/3) of the inner faces and the cell midpoints, and the cells'
    dry volumes (units of the dry sphere: rho^3 differences), for the Korteweg term."""
    n = geo.shape[1] - 1
    prev = 0.0
    for i in range(n):
        s_hi = y[i] if i < n - 1 else 1.0
        c = s_hi - prev
        work[W_RHOF, i] = np.cbrt(prev)
        work[W_RHOC, i] = np.cbrt(prev + c * geo[3, i])
        work[W_DRY, i] = c
        prev = s_hi


def geometry(n: int) -> np.ndarray:
    """Grid rows: faces R_k, centres R_i, shell volumes w_i, inner half-shell fraction."""
    geo = np.zeros((4, n + 1))
    faces = np.arange(n + 1) / n
    centres = (np.arange(n) + 0.5) / n
    w = np.diff(faces**3)
    geo[0] = faces
    geo[1, :n] = centres
    geo[2, :n] = w
    geo[3, :n] = (centres**3 - faces[:-1] ** 3) / w
    return geo


@njit(cache=True)
def cell_state(y, geo, work):
    """Porosity, J and hoop stretch at the cell centres from (s, a); False if unphysical."""
    n = geo.shape[1] - 1
    a = y[n - 1]
    if not (a > 0.0):
        return False
    a3 = a * a * a
    prev = 0.0
    for i in range(n):
        s_hi = y[i] if i < n - 1 else 1.0
        c = s_hi - prev
        v = a3 * geo[2, i]
        if not (0.0 < c < v):
            return False
        work[W_PHI, i] = 1.0 - c / v
        work[W_JAC, i] = v / c
        dry_centre = prev + c * geo[3, i]
        work[W_LAMT, i] = a * geo[1, i] / np.cbrt(dry_centre)
        prev = s_hi
    return True


@njit(cache=True)
def mu_gradient(a, phi_b, geo, omega, chi0, chi1, ell2, work):
    """dmu/dr at the interior faces (work[W_MU, 1..n-1]) and at r = a (returned).

    eq. ChemPotential_Dimless: dmu/dr = d sigma'_r/dr + 2 (sigma'_r - sigma'_theta)/r - dPi/dr,
    central differences between centres, face averages of the hoop term, a one-sided
    difference at the edge (appendix steps 3-4).  The single place where stress terms
    enter: with ell > 0 the Korteweg pressure q joins Pi (X = sigma'_r - Pi - q, needs
    :func:`dry_radii` first) and the edge value of X is 0 (docs/interfacial.md).
    """
    n = geo.shape[1] - 1
    dr = a / n
    for i in range(n):
        work[W_X, i], work[W_D, i] = cell_stress(work[W_LAMT, i], work[W_JAC, i],
                                                 work[W_PHI, i], omega, chi0, chi1)
    if ell2 > 0.0:
        korteweg(work[W_JAC], work[W_RHOF], work[W_RHOC], work[W_DRY], ell2, n, work[W_Q])
        for i in range(n):
            work[W_X, i] -= work[W_Q, i]
    for k in range(1, n):
        work[W_MU, k] = ((work[W_X, k] - work[W_X, k - 1]) / dr
                         + (work[W_D, k - 1] + work[W_D, k]) / (a * geo[0, k]))
    x_b, d_b = cell_stress(a, 1.0 / (1.0 - phi_b), phi_b, omega, chi0, chi1)
    if ell2 > 0.0:
        x_b = 0.0
    return (x_b - work[W_X, n - 1]) / (0.5 * dr) + 2.0 * d_b / a


@njit(cache=True)
def _rhs(y, par, geo, out, work):
    """d(s_1..s_{n-1}, a)/dt; returns False for an unphysical state."""
    n = geo.shape[1] - 1
    omega, chi0, chi1, ell2 = par.omega, par.chi0, par.chi1, par.ell2
    code, beta = par.perm_code, par.perm_beta
    if not cell_state(y, geo, work):
        return False
    a = y[n - 1]
    phi_b = edge_phi(a, work[W_PHI, n - 1], omega, chi0, chi1, ell2)
    if not (0.0 < phi_b < 1.0):
        return False
    if ell2 > 0.0:
        dry_radii(y, geo, work)
    mu_edge = mu_gradient(a, phi_b, geo, omega, chi0, chi1, ell2, work)
    da = permeability(phi_b, code, beta) * mu_edge
    for k in range(1, n):
        phf = 0.5 * (work[W_PHI, k - 1] + work[W_PHI, k])
        rk = a * geo[0, k]
        out[k - 1] = 3.0 * rk * rk * (1.0 - phf) * (
            geo[0, k] * da - permeability(phf, code, beta) * work[W_MU, k])
    out[n - 1] = da
    return np.isfinite(da)


@njit(cache=True, inline="always")
def _add(row, col, val, jband, jc, jd, je, upper):
    """Accumulate J[row, col] into the bordered band storage (m = band size)."""
    m = jband.shape[1]
    if col < 0:
        return
    if col < m:
        if row < m:
            jband[upper + row - col, col] += val
        else:
            jd[row - m, col] += val
    elif row < m:
        jc[row, col - m] += val
    else:
        je[row - m, col - m] += val


@njit(cache=True)
def _jacobian(y, par, geo, work, upper, jband, jc, jd, je, out):
    """Analytic Jacobian of :func:`rhs` in the bordered band layout, and rhs into ``out``;
    False if unphysical.

    Cell partials of (phi, X, D) w.r.t. (s_lo, s_hi, a) by the chain rule through J and
    lambda_theta; the edge root's slope by the implicit function theorem.  The paper's
    model only (ell = 0): with the interfacial term this grid uses finite differences.
    """
    n = geo.shape[1] - 1
    omega, chi0, chi1 = par.omega, par.chi0, par.chi1
    code, beta = par.perm_code, par.perm_beta
    if par.ell2 > 0.0:
        return False
    if not cell_state(y, geo, work):
        return False
    a = y[n - 1]
    phi_b = edge_porosity(a, work[W_PHI, n - 1], omega, chi0, chi1)
    if not (0.0 < phi_b < 1.0):
        return False
    mu_edge = mu_gradient(a, phi_b, geo, omega, chi0, chi1, 0.0, work)
    jband[:, :] = 0.0
    jc[:, :] = 0.0
    jd[:, :] = 0.0
    je[:, :] = 0.0
    a3 = a * a * a
    s_lo = 0.0
    for i in range(n):
        s_hi = y[i] if i < n - 1 else 1.0
        jac_i, lam, phi = work[W_JAC, i], work[W_LAMT, i], work[W_PHI, i]
        v = a3 * geo[2, i]
        c = s_hi - s_lo
        frac = geo[3, i]
        dry = s_lo + c * frac
        dj0, dj1, dj2 = v / (c * c), -v / (c * c), 3.0 * jac_i / a
        dl0, dl1, dl2 = -lam * (1.0 - frac) / (3.0 * dry), -lam * frac / (3.0 * dry), lam / a
        x_j, x_l, d_j, d_l = cell_stress_partials(lam, jac_i, phi, omega, chi0, chi1)
        work[W_DX, i], work[W_DX + 1, i], work[W_DX + 2, i] = (
            x_j * dj0 + x_l * dl0, x_j * dj1 + x_l * dl1, x_j * dj2 + x_l * dl2)
        work[W_DD, i], work[W_DD + 1, i], work[W_DD + 2, i] = (
            d_j * dj0 + d_l * dl0, d_j * dj1 + d_l * dl1, d_j * dj2 + d_l * dl2)
        work[W_DPHI, i], work[W_DPHI + 1, i], work[W_DPHI + 2, i] = (
            1.0 / v, -1.0 / v, 3.0 * (1.0 - phi) / a)
        s_lo = s_hi
    # edge: mu_e = -X_{n-1} / (a dR/2) + 2 B(a) / a, da/dt = k(phi_b) mu_e
    half = 0.5 / n
    b, db, dphib = edge_terms(a, phi_b, omega, chi0, chi1)
    xl = work[W_X, n - 1]
    dmue_s = -work[W_DX, n - 1] / (a * half)
    dmue_a = (-work[W_DX + 2, n - 1] / (a * half) + xl / (a * a * half)
              + 2.0 * db / a - 2.0 * b / (a * a))
    kb = permeability(phi_b, code, beta)
    da = kb * mu_edge
    dda_s = kb * dmue_s
    dda_a = permeability_slope(phi_b, code, beta) * dphib * mu_edge + kb * dmue_a
    ia = n - 1
    out[ia] = da
    _add(ia, n - 2, dda_s, jband, jc, jd, je, upper)
    _add(ia, ia, dda_a, jband, jc, jd, je, upper)
    inv_dr = n / a
    for k in range(1, n):
        row = k - 1
        lc, rc_ = k - 1, k
        rk = geo[0, k]
        q = 3.0 * a * a * rk * rk
        phf = 0.5 * (work[W_PHI, lc] + work[W_PHI, rc_])
        kf = permeability(phf, code, beta)
        mu = work[W_MU, k]
        g = rk * da - kf * mu
        f_phf = q * (-g - (1.0 - phf) * permeability_slope(phf, code, beta) * mu)
        f_mu = -q * (1.0 - phf) * kf
        f_da = q * (1.0 - phf) * rk
        cd = 1.0 / (a * rk)
        # s_{k-1} (variable k-2): lower face of the left cell
        e_lo = (f_phf * 0.5 * work[W_DPHI, lc]
                + f_mu * (-inv_dr * work[W_DX, lc] + cd * work[W_DD, lc]))
        # s_k (variable k-1): the shared face
        e_mid = (f_phf * 0.5 * (work[W_DPHI + 1, lc] + work[W_DPHI, rc_])
                 + f_mu * (-inv_dr * work[W_DX + 1, lc] + cd * work[W_DD + 1, lc]
                           + inv_dr * work[W_DX, rc_] + cd * work[W_DD, rc_]))
        # s_{k+1} (variable k): upper face of the right cell (s_n = 1 is fixed)
        e_hi = (f_phf * 0.5 * work[W_DPHI + 1, rc_]
                + f_mu * (inv_dr * work[W_DX + 1, rc_] + cd * work[W_DD + 1, rc_]))
        # a (explicitly and through da/dt), and s_{n-1} through da/dt
        dmu = (-inv_dr * work[W_DX + 2, lc] + cd * work[W_DD + 2, lc]
               + inv_dr * work[W_DX + 2, rc_] + cd * work[W_DD + 2, rc_] - mu / a)
        dph = 0.5 * (work[W_DPHI + 2, lc] + work[W_DPHI + 2, rc_])
        e_a = f_phf * dph + f_mu * dmu + f_da * dda_a + 2.0 * q * (1.0 - phf) * g / a
        e_s = f_da * dda_s
        out[row] = q * (1.0 - phf) * g
        if k <= n - 3:  # row and columns inside the band block
            if k >= 2:
                jband[upper + 1, k - 2] = e_lo
            jband[upper, k - 1] = e_mid
            jband[upper - 1, k] = e_hi
            jc[row, 1] = e_a
            jc[row, 0] = e_s
        else:
            _add(row, k - 2, e_lo, jband, jc, jd, je, upper)
            _add(row, k - 1, e_mid, jband, jc, jd, je, upper)
            if k + 1 <= n - 1:
                _add(row, k, e_hi, jband, jc, jd, je, upper)
            _add(row, ia, e_a, jband, jc, jd, je, upper)
            _add(row, n - 2, e_s, jband, jc, jd, je, upper)
    return True


@njit(cache=True)
def fd_scale(y, geo, out):
    """Finite-difference increments: 1e-8 of the smaller adjacent cell solid content."""
    n = geo.shape[1] - 1
    prev = 0.0
    for k in range(n - 1):
        nxt = y[k + 1] if k + 1 < n - 1 else 1.0
        out[k] = 1e-8 * min(y[k] - prev, nxt - y[k])
        prev = y[k]
    out[n - 1] = 1e-8 * y[n - 1]


@njit(cache=True)
def error_norm(y, ynew, err, geo, rtol, atol, work):
    """Error measure of a step: volume-weighted RMS of the porosity error (the fluid volume
    error), max with the radius error.

    The state error (in s, a) is mapped to porosity errors
    e_phi_i = -(e_s_i - e_s_{i-1})/(a^3 w_i) + 3 (1 - phi_i) e_a / a.
    """
    n = geo.shape[1] - 1
    a = ynew[n - 1]
    a3 = a * a * a
    ea = err[n - 1]
    prev_e = 0.0
    prev_s = 0.0
    acc = 0.0
    for i in range(n):
        e_hi = err[i] if i < n - 1 else 0.0
        s_hi = ynew[i] if i < n - 1 else 1.0
        v = a3 * geo[2, i]
        phi = 1.0 - (s_hi - prev_s) / v
        e_phi = -(e_hi - prev_e) / v + 3.0 * (1.0 - phi) * ea / a
        sc = atol + rtol * abs(phi)
        acc += geo[2, i] * n * (e_phi / sc) ** 2
        prev_e = e_hi
        prev_s = s_hi
    rms = np.sqrt(acc / n)
    ra = abs(ea) / (atol + rtol * max(abs(a), abs(y[n - 1])))
    return max(rms, ra)


@njit(cache=True)
def porosity(y, geo, out):
    """Cell porosities from (s, a) (no validity check); returns a."""
    n = geo.shape[1] - 1
    a = y[n - 1]
    a3 = a * a * a
    prev = 0.0
    for i in range(n):
        s_hi = y[i] if i < n - 1 else 1.0
        out[i] = 1.0 - (s_hi - prev) / (a3 * geo[2, i])
        prev = s_hi
    return a


def state_from_profile(radius: float, phi: np.ndarray) -> np.ndarray:
    """(s_1..s_{n-1}, a) from cell porosities; a is recomputed so the solid volume is 1."""
    n = phi.size
    w = np.diff((np.arange(n + 1) / n) ** 3)
    solid = (1.0 - phi) * w
    a3 = 1.0 / solid.sum()
    y = np.empty(n)
    y[: n - 1] = np.cumsum(solid)[: n - 1] * a3
    y[n - 1] = a3 ** (1.0 / 3.0)
    return y


def dry_profile(y: np.ndarray, geo: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(r, s) at every face: the dry volume s enclosed by radius r (for remapping states)."""
    n = geo.shape[1] - 1
    s = np.concatenate([[0.0], y[: n - 1], [1.0]])
    return y[n - 1] * geo[0], s


def state_from_dry(r: np.ndarray, s: np.ndarray, n: int) -> np.ndarray:
    """(s, a) on n cells from a dry profile; exact for piecewise-uniform source cells."""
    a = float(r[-1])
    faces = a * np.arange(1, n) / n
    return np.concatenate([np.interp(faces**3, r**3, s), [a]])


def solid_volume(y: np.ndarray, geo: np.ndarray) -> float:
    """Dry volume a^3 sum (1 - phi_i) w_i (should be 1), from the porosity representation."""
    phi = np.empty(geo.shape[1] - 1)
    a = porosity(y, geo, phi)
    return float(a**3 * np.sum((1.0 - phi) * geo[2, :-1]))


def cell_radii(y: np.ndarray, geo: np.ndarray) -> np.ndarray:
    """Cell-centre radii r_i = a R_i."""
    n = geo.shape[1] - 1
    return y[n - 1] * geo[1, :n]


def radius(y: np.ndarray) -> float:
    """The sphere radius a."""
    return float(y[-1])


MERGE_DEPTH = 4  # a core this many cells wide or less is merged into the shell
MERGE_JUMP = 0.2  # porosity drop across the front that marks a swollen core


@njit(cache=True)
def merge_core(y, geo):
    """Merge a vanishing swollen core into the first shell cell, conserving solid.

    When a shrinking front reaches the centre, the last swollen cells of this grid are
    pulled to phi -> 1 (see DESIGN.md); once the core is at most MERGE_DEPTH cells wide,
    the core and the first shell cell are replaced by their uniform mixture (same solid
    s_K inside face K, so s_k = s_K (k/K)^3).  Returns the number of cells merged (0: none).
    """
    n = geo.shape[1] - 1
    a = y[n - 1]
    a3 = a * a * a
    prev_s = 0.0
    prev_phi = 0.0
    for i in range(min(MERGE_DEPTH, n - 2) + 1):
        phi = 1.0 - (y[i] - prev_s) / (a3 * geo[2, i])
        if i > 0 and prev_phi - phi > MERGE_JUMP:
            cells = i + 1
            for k in range(1, cells):
                y[k - 1] = y[cells - 1] * (k / cells) ** 3
            return cells
        prev_s = y[i]
        prev_phi = phi
    return 0


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
