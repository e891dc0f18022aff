"""A batch of drug-loaded beads releasing into one shared, well-mixed medium (issue 26).

Dimensionless as the rest of the package: lengths by a bead's dry radius, volumes in units
of its dry volume 4 pi R^3 / 3, time by tau of the reference bead (eq. timescale).  Every
bead sees the medium's concentration c(t).  The solute is linear in (m, c) for a given
mechanics, so the batch is one linear system: the cells of every size class k (its own
Lagrangian solute, module ``kernels``) and the drug in the medium P (a fraction of the
batch's load).  Class k follows the batch's one dimensionless trajectory in its own time
s = t / rho_k (rho_k = tau_k / tau_ref = (R_k / R_ref)^2, as tau ~ R^2 in eq. timescale);
in its own units (load, 4 pi R_k^3 / 3) its operator is the single bead's
``kernels.operator`` with the medium's unknown read as c:

    dm_k/dt = (A_k m_k + alpha_k c e_edge) / rho_k,
    dP/dt   = sum_k nu_k (beta_k m_k,edge - alpha_k c) / rho_k,     c = P / v(t),

with nu_k the classes' shares of the load (their volume weights: a bead's load is
K c_load (a0^3 - 1) 4 pi R^3 / 3 with one loading solution), v(t) = v0 + sum_k nu_k
(a0^3 - a_k(t)^3) the medium in units of the batch's dry volume (it grows by the expelled
fluid, eq. FluidVolExpelled, as the single bead's), beta_k the edge's outflow per unit edge
mass and alpha_k the medium's back-flux per unit c (re-absorption included).  A perfect sink
is c = 0.  One bead class with nu = 1 is exactly the single bead in a medium v0 (the
kernel's finite-medium boundary condition).

Time: fixed-step TR-BDF2 (the kernel's scheme) on the union of the classes' mechanics
sample times (t = rho_k s_j: no step crosses a kink of any class's piecewise-linear
geometry), each interval cut into ``sub`` steps, or on even intervals; the node fluxes are
each step's mean and the conductances frozen at each class's sample interval's midpoint, as
the kernel does (at the step's midpoint when a step spans several).  Each implicit stage is
an arrowhead system solved by its Schur complement: two tridiagonal solves per class, then
one scalar equation for P.  Every flux enters two rows with opposite signs (in load
units), so the batch's mass is conserved to round-off by the scheme.

The entry point is :func:`coupled_release` (a :class:`~.result.MediumRelease`); the
planner's way in is ``dosing.batch_drug``.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numba import njit

from ..errors import ParameterError, SolverError
from .kernels import A_N, A_U, D_COEF, GAMMA, _solve, cell_props, conductances, operator
from .result import MediumRelease
from .transport import Solute

GRADING = 0.25  # near the start, steps <= GRADING / sub x t (the start's sqrt(t) layer)
START_FLOOR = 1e-10  # the first step, a fraction of the grid's first interval


@njit(cache=True)
def _volumes(s, s3, x, out):
    """r^3 at the nodes at own time x (linear between samples; the final state after the
    trajectory's end: the bead rests there)."""
    last = s.size - 1
    if x >= s[last]:
        out[:] = s3[last]
        return
    j = np.searchsorted(s, x, side="right") - 1
    th = (x - s[j]) / (s[j + 1] - s[j])
    for i in range(out.size):
        out[i] = (1.0 - th) * s3[j, i] + th * s3[j + 1, i]


@njit(cache=True)
def _march(grid, s_all, s3_all, ns, band, dw, rd, par, rho, nu, v0, m, out_at, out_cls, out_p,
           out_c):
    """TR-BDF2 over ``grid`` for every class (state ``m``, classes x cells, updated) and
    the medium (module doc); class k follows mechanics ``band[k]`` (its samples
    ``s_all[b, :ns[b]]``, node volumes ``s3_all[b, :ns[b]]``); ``v0`` <= 0 a perfect sink.
    Writes the classes' released fractions, the medium's drug and concentration at the grid
    points flagged in ``out_at`` (>= 0: the output's index).  Returns (steps, max |mass - 1|,
    status)."""
    kk, n = m.shape
    sink = v0 <= 0.0
    lo = np.zeros((kk, n + 1))
    di = np.zeros((kk, n + 1))
    up = np.zeros((kk, n + 1))
    g = np.zeros((kk, n))
    frozen = np.full(kk, -1)
    s3a = np.zeros((kk, n + 1))
    s3b = np.zeros((kk, n + 1))
    q = np.zeros((kk, n))
    al = np.zeros(kk)
    be = np.zeros(kk)
    r3 = np.zeros(n + 1)
    mid = np.zeros(n + 1)
    fw, fl = np.zeros(n), np.zeros(4)
    phi, lam, kc, wc = np.zeros(n), np.zeros(n), np.zeros(n), np.zeros(n)
    cp = np.zeros(n + 1)
    f0 = np.zeros((kk, n))
    u = np.zeros((kk, n))
    av = np.zeros((kk, n))
    bv = np.zeros((kk, n))
    rhs = np.zeros(n)
    e = np.zeros(n)
    a3_0 = s3_all[0, 0, n]  # every mechanics starts from the same loaded bead
    p = 0.0
    balance = 0.0
    steps = 0

    up_p = 0.0
    fp0 = 0.0
    o = out_at[0]
    if o >= 0:
        for k in range(kk):
            out_cls[k, o] = 1.0 - np.sum(m[k])
        out_c[o] = 0.0
    for i in range(grid.size - 1):
        ta, tb = grid[i], grid[i + 1]
        h = tb - ta
        if not h > 0.0:
            continue
        dh = D_COEF * h
        for k in range(kk):  # the step's geometry, node fluxes and conductances per class
            b = band[k]
            s = s_all[b, : ns[b]]
            s3 = s3_all[b, : ns[b]]
            last = ns[b] - 1
            sa, sb = ta / rho[k], tb / rho[k]
            _volumes(s, s3, sa, s3a[k])
            _volumes(s, s3, sb, s3b[k])
            for j in range(n):
                q[k, j] = -(s3b[k, j + 1] - s3a[k, j + 1]) / (sb - sa)
            if par.d0 > 0.0:
                sm = 0.5 * (sa + sb)
                j = np.searchsorted(s, sm, side="right") - 1
                tol = 1e-12 * max(1.0, sb)
                key = -1
                if j < last and sa >= s[j] - tol and sb <= s[j + 1] + tol:
                    key = j  # inside one sample interval: frozen at its midpoint (kernel)
                    for c in range(n + 1):
                        mid[c] = 0.5 * (s3[j, c] + s3[j + 1, c])
                else:
                    for c in range(n + 1):
                        mid[c] = 0.5 * (s3a[k, c] + s3b[k, c])
                if key < 0 or key != frozen[k]:
                    conductances(mid, dw, rd, par, g[k], phi, lam, kc, wc)
                frozen[k] = key
        for stage in range(3):
            theta = 0.0 if stage == 0 else (GAMMA if stage == 1 else 1.0)
            vol = v0
            for k in range(kk):
                for c in range(n + 1):
                    r3[c] = (1.0 - theta) * s3a[k, c] + theta * s3b[k, c]
                if not operator(r3, dw, rd, par, q[k], g[k], 1.0, lo[k], di[k], up[k], fw,
                                fl, phi, lam, kc, wc):
                    return steps, balance, 2
                al[k] = up[k, n - 1]
                be[k] = lo[k, n - 1]
                vol += nu[k] * (a3_0 - r3[n])
            inv_v = 0.0 if sink else 1.0 / vol
            if stage == 0:  # f0 = B y at the step's start
                conc = p * inv_v
                fp0 = 0.0
                for k in range(kk):
                    for c in range(n):
                        x = di[k, c] * m[k, c]
                        if c > 0:
                            x += lo[k, c - 1] * m[k, c - 1]
                        if c < n - 1:
                            x += up[k, c] * m[k, c + 1]
                        f0[k, c] = x
                    f0[k, n - 1] += al[k] * conc
                    for c in range(n):
                        f0[k, c] /= rho[k]
                    fp0 += nu[k] * (be[k] * m[k, n - 1] - al[k] * conc) / rho[k]
                continue
            # (I - dh B) (y, P) = (rhs, rp) by the Schur complement on P
            den = 1.0
            num = p + dh * fp0 if stage == 1 else A_U * up_p + A_N * p
            for k in range(kk):
                for c in range(n):
                    rhs[c] = m[k, c] + dh * f0[k, c] if stage == 1 else \
                        A_U * u[k, c] + A_N * m[k, c]
                _solve(lo[k, : n - 1], di[k, :n], up[k, : n - 1], dh / rho[k], rhs, av[k], cp)
                if inv_v > 0.0:
                    e[:] = 0.0
                    e[n - 1] = dh * al[k] * inv_v / rho[k]
                    _solve(lo[k, : n - 1], di[k, :n], up[k, : n - 1], dh / rho[k], e, bv[k],
                           cp)
                else:
                    bv[k, :] = 0.0
                w = nu[k] * dh * be[k] / rho[k]
                den += nu[k] * dh * al[k] * inv_v / rho[k] - w * bv[k, n - 1]
                num += w * av[k, n - 1]
            pp = num / den
            if stage == 1:
                for k in range(kk):
                    for c in range(n):
                        u[k, c] = av[k, c] + pp * bv[k, c]
                up_p = pp
            else:
                for k in range(kk):
                    for c in range(n):
                        m[k, c] = av[k, c] + pp * bv[k, c]
                p = pp
                total = p
                for k in range(kk):
                    total += nu[k] * np.sum(m[k])
                if not np.isfinite(total):
                    return steps, balance, 2
                balance = max(balance, abs(total - 1.0))
                steps += 1
                o = out_at[i + 1]
                if o >= 0:
                    for k in range(kk):
                        out_cls[k, o] = 1.0 - np.sum(m[k])
                    out_p[o] = p
                    out_c[o] = p * inv_v
    return steps, balance, 0


def _start(s3: np.ndarray, dw: np.ndarray, par: Any) -> tuple[np.ndarray, np.ndarray]:
    """(dry node radii, the loaded state): uniform in equilibrium with one loading solution
    (m_i ~ w_i K_i, total 1), as :func:`.transport.release_on_nodes`."""
    n = dw.size
    rho = np.cbrt(np.concatenate(([0.0], np.cumsum(dw))))
    phi, lam, kc, wc = (np.zeros(n) for _ in range(4))
    cell_props(np.ascontiguousarray(s3[0]), dw, rho, par, phi, lam, kc, wc)
    m = (s3[0, 1:] - s3[0, :-1] - dw) * kc
    return rho, m / m.sum()


def time_grid(s: Any, rho: np.ndarray, t_end: float, times: np.ndarray,
              sub: int, points: int | None = None) -> np.ndarray:
    """The union of the classes' sample times rho_k s_j (``s``: one array, or one per class;
    or, given ``points``, that many even intervals; 0: none) and the output times up to
    ``t_end``, each interval cut into ``sub`` equal steps, the start graded."""
    outs = np.unique(np.concatenate((times[times <= t_end], [0.0, t_end])))
    per = s if isinstance(s, list) else [s] * len(rho)
    pts = [np.zeros(0)]
    if points is None:
        pts += [r * sk[r * sk < t_end] for r, sk in zip(rho, per, strict=True)]
    elif points > 0:
        pts.append(np.linspace(0.0, t_end, points + 1))
    eps = 1e-14 * max(t_end, 1.0)
    # a sample within eps of an output gives way to it (the outputs stay on the grid)
    other = np.unique(np.concatenate(pts))
    j = np.searchsorted(outs, other)
    lo, hi = outs[np.maximum(j - 1, 0)], outs[np.minimum(j, outs.size - 1)]
    near = np.minimum(np.abs(other - lo), np.abs(other - hi)) <= eps
    base = np.unique(np.concatenate((outs, other[~near])))
    base = base[np.concatenate(([True], np.diff(base) > eps)) | np.isin(base, outs)]
    frac = np.arange(sub) / sub
    fine = np.concatenate(((base[:-1, None] + np.diff(base)[:, None] * frac[None, :]).ravel(),
                           base[-1:]))
    if fine.size < 2:
        return fine
    # the release starts in a diffusive layer (sqrt(t)): steps <= q t until the grid's own
    # steps are finer (q = GRADING / sub, so the start converges with the rest)
    q = GRADING / sub
    h0 = fine[1]
    k = int(math.ceil(math.log(1.0 / (q * START_FLOOR)) / math.log1p(q)))
    geo = h0 * START_FLOOR * (1.0 + q) ** np.arange(k + 1)
    return np.unique(np.concatenate((fine, geo[geo < h0 / q])))


def coupled_release(s: Any, s3: Any, solute: Solute, rho: Any, nu: Any,
                    medium_volume: float | None, times: Any, sub: int = 2,
                    points: int | None = None, band: Any = None) -> MediumRelease:
    """The batch's release into one medium (module doc).

    ``s`` (samples) and ``s3`` (samples, n + 1: the node volumes r^3 of the dry cells,
    :func:`.transport.node_volumes`) are the one dimensionless mechanics trajectory, or
    lists of several (one per interfacial-length band, the same n and start) with ``band``
    the index of each class's; ``solute`` its drug (its own ``release_volume`` is not used);
    ``rho`` the classes' tau over the reference tau, ``nu`` their shares of the load
    (normalised here); ``medium_volume`` v0 in units of the batch's dry volume (None: a
    perfect sink); ``times`` the outputs (units of tau_ref, from 0); ``sub`` steps per grid
    interval; ``points``: even grid intervals (None: the classes' own sample times; 0: the
    outputs alone)."""
    several = isinstance(s, (list, tuple))
    ss = [np.asarray(x, dtype=float) for x in (s if several else [s])]
    s3s = [np.ascontiguousarray(x, dtype=float) for x in (s3 if several else [s3])]
    rho = np.atleast_1d(np.asarray(rho, dtype=float))
    nu = np.atleast_1d(np.asarray(nu, dtype=float))
    times = np.asarray(times, dtype=float)
    if rho.size != nu.size or rho.size == 0 or not np.all(rho > 0) or not np.all(nu >= 0):
        raise ParameterError("size_distribution", rho.size, "classes with tau > 0 and "
                             "shares >= 0")
    nu = nu / nu.sum()
    bands = np.zeros(rho.size, dtype=np.int64) if band is None else np.asarray(band,
                                                                             dtype=np.int64)
    if len(ss) != len(s3s) or bands.shape != rho.shape or bands.min() < 0 or \
            bands.max() >= len(ss):
        raise ParameterError("band", band, f"one index 0-{len(ss) - 1} per class")
    for x, x3 in zip(ss, s3s, strict=True):
        if x.size < 2 or x3.shape[0] != x.size or abs(x[0]) > 1e-14 or \
                x3.shape[1] != s3s[0].shape[1]:
            raise ParameterError("mechanics", x.size, "at least two samples from s = 0 (the "
                                 "same cells in every band)")
    if times.size == 0 or times[0] < 0 or np.any(np.diff(times) < 0):
        raise ParameterError("times", times, "non-decreasing times >= 0")
    if isinstance(sub, bool) or not isinstance(sub, int) or not 1 <= sub <= 64:
        raise ParameterError("sub", sub, "an integer 1-64")
    n = s3s[0].shape[1] - 1
    if medium_volume is not None and not medium_volume > 0.0:
        raise ParameterError("medium_volume", medium_volume, "None (a perfect sink) or > 0")
    ns = np.array([x.size for x in ss], dtype=np.int64)
    s_all = np.zeros((len(ss), int(ns.max())))
    s3_all = np.zeros((len(ss), int(ns.max()), n + 1))
    for b, (x, x3) in enumerate(zip(ss, s3s, strict=True)):
        s_all[b, : x.size], s3_all[b, : x.size] = x, x3
    s3 = s3s[0]
    dw = np.diff((np.arange(n + 1) / n) ** 3)
    par = solute.params()
    rd, m0 = _start(s3, dw, par)
    grid = time_grid([ss[b] for b in bands], rho, float(times[-1]), times, sub, points)
    at = np.searchsorted(grid, times)
    at = np.minimum(at, grid.size - 1)
    if not np.allclose(grid[at], times, rtol=1e-12, atol=1e-300):
        raise SolverError("batch medium: an output time off the grid", {})
    out_at = np.full(grid.size, -1, dtype=np.int64)
    out_at[at] = np.arange(times.size)  # repeated output times: the last takes it
    out_rel = np.zeros((rho.size, times.size))
    out_p = np.zeros(times.size)
    out_c = np.zeros(times.size)
    m = np.ascontiguousarray(np.tile(m0, (rho.size, 1)))
    sink = medium_volume is None
    v0 = -1.0 if sink else float(medium_volume)
    steps, balance, status = _march(grid, s_all, s3_all, ns, bands, dw, rd, par, rho, nu, v0,
                                    m, out_at, out_rel, out_p, out_c)
    if status != 0:
        raise SolverError("batch medium: a cell without fluid or a non-finite state",
                          {"steps": int(steps)})
    dup = np.nonzero(np.diff(times) == 0.0)[0]
    for j in dup[::-1]:  # a repeated output time copies its twin
        out_rel[:, j], out_p[j], out_c[j] = out_rel[:, j + 1], out_p[j + 1], out_c[j + 1]
    return MediumRelease(
        t=times.copy(), released=out_p, class_released=out_rel, concentration=out_c,
        nu=nu, rho=rho, medium_volume=None if sink else v0, mass_balance_error=float(balance),
        steps=int(steps), diagnostics={"grid_points": int(grid.size), "sub": sub, "n": n})
