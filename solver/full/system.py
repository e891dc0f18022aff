"""Grid dispatch for the integrators, and the colored finite-difference Jacobian.

Both grids expose the same numba kernels (rhs, fd_scale, error_norm, porosity); the
integrators call them through these dispatchers with an integer grid code, so one
compiled integrator serves both grids.  The state is y = [band part (m) | border (p)].
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ..heating import mobility_factor, temperature_rate
from . import ale, eulerian, lagrangian
from .kernels import KernelParams

EULERIAN, LAGRANGIAN, MOVING = 0, 1, 2
GRID_CODES = {"eulerian": EULERIAN, "lagrangian": LAGRANGIAN, "moving": MOVING}  # see grids.py
MODULES = {EULERIAN: eulerian, LAGRANGIAN: lagrangian, MOVING: ale}


@njit(cache=True)
def rhs(grid, y, par, geo, out, work):
    """dy/dt on the chosen grid; False for an unphysical state."""
    if grid == EULERIAN:
        return eulerian.rhs(y, par, geo, out, work)
    if grid == MOVING:
        return ale.rhs(y, par, geo, out, work)
    return lagrangian.rhs(y, par, geo, out, work)


@njit(cache=True)
def fd_scale(grid, y, geo, out):
    """Finite-difference increments for the Jacobian."""
    if grid == EULERIAN:
        eulerian.fd_scale(y, geo, out)
    elif grid == MOVING:
        ale.fd_scale(y, geo, out)
    else:
        lagrangian.fd_scale(y, geo, out)


@njit(cache=True)
def error_norm(grid, y, ynew, err, geo, rtol, atol, work):
    """Weighted norm of a local error estimate (porosity and radius errors)."""
    if grid == EULERIAN:
        return eulerian.error_norm(y, ynew, err, geo, rtol, atol, work)
    if grid == MOVING:
        return ale.error_norm(y, ynew, err, geo, rtol, atol, work)
    return lagrangian.error_norm(y, ynew, err, geo, rtol, atol, work)


@njit(cache=True)
def porosity(grid, y, geo, out):
    """Cell porosities; returns the radius a."""
    if grid == EULERIAN:
        return eulerian.porosity(y, geo, out)
    if grid == MOVING:
        return ale.porosity(y, geo, out)
    return lagrangian.porosity(y, geo, out)


@njit(cache=True)
def edge_porosity(grid, y, geo):
    """Porosity of the outermost cell (where a front nucleates), from state y."""
    n = geo.shape[1] - 1
    if grid == EULERIAN:
        a = y[n - 1]
        return 1.0 - (1.0 - y[n - 2]) / (a * a * a * geo[2, n - 1])
    if grid == MOVING:
        ale.refresh(geo, y[n])
    return 1.0 - geo[2, n - 1] / (y[n - 1] ** 3 - y[n - 2] ** 3)


JAC_ANALYTIC, JAC_FD = 0, 1


@njit(cache=True)
def dense_output(grid, geo, t0, t1, y0, y1, f0, f1, t, out, phi):
    """State at t in [t0, t1] into ``out`` (cubic Hermite; linear where the cubic leaves
    the physical range in a fast transient), its porosities into ``phi``; returns
    |solid volume - 1| of the porosity representation (the conservation check).

    On the moving grid the fallback keeps the radius on its cubic when the state stays
    physical: the cubic of the radius is the one a terminal event's time is the root of,
    and a thin front's moving nodes leave the range over a long step (HHT, ell = 1e-3, the
    30 % dose's event: cells 238-248, the radius then 2.5e-6 off the event's, more than the
    planner's stop margin)."""
    h = t1 - t0
    s = (t - t0) / h if h > 0.0 else 1.0
    c0 = (1.0 + 2.0 * s) * (1.0 - s) ** 2
    c1 = s * (1.0 - s) ** 2 * h
    c2 = s * s * (3.0 - 2.0 * s)
    c3 = s * s * (s - 1.0) * h
    for i in range(out.size):
        out[i] = c0 * y0[i] + c1 * f0[i] + c2 * y1[i] + c3 * f1[i]
    porosity(grid, out, geo, phi)
    for i in range(phi.size):
        if not (0.0 < phi[i] < 1.0):
            ia = radius_index(grid, out.size)
            cubic = out[ia]
            for j in range(out.size):
                out[j] = (1.0 - s) * y0[j] + s * y1[j]
            if grid == MOVING:
                out[ia] = cubic
                porosity(grid, out, geo, phi)
                for k in range(phi.size):
                    if not (0.0 < phi[k] < 1.0):
                        out[ia] = (1.0 - s) * y0[ia] + s * y1[ia]
                        break
            porosity(grid, out, geo, phi)
            break
    return solid_error(grid, out, geo, phi)


@njit(cache=True)
def solid_error(grid, y, geo, phi):
    """|dry volume - 1| from the radius and the cell porosities ``phi`` of state y."""
    n = phi.size
    acc = 0.0
    if grid == EULERIAN:
        a = y[n - 1]
        for i in range(n):
            acc += (1.0 - phi[i]) * geo[2, i]
        return abs(a * a * a * acc - 1.0)
    if grid == MOVING:
        ale.refresh(geo, y[n])
    prev3 = 0.0
    for c in range(n):
        r3 = y[c] * y[c] * y[c]
        acc += (r3 - prev3) * (1.0 - phi[c])
        prev3 = r3
    return abs(acc - 1.0)


@njit(cache=True)
def linearize(grid, y, f, par, geo, work, lower, upper, jband, jc, jd, je,
              ytmp, ftmp, scale, mode):
    """f(y) into ``f`` and the Jacobian at y in bordered band storage: analytic (mode
    JAC_ANALYTIC) or colored finite differences.  Returns the cost in rhs-call
    equivalents, or -1 if y is unphysical.
    """
    if mode == JAC_FD:
        if not rhs(grid, y, par, geo, f, work):
            return -1
        calls = fd_jacobian(grid, y, f, par, geo, work, lower, upper, jband, jc, jd, je,
                            ytmp, ftmp, scale)
        return calls + 1 if calls >= 0 else -1
    if grid == EULERIAN:
        ok = eulerian.jacobian(y, par, geo, work, upper, jband, jc, jd, je, f)
    elif grid == MOVING:
        ok = ale.jacobian(y, par, geo, work, upper, jband, jc, jd, je, f, ytmp, ftmp)
        return 4 if ok and np.isfinite(f[f.size - 2]) else -1  # + the time column's 2
    else:
        ok = lagrangian.jacobian(y, par, geo, work, upper, jband, jc, jd, je, f)
    return 2 if ok and np.isfinite(f[f.size - 1]) else -1


@njit(cache=True)
def fd_jacobian(grid, y, f0, par, geo, work, lower, upper, jband, jc, jd, je,
                ytmp, ftmp, scale):
    """Colored forward-difference Jacobian of the bordered band structure.

    Band columns are perturbed lower + upper + 1 at a time; each border column alone.
    Border rows may depend only on the last lower + upper + 1 band columns (true on both
    grids: only the outermost cells feed the edge).  Returns the number of rhs calls, or
    -1 if a perturbed state is unphysical.
    """
    m = jband.shape[1]
    p = je.shape[0]
    w = lower + upper + 1
    fd_scale(grid, y, geo, scale)
    for i in range(y.size):
        ytmp[i] = y[i]
    jd[:, :] = 0.0
    calls = 0
    for color in range(min(w, m)):
        for j in range(color, m, w):
            ytmp[j] = y[j] + scale[j]
        calls += 1
        if not rhs(grid, ytmp, par, geo, ftmp, work):
            return -1
        for j in range(color, m, w):
            d = scale[j]
            for i in range(max(0, j - upper), min(m, j + lower + 1)):
                jband[upper + i - j, j] = (ftmp[i] - f0[i]) / d
            if j >= m - w:
                for r in range(p):
                    jd[r, j] = (ftmp[m + r] - f0[m + r]) / d
            ytmp[j] = y[j]
    for k in range(p):
        d = scale[m + k]
        ytmp[m + k] = y[m + k] + d
        calls += 1
        if not rhs(grid, ytmp, par, geo, ftmp, work):
            return -1
        for i in range(m):
            jc[i, k] = (ftmp[i] - f0[i]) / d
        for r in range(p):
            je[r, k] = (ftmp[m + r] - f0[m + r]) / d
        ytmp[m + k] = y[m + k]
    return calls


@njit(cache=True)
def radius_index(grid, size):
    """Index of the radius a in a state of ``size`` entries (the moving grid appends t)."""
    if grid == MOVING:
        return size - 2
    return size - 1


@njit(cache=True)
def underflow(grid):
    """Smallest relative step before the integrator gives up: 1e-14 on the fixed grids; on
    the moving grid 1e-22, since its cells resolve a stiff gel's spinodal burst at the edge
    (Omega = 1e4: the edge cell's porosity falls 0.96 -> 0.4 within ~1e-10, docs/moving_mesh.md)."""
    if grid == MOVING:
        return 1e-22
    return 1e-14


@njit(cache=True)
def event(grid, y, geo):
    """Apply a discrete event to y in place (the Eulerian core merge); returns cells merged."""
    if grid == EULERIAN:
        return eulerian.merge_core(y, geo)
    return 0


HEAT_DT = 1e-3  # K: the central difference of f in T for df/dt (f is smooth in T)


@njit(cache=True)
def par_shift(par, heat, temp):
    """``par`` at temperature ``temp``: chi0, chi1 (eq. FloryParam) and the mobility from
    the program's header row heat[0] = [A0, B0, A1, B1, mobility kind, T_ref, ...]."""
    head = heat[0]
    return KernelParams(float(par.omega), head[0] + head[1] * temp, head[2] + head[3] * temp,
                        par.perm_code, float(par.perm_beta), float(par.ell2),
                        mobility_factor(int(head[4]), temp, head[5]))


@njit(cache=True)
def par_at(par, heat, t):
    """The kernel parameters at time t: ``par`` itself without a program (empty ``heat``),
    else at the program's temperature T(t) (solver.heating)."""
    if heat.shape[0] == 0:
        return par
    temp, _ = temperature_rate(heat, t)
    return par_shift(par, heat, temp)


@njit(cache=True)
def time_derivative(grid, y, par, heat, t, geo, work, ft, ftmp):
    """df/dt at (t, y) into ``ft``: (df/dT) dT/dt, df/dT by a central difference of
    HEAT_DT in T (chi and the mobility are smooth in T); zero without a program or while
    T is constant.  Returns the rhs calls used (2 or 0)."""
    if heat.shape[0] == 0:
        return 0
    temp, rate = temperature_rate(heat, t)
    if rate == 0.0:
        ft[:] = 0.0
        return 0
    ok = rhs(grid, y, par_shift(par, heat, temp + HEAT_DT), geo, ft, work)
    ok = rhs(grid, y, par_shift(par, heat, temp - HEAT_DT), geo, ftmp, work) and ok
    if grid == MOVING:
        ale.refresh(geo, y[y.size - 1])
    if not ok:
        ft[:] = 0.0
        return 2
    scale = rate / (2.0 * HEAT_DT)
    for i in range(ft.size):
        ft[i] = (ft[i] - ftmp[i]) * scale
    if grid == MOVING:
        ft[ft.size - 1] = 0.0
    return 2
