"""Kernels of the moving grid: Lagrangian cells whose nodes move in the dry coordinate.

Between two mesh checks the nodes move in the dry coordinate at a velocity
V_k + A_k s + B_k s^2 / 2, s = t - t0, constant after s = T (rho_k = rho0_k + V_k s
+ A_k s^2 / 2 + B_k s^3 / 6 until then; the end nodes fixed), so the mesh can follow an
accelerating interface
instead of letting it cross the cells.  The unknowns are the radii of the moving nodes,
r_k(t) = r(rho_k(t), t), and the time itself (appended, dt/dt = 1, so the system stays
autonomous for the Rosenbrock integrator; its Jacobian column is one bordered column).
The chain rule adds the arbitrary-Lagrangian-Eulerian term to the solid's velocity:

    dr_k/dt = k(phi) dmu/dr (eqs. Darcy, VolConservation, as on the Lagrangian grid)
              + V_k dr/drho,     dr/drho = J rho^2 / r^2 (from r^2 dr = J rho^2 drho),

with J at the node interpolated linearly between the adjacent cell midpoints.  The solid
stays exact (the cells' dry volumes follow from the nodes) and so does the total volume
(the edge node does not move).  Every kernel first sets the geometry rows 0-2 (those of
``lagrangian.py``: nodes, volume midpoints, dry volumes) to the time in its state, then
uses the Lagrangian grid's kernels.

Geometry rows: 0-2 current geometry, 3 the node velocity now, 4 rho0, 5 V, 6 [t0, moving
flag, T], 7 A, 8 B.  At rest
(flag 0) rows 0-2 are those of ``lagrangian.geometry``-style arithmetic and are not
recomputed, so a mesh at rest with equal widths is the uniform Lagrangian grid bit for bit.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from . import lagrangian
from .lagrangian import W_JAC

GEO_ROWS = 9
R_VNOW, R_NODES0, R_VEL, R_T0, R_ACC, R_JERK = 3, 4, 5, 6, 7, 8
EXTRA = 1  # the time, appended to the node radii
# the time column's difference: the fastest node moves TIME_STEP of the smallest cell
TIME_STEP = 0.1
WORK_ROWS = lagrangian.WORK_ROWS


def structure(interfacial: bool) -> tuple[int, int, int]:
    """(lower, upper, border): the Lagrangian band, bordered by the time column."""
    lower, upper, _ = lagrangian.structure(interfacial)
    return lower, upper, 1


def geometry_rows(nodes: np.ndarray) -> np.ndarray:
    """Geometry of a mesh at rest at ``nodes`` (t0 = 0)."""
    geo = np.zeros((GEO_ROWS, nodes.size))
    set_mesh(geo, nodes, np.zeros(nodes.size), 0.0)
    return geo


def set_mesh(geo: np.ndarray, nodes: np.ndarray, velocity: np.ndarray, t0: float,
             motion: tuple[np.ndarray, np.ndarray, float] | None = None) -> None:
    """In place: nodes at time t0 moving at ``velocity``; ``motion`` (A, B, T): their
    acceleration and its rate for a time T (the end nodes held fixed).  A mesh at rest gets
    rows 0-2 by lagrangian.geometry's numpy arithmetic (bit for bit the uniform grid's)."""
    if motion is None:
        zero = np.zeros(nodes.size)
        motion = (zero, zero, 0.0)
    if not set_motion(geo, nodes, velocity, motion[0], motion[1], t0, motion[2]):
        n = nodes.size - 1
        geo[0] = nodes
        geo[1, :n] = np.cbrt(0.5 * (nodes[:-1] ** 3 + nodes[1:] ** 3))
        geo[2, :n] = np.diff(nodes**3)


@njit(cache=True)
def set_motion(geo, nodes, velocity, accel, jerk, t0, span):
    """The motion rows of ``set_mesh`` (compiled: a mesh check's largest cost in Python);
    for a moving mesh also rows 0-2 at t0 (``refresh``).  Returns whether it moves."""
    n = nodes.size - 1
    moving = False
    for k in range(n + 1):
        end = k == 0 or k == n
        geo[R_NODES0, k] = nodes[k]
        geo[R_VEL, k] = 0.0 if end else velocity[k]
        geo[R_ACC, k] = 0.0 if end else accel[k]
        geo[R_JERK, k] = 0.0 if end else jerk[k]
        geo[R_VNOW, k] = geo[R_VEL, k]
        if geo[R_VEL, k] != 0.0 or geo[R_ACC, k] != 0.0 or geo[R_JERK, k] != 0.0:
            moving = True
    geo[R_T0, 0] = t0
    geo[R_T0, 1] = 1.0 if moving else 0.0
    geo[R_T0, 2] = span
    if moving:
        refresh(geo, t0)
    return moving


@njit(cache=True)
def refresh(geo, t):
    """Rows 0-2 at time t; False if a cell has collapsed (nodes out of order)."""
    n = geo.shape[1] - 1
    if geo[R_T0, 1] == 0.0:
        return True
    dt = t - geo[R_T0, 0]
    span = geo[R_T0, 2]
    sa = min(dt, span)  # the time spent accelerating
    travel = sa * (dt - 0.5 * sa)  # of the acceleration: s^2/2 until T, then T (s - T/2)
    travel3 = sa * sa * (dt / 2.0 - sa / 3.0)  # of its rate: s^3/6, then T^3/6 + T^2/2 (s - T)
    prev = 0.0
    prev3 = 0.0
    geo[0, 0] = 0.0
    ok = True
    for k in range(1, n + 1):
        x = 1.0
        if k < n:
            x = (geo[R_NODES0, k] + geo[R_VEL, k] * dt + geo[R_ACC, k] * travel
                 + geo[R_JERK, k] * travel3)
            geo[R_VNOW, k] = geo[R_VEL, k] + geo[R_ACC, k] * sa + geo[R_JERK, k] * 0.5 * sa * sa
        if not (x > prev):
            ok = False
        x3 = x * x * x
        geo[0, k] = x
        geo[1, k - 1] = np.cbrt(0.5 * (prev3 + x3))
        geo[2, k - 1] = x3 - prev3
        prev = x
        prev3 = x3
    return ok


@njit(cache=True)
def _ale_terms(y, geo, work, out):
    """Add V_k J(rho_k) rho_k^2 / r_k^2 to dr_k/dt (needs work[W_JAC] of the cells)."""
    n = geo.shape[1] - 1
    for k in range(1, n):
        v = geo[R_VNOW, k]
        if v == 0.0:
            continue
        x = geo[0, k]
        d_in = x - geo[1, k - 1]
        d_out = geo[1, k] - x
        jbar = (work[W_JAC, k - 1] * d_out + work[W_JAC, k] * d_in) / (d_in + d_out)
        r = y[k - 1]
        out[k - 1] += v * jbar * x * x / (r * r)


@njit(cache=True)
def rhs(y, par, geo, out, work):
    """d(r_1..r_n, t)/dt at the state's time; False for an unphysical state."""
    n = geo.shape[1] - 1
    if not refresh(geo, y[n]):
        return False
    if not lagrangian.rhs(y, par, geo, out, work):
        return False
    _ale_terms(y, geo, work, out)
    out[n] = 1.0
    return True


@njit(cache=True)
def jacobian(y, par, geo, work, upper, jband, jc, jd, je, out, ytmp, ftmp):
    """The Lagrangian grid's analytic band plus the ALE term's (tridiagonal), and the time
    column by a central difference; rhs into ``out``; False if unphysical.

    The time column is df/dt at fixed radii: the nodes slide under the material, so only
    the cells' widths change, by the velocity differences of neighbouring nodes, a small
    fraction of the fastest node's speed; and the rounding of the node positions and of
    the thin cells' dry volumes (x^3 - x'^3) enters the rhs amplified by the Korteweg
    term's inverse powers of the cell width.  A step that moved the fastest node 1e-7 of
    the smallest cell (the first version) left the column rounding noise, up to 100x its
    size at a running front (Omega = 300, ell = 1e-4), and a Rosenbrock method with a
    wrong Jacobian loses its order: 1e-6 steps instead of 3e-5.  Central differences at
    TIME_STEP = 0.1 of a cell agree with those at 0.03 to 5e-4 (their noise falls as
    1/step, the truncation error is below it; 1.3e-6 on a smooth profile).
    """
    n = geo.shape[1] - 1
    t = y[n]
    if not refresh(geo, t):
        return False
    if not lagrangian.jacobian(y, par, geo, work, upper, jband, jc, jd, je, out):
        return False
    _ale_terms(y, geo, work, out)
    out[n] = 1.0
    vmax = 0.0
    hmin = 1.0
    for k in range(1, n):
        v = geo[R_VNOW, k]
        hmin = min(hmin, geo[0, k] - geo[0, k - 1])
        if v == 0.0:
            continue
        vmax = max(vmax, abs(v))
        x = geo[0, k]
        d_in = x - geo[1, k - 1]
        d_out = geo[1, k] - x
        w_in = d_out / (d_in + d_out)
        w_out = d_in / (d_in + d_out)
        r = y[k - 1]
        a = v * x * x / (r * r)
        jbar = work[W_JAC, k - 1] * w_in + work[W_JAC, k] * w_out
        if k >= 2:  # r_{k-1}: y index k-2
            rl = y[k - 2]
            jband[upper + 1, k - 2] += a * w_in * (-3.0 * rl * rl / geo[2, k - 1])
        jband[upper, k - 1] += (a * (w_in * 3.0 * r * r / geo[2, k - 1]
                                     - w_out * 3.0 * r * r / geo[2, k]) - 2.0 * a * jbar / r)
        ru = y[k]
        jband[upper - 1, k] += a * w_out * 3.0 * ru * ru / geo[2, k]
    jd[0, :] = 0.0
    je[0, 0] = 0.0
    if vmax == 0.0:
        jc[:, 0] = 0.0
        return True
    d = TIME_STEP * hmin / vmax
    for i in range(n):
        ytmp[i] = y[i]
    ytmp[n] = t + d
    ok = rhs(ytmp, par, geo, ftmp, work)
    for i in range(n):
        jc[i, 0] = ftmp[i]
    ytmp[n] = t - d
    ok = ok and rhs(ytmp, par, geo, ftmp, work)
    refresh(geo, t)
    if not ok:
        return False
    for i in range(n):
        jc[i, 0] = (jc[i, 0] - ftmp[i]) / (2.0 * d)
    return True


@njit(cache=True)
def fd_scale(y, geo, out):
    """Finite-difference increments: the Lagrangian grid's, and for the time 0.1 TIME_STEP
    of the time the fastest node needs to cross the smallest cell (a forward difference:
    smaller than the analytic Jacobian's central one, larger than the rhs's rounding
    allows below, see ``jacobian``)."""
    n = geo.shape[1] - 1
    refresh(geo, y[n])
    lagrangian.fd_scale(y, geo, out)
    vmax = 0.0
    hmin = 1.0
    for k in range(1, n):
        vmax = max(vmax, abs(geo[R_VNOW, k]))
        hmin = min(hmin, geo[0, k] - geo[0, k - 1])
    out[n] = 0.1 * TIME_STEP * hmin / vmax if vmax > 0.0 else 1e-7


@njit(cache=True)
def error_norm(y, ynew, err, geo, rtol, atol, work):
    """The Lagrangian grid's norm at the new state's geometry (the time has no error)."""
    n = geo.shape[1] - 1
    refresh(geo, ynew[n])
    return lagrangian.error_norm(y, ynew, err, geo, rtol, atol, work)


@njit(cache=True)
def porosity(y, geo, out):
    """Cell porosities at the state's time (geometry rows set to it); returns a."""
    n = geo.shape[1] - 1
    refresh(geo, y[n])
    return lagrangian.porosity(y, geo, out)
