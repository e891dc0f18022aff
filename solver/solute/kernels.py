"""Numba kernels of the solute transport on the Lagrangian (dry-coordinate) cells.

Unknowns: the solute mass m_i of every cell (i < n) and the released mass M = m_n, in
units of the loaded mass.  Cell i has the fixed dry volume dw_i and the fluid volume
w_i(t) = r_{i+1}^3 - r_i^3 - dw_i (units of 4 pi R^3 / 3); between two mechanics samples
the node volumes r_k^3 are linear in t, so the fluid flux through node k+1 (outward,
relative to the solid, same units per time) is the constant Q_k = -d(r_{k+1}^3)/dt
(continuity: Q_k = Q_{k-1} - dw_k/dt, Q = 0 at the centre).  Pore concentration
c_i = m_i / w_i; the partition K_i = K0 K_s(phi_i) (module ``hindrance``) makes
u_i = c_i / K_i the concentration of the medium in equilibrium with cell i, the potential
diffusion levels (flux on grad(c / K), continuous u across the front's jump of K).
Fluxes out of cell i:
advective W Q c_upwind (W the convective sieving of the face's tighter cell; the medium
side carries c_med itself: inflowing medium is not enriched, the partition is set up by
diffusion), diffusive G_i (u_i - u_{i+1}) with the conductance of the two half cells in
series, G = 3 r^2 / ((r - rc_i) / (phi_i D_i K_i) + (rc_{i+1} - r) / (phi_{i+1} D_{i+1}
K_{i+1})) (frozen over each sample interval at its midpoint geometry), D = D0 f (module
``hindrance``), and at the edge G_e (u_{n-1} - c_med) with
G_e = 3 a^2 phi_{n-1} D_{n-1} K_{n-1} / (a - rc_{n-1}).  c_med = M / V_med (0 for a
perfect sink).  The mesh stretch of cell i (for f and W) is min(dr/drho, r/rho) or
J^(1/3) (``hindrance.MESH_STRETCHES``).  Every flux enters two rows with opposite signs,
so the column sums of the operator vanish and the total mass is conserved by any linear
integrator to round-off.

Time: TR-BDF2 (gamma = 2 - sqrt 2; Bank et al. 1985, Hosea & Shampine 1996), L-stable and
second order, with the filtered error estimate (I - d h L)^-1 C h^3 y''' and steps that
never cross a mechanics sample (where Q changes).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import njit

from .hindrance import diffusion_factor, partition_factor, sieving_factor


class SoluteParams(NamedTuple):
    """The solute's constants by name, as :func:`release_run` reads them: free
    diffusivity ``d0``, the hindrance law ``law_code`` with ``mesh`` (r_s / xi_dry),
    ``fiber`` (r_s / r_f) and exponent ``y``, the affinity ``partition`` K0 with the steric
    ``partition_code``, ``convective`` (1: sieve the advective flux) and ``stretch_code``
    (0: the smallest principal stretch sets the mesh; 1: J^(1/3)); module ``hindrance``."""

    d0: float
    law_code: int
    mesh: float
    fiber: float
    y: float
    partition: float
    partition_code: int = 0
    convective: int = 1
    stretch_code: int = 0

GAMMA = 2.0 - np.sqrt(2.0)
D_COEF = GAMMA / 2.0
A_U = 1.0 / (GAMMA * (2.0 - GAMMA))
A_N = -((1.0 - GAMMA) ** 2) / (GAMMA * (2.0 - GAMMA))
ERR_C = (-3.0 * GAMMA**2 + 4.0 * GAMMA - 2.0) / (12.0 * (2.0 - GAMMA))

# status codes of release_run
OK, BUDGET, BAD = 0, 1, 2


@njit(cache=True)
def cell_props(r3, dw, rho, par, phi, lam, kcell, wcell):
    """Per cell at node volumes ``r3`` (dry node radii ``rho``): porosity, mesh stretch,
    partition K0 K_s(phi) and convective transmission W."""
    n = dw.size
    for i in range(n):
        vol = r3[i + 1] - r3[i]
        p = (vol - dw[i]) / vol if vol > 0.0 else 0.0
        phi[i] = p
        if par.stretch_code == 1:
            lm = np.cbrt(vol / dw[i]) if vol > 0.0 else 0.0
        else:
            lr = (np.cbrt(r3[i + 1]) - np.cbrt(r3[i])) / (rho[i + 1] - rho[i])
            rc = np.cbrt(0.5 * (r3[i] + r3[i + 1]))
            pc = np.cbrt(0.5 * (rho[i] ** 3 + rho[i + 1] ** 3))
            lm = min(lr, rc / pc)
        lam[i] = lm
        kcell[i] = par.partition * partition_factor(p, par.partition_code, par.fiber)
        wcell[i] = sieving_factor(lm, par.mesh) if par.convective != 0 else 1.0


@njit(cache=True)
def conductances(r3, dw, rho, par, g, phi, lam, kcell, wcell):
    """Diffusive conductances at node volumes ``r3``: g[k] through node k+1 (k < n-1, between
    cells k and k+1; the two half cells in series) and g[n-1] at the edge (the last half
    cell), on the potential u = c / K.  Units of volume (4 pi R^3 / 3) per time."""
    n = dw.size
    cell_props(r3, dw, rho, par, phi, lam, kcell, wcell)
    cond_prev = 0.0
    rc_prev = 0.0
    for i in range(n):
        p = phi[i]
        rc = np.cbrt(0.5 * (r3[i] + r3[i + 1]))
        cond = p * par.d0 * kcell[i] * diffusion_factor(
            p, lam[i], par.law_code, par.mesh, par.fiber, par.y) if p > 0.0 else 0.0
        if i > 0:
            rf = np.cbrt(r3[i])
            g[i - 1] = 0.0
            if cond_prev > 0.0 and cond > 0.0:
                g[i - 1] = 3.0 * rf * rf / ((rf - rc_prev) / cond_prev + (rc - rf) / cond)
        cond_prev = cond
        rc_prev = rc
    a_edge = np.cbrt(r3[n])
    g[n - 1] = 3.0 * a_edge * a_edge * cond_prev / (a_edge - rc_prev) if cond_prev > 0.0 \
        else 0.0


@njit(cache=True)
def operator(r3, dw, rho, par, qrate, g, vmed, lo, di, up, fw, fl, phi, lam, kcell, wcell):
    """The tridiagonal operator L (dm/dt = L m) at node volumes ``r3`` (n + 1 values from the
    centre, r3[0] = 0), node flux rates ``qrate`` (Q at node k+1 in qrate[k]) and
    conductances ``g`` (:func:`conductances`).

    lo[i] = L[i+1, i], di[i] = L[i, i], up[i] = L[i, i+1] (n + 1 unknowns, the last the
    released mass).  ``vmed`` <= 0 means a perfect sink.  ``fw`` (cell fluid volumes) and
    ``fl`` (the edge's advective and diffusive rates per unit m_{n-1} and per unit M) are
    returned for the mechanism split.  False if a cell has no fluid.
    """
    n = dw.size
    for i in range(n + 1):
        lo[i] = 0.0
        di[i] = 0.0
        up[i] = 0.0
    cell_props(r3, dw, rho, par, phi, lam, kcell, wcell)
    for i in range(n):
        w = r3[i + 1] - r3[i] - dw[i]
        if not (w > 0.0):
            return False
        fw[i] = w
    inv_v = 1.0 / vmed if vmed > 0.0 else 0.0
    # diffusion (on u = c / K) and advection through the interior nodes 1..n-1
    for k in range(n - 1):
        a, b = g[k] / (fw[k] * kcell[k]), g[k] / (fw[k + 1] * kcell[k + 1])
        q = qrate[k] * min(wcell[k], wcell[k + 1])
        if q >= 0.0:
            a += q / fw[k]
        else:
            b -= q / fw[k + 1]
        di[k] -= a
        lo[k] += a
        up[k] += b
        di[k + 1] -= b
    # the edge: diffusion and advection between cell n-1 and the medium (unknown n)
    q = qrate[n - 1] * wcell[n - 1]
    adv_c = q / fw[n - 1] if q >= 0.0 else 0.0  # outflow per unit m_{n-1}
    adv_m = -q * inv_v if q < 0.0 else 0.0  # inflow of c_med, per unit M
    dif_c = g[n - 1] / (fw[n - 1] * kcell[n - 1])
    dif_m = g[n - 1] * inv_v
    di[n - 1] -= adv_c + dif_c
    lo[n - 1] += adv_c + dif_c
    up[n - 1] += adv_m + dif_m
    di[n] -= adv_m + dif_m
    fl[0], fl[1], fl[2], fl[3] = adv_c, -adv_m, dif_c, -dif_m
    return True


@njit(cache=True)
def _apply(lo, di, up, x, out):
    """out = L x."""
    m = di.size
    for i in range(m):
        v = di[i] * x[i]
        if i > 0:
            v += lo[i - 1] * x[i - 1]
        if i < m - 1:
            v += up[i] * x[i + 1]
        out[i] = v


@njit(cache=True)
def _solve(lo, di, up, dh, rhs, out, cp):
    """Solve (I - dh L) out = rhs (Thomas algorithm; the matrix is an M-matrix, diagonally
    dominant by columns, so no pivoting is needed)."""
    m = di.size
    b0 = 1.0 - dh * di[0]
    cp[0] = -dh * up[0] / b0 if m > 1 else 0.0
    out[0] = rhs[0] / b0
    for i in range(1, m):
        a = -dh * lo[i - 1]
        b = 1.0 - dh * di[i] - a * cp[i - 1]
        if i < m - 1:
            cp[i] = -dh * up[i] / b
        out[i] = (rhs[i] - a * out[i - 1]) / b
    for i in range(m - 2, -1, -1):
        out[i] -= cp[i] * out[i + 1]


@njit(cache=True)
def _geometry(s3a, s3b, theta, r3):
    for k in range(r3.size):
        r3[k] = (1.0 - theta) * s3a[k] + theta * s3b[k]


@njit(cache=True)
def release_run(ts, s3, dw, vmed0, par, m, out, out_prof, prof_idx, rtol, max_steps, counters,
                carry, mark_idx, out_mark):
    """March the solute through the mechanics samples ``ts`` with node volumes ``s3``
    (len(ts), n + 1).  ``m`` (n + 1) is the initial state, updated in place.

    ``par`` is a :class:`SoluteParams`.  ``vmed0`` > 0: the medium volume at t = 0 (it grows
    by the expelled fluid), else a perfect sink.  Writes the released mass, and its
    advective part, and the mass in the gel at every sample (the rows of ``out``, (3,
    len(ts))) and the concentration
    profile at the samples flagged in ``prof_idx`` (row prof_idx[k] >= 0).  Returns a
    status code; counters = (steps, rejected).

    ``carry`` = (step size, advected mass) in and out: what the march carries from one
    sample to the next besides ``m`` (a step size <= 0: start afresh, 1e-9 of the span).
    At the samples flagged in ``mark_idx`` (row >= 0) the whole state is written to
    ``out_mark`` (m, then the step size and the advected mass): a march started from such
    a row with ``carry`` from it continues exactly as this one does.
    """
    n = dw.size
    size = n + 1
    d0 = par.d0
    lo = np.zeros(size)
    di = np.zeros(size)
    up = np.zeros(size)
    lo1 = np.zeros(size)
    di1 = np.zeros(size)
    up1 = np.zeros(size)
    r3 = np.zeros(n + 1)
    q = np.zeros(n)
    gf = np.zeros(n)
    fw = np.zeros(n)
    fl = np.zeros(4)
    fl1 = np.zeros(4)
    f0 = np.zeros(size)
    fg = np.zeros(size)
    f1 = np.zeros(size)
    u = np.zeros(size)
    y1 = np.zeros(size)
    rhs = np.zeros(size)
    err = np.zeros(size)
    est = np.zeros(size)
    cp = np.zeros(size)
    rho = np.zeros(n + 1)
    for i in range(n):
        rho[i + 1] = rho[i] + dw[i]
    for i in range(n + 1):
        rho[i] = np.cbrt(rho[i])
    phi = np.zeros(n)
    lam = np.zeros(n)
    kcell = np.zeros(n)
    wcell = np.zeros(n)
    adv = carry[1]
    h = carry[0] if carry[0] > 0.0 else 1e-9 * max(1.0, ts[-1] - ts[0])
    a3_0 = s3[0, n]
    out[0, 0] = m[n]
    out[1, 0] = adv
    out[2, 0] = np.sum(m[:n])
    for k in range(ts.size - 1):
        ta, tb = ts[k], ts[k + 1]
        if mark_idx[k] >= 0:
            _mark(m, h, adv, out_mark[mark_idx[k]])
        if prof_idx[k] >= 0:
            _geometry(s3[k], s3[k], 0.0, r3)
            for i in range(n):
                out_prof[prof_idx[k], i] = m[i] / (r3[i + 1] - r3[i] - dw[i])
        span = tb - ta
        if span <= 0.0:
            out[0, k + 1] = m[n]
            out[1, k + 1] = adv
            out[2, k + 1] = np.sum(m[:n])
            continue
        for i in range(n):
            q[i] = -(s3[k + 1, i + 1] - s3[k, i + 1]) / span
        if d0 > 0.0:  # frozen at the interval's midpoint (second order in the sample spacing)
            _geometry(s3[k], s3[k + 1], 0.5, r3)
            conductances(r3, dw, rho, par, gf, phi, lam, kcell, wcell)
        t = ta
        fresh = False  # f0, g0 hold L(t) m at this t (the last accepted step's f1, g1)
        while t < tb:
            if counters[0] >= max_steps:
                return BUDGET
            hh = min(h, tb - t)
            last = hh >= tb - t - 1e-14 * max(1.0, abs(tb))
            if last:
                hh = tb - t
            dh = D_COEF * hh
            if not fresh:  # f0 at t
                _geometry(s3[k], s3[k + 1], (t - ta) / span, r3)
                vm = vmed0 + (a3_0 - r3[n]) if vmed0 > 0.0 else 0.0
                if not operator(r3, dw, rho, par, q, gf, vm, lo, di, up, fw, fl, phi, lam,
                                kcell, wcell):
                    return BAD
                _apply(lo, di, up, m, f0)
                g0 = fl[0] * m[n - 1] + fl[1] * m[n]
                fresh = True
            # stage 1: trapezoid to t + gamma h
            _geometry(s3[k], s3[k + 1], (t + GAMMA * hh - ta) / span, r3)
            vm = vmed0 + (a3_0 - r3[n]) if vmed0 > 0.0 else 0.0
            if not operator(r3, dw, rho, par, q, gf, vm, lo, di, up, fw, fl, phi, lam, kcell,
                            wcell):
                return BAD
            for i in range(size):
                rhs[i] = m[i] + dh * f0[i]
            _solve(lo, di, up, dh, rhs, u, cp)
            _apply(lo, di, up, u, fg)  # L u: its entries sum to 0 (not (u - rhs) / dh)
            gg = fl[0] * u[n - 1] + fl[1] * u[n]
            adv_g = adv + dh * (g0 + gg)
            # stage 2: BDF2 to t + h
            tt = t + hh
            _geometry(s3[k], s3[k + 1], min(1.0, (tt - ta) / span), r3)
            vm = vmed0 + (a3_0 - r3[n]) if vmed0 > 0.0 else 0.0
            if not operator(r3, dw, rho, par, q, gf, vm, lo1, di1, up1, fw, fl1, phi, lam, kcell,
                        wcell):
                return BAD
            for i in range(size):
                rhs[i] = A_U * u[i] + A_N * m[i]
            _solve(lo1, di1, up1, dh, rhs, y1, cp)
            _apply(lo1, di1, up1, y1, f1)
            g1 = fl1[0] * y1[n - 1] + fl1[1] * y1[n]
            # filtered error estimate
            for i in range(size):
                est[i] = ERR_C * 2.0 * hh * ((f1[i] - fg[i]) / (1.0 - GAMMA)
                                             - (fg[i] - f0[i]) / GAMMA)
            _solve(lo1, di1, up1, dh, est, err, cp)
            acc = 0.0
            for i in range(size):
                sc = rtol * (abs(y1[i]) + 1.0 / n)
                acc += (err[i] / sc) ** 2
            norm = np.sqrt(acc / size)
            if not np.isfinite(norm):
                return BAD
            if norm <= 1.0:
                adv = A_U * adv_g + A_N * adv + dh * g1
                for i in range(size):
                    m[i] = y1[i]
                    f0[i] = f1[i]
                g0 = g1
                t = tb if last else tt
                counters[0] += 1
                fac = 4.0 if norm == 0.0 else min(4.0, max(0.2, 0.9 * norm ** (-1.0 / 3.0)))
                if not last or fac < 1.0:
                    h = hh * fac
                else:
                    h = max(h, hh * fac)
            else:
                counters[1] += 1
                h = hh * max(0.2, 0.9 * norm ** (-1.0 / 3.0))
        out[0, k + 1] = m[n]
        out[1, k + 1] = adv
        out[2, k + 1] = np.sum(m[:n])
    kl = ts.size - 1
    if prof_idx[kl] >= 0:
        _geometry(s3[kl], s3[kl], 0.0, r3)
        for i in range(n):
            out_prof[prof_idx[kl], i] = m[i] / (r3[i + 1] - r3[i] - dw[i])
    if mark_idx[kl] >= 0:
        _mark(m, h, adv, out_mark[mark_idx[kl]])
    carry[0] = h
    carry[1] = adv
    return OK


@njit(cache=True)
def _mark(m, h, adv, row):
    """The march's whole state as one row: m, the step size, the advected mass."""
    size = m.size
    for i in range(size):
        row[i] = m[i]
    row[size] = h
    row[size + 1] = adv
