"""RODASP: a 6-stage, order-4(3), L-stable, stiffly accurate Rosenbrock method, in numba.

Coefficients: Steinebach (1995), RODASP (RODAS4 variant without order reduction on
parabolic problems), given as alpha_ij and beta_ij = alpha_ij + gamma_ij with gamma = 1/4;
they are converted here to the transformed form of Hairer & Wanner (1996, sec. IV.7),

    (I/(h gamma) - J) U_i = f(y0 + sum_j a_ij U_j) + sum_j (c_ij / h) U_j,
    y1 = y0 + sum_i m_i U_i,     error = sum_i (m_i - mhat_i) U_i,

so each step needs one Jacobian, one factorization and six bordered band solves.

A non-autonomous system y' = f(t, y) (a temperature program, ``heat``: docs/heating.md)
evaluates stage i at t0 + alpha_i h and adds gamma_i h df/dt(t0, y0) to its right-hand side
(Hairer & Wanner IV.7, eq. 7.4'), alpha_i = sum_j alpha_ij, gamma_i = sum_j gamma_ij; df/dt
is (df/dT) dT/dt by a central difference in T.  An empty ``heat`` is the autonomous method.

Terminal events: ``ctrl[4:8]`` holds two radius targets (target, direction), direction -1
(the radius falls to it), +1 (rises to it) or 0 (off); an accepted step that reaches one
ends the run with RUN_EVENT, and the driver locates the time inside the step.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import njit

from .banded import bordered_factor, bordered_solve
from .system import (
    edge_porosity,
    error_norm,
    event,
    linearize,
    par_at,
    radius_index,
    rhs,
    time_derivative,
    underflow,
)

GAMMA = 0.25
_ALPHA = np.zeros((6, 6))
_ALPHA[1, 0] = 0.75
_ALPHA[2, :2] = [8.6120400814152190e-2, 0.1238795991858478]
_ALPHA[3, :3] = [0.7749345355073236, 0.1492651549508680, -0.2941996904581916]
_ALPHA[4, :4] = [5.308746682646142, 1.330892140037269, -5.374137811655562, -0.2655010110278497]
_ALPHA[5, :5] = [-1.764437648774483, -0.4747565572063027, 2.369691846915802,
                 0.6195023590649829, 0.25]
_BETA = np.zeros((6, 6))
_BETA[2, :2] = [-0.049392, -0.014112]
_BETA[3, :3] = [-0.4820494693877561, -0.1008795555555556, 0.9267290249433117]
_BETA[4, :4] = [-1.764437648774483, -0.4747565572063027, 2.369691846915802, 0.6195023590649829]
_BETA[5, :5] = [-8.0368370789113464e-2, -5.6490613592447572e-2, 0.4882856300427991,
                0.5057162114816189, -0.1071428571428569]


def _transformed() -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(a, c, m, m - mhat) of the transformed method from (alpha, beta)."""
    gam = _BETA - _ALPHA
    np.fill_diagonal(gam, GAMMA)
    ginv = np.linalg.inv(gam)
    b = np.append(_BETA[5, :5], GAMMA)
    bhat = np.append(np.append(_BETA[4, :4], GAMMA), 0.0)
    a = _ALPHA @ ginv
    c = np.diag(np.full(6, 1.0 / GAMMA)) - ginv
    m = b @ ginv
    mhat = bhat @ ginv
    return np.tril(a, -1), np.tril(c, -1), m, m - mhat


A_COEF, C_COEF, M_COEF, E_COEF = _transformed()


class Method(NamedTuple):
    """A Rosenbrock method in transformed form: tableau = [gamma, 1/(embedded order + 1),
    alpha_i (stage times), gamma_i (weights of df/dt)], a, c, m, e."""

    tableau: np.ndarray
    a: np.ndarray
    c: np.ndarray
    m: np.ndarray
    e: np.ndarray


ALPHA_SUM = _ALPHA.sum(axis=1)
GAMMA_SUM = _BETA.sum(axis=1) - _ALPHA.sum(axis=1) + GAMMA
RODASP = Method(np.concatenate([[GAMMA, 0.25], ALPHA_SUM, GAMMA_SUM]), A_COEF, C_COEF,
                M_COEF, E_COEF)


# The kernels' arguments come in typed bundles (numba NamedTuples), built once per run by
# integrate.Workspace / run_implicit and passed through, so no kernel has a long signature.
class Band(NamedTuple):
    """The bordered band Jacobian J = [[jband, jc], [jd, je]] (half-widths ``lower``,
    ``upper``; banded.py) and the factorization of I/(h gamma) - J: band LU ``lu`` with
    pivots ``ipiv``, border blocks ``cm``, ``dm``, ``xm``, Schur complement ``em`` with
    pivots ``spiv``, and the border solve's buffer ``zbuf``."""

    lower: int
    upper: int
    jband: np.ndarray
    jc: np.ndarray
    jd: np.ndarray
    je: np.ndarray
    lu: np.ndarray
    ipiv: np.ndarray
    cm: np.ndarray
    dm: np.ndarray
    xm: np.ndarray
    em: np.ndarray
    spiv: np.ndarray
    zbuf: np.ndarray


class Buffers(NamedTuple):
    """Scratch of one step: the grid kernels' ``work`` rows, the stages ``u`` (row
    ``stages``: df/dt), a trial state and its f (``ytmp``, ``ftmp``), the new state and its
    f (``ynew``, ``fnew``), the local error ``errv`` and the finite-difference increments
    ``scale``."""

    work: np.ndarray
    u: np.ndarray
    ytmp: np.ndarray
    ftmp: np.ndarray
    ynew: np.ndarray
    fnew: np.ndarray
    errv: np.ndarray
    scale: np.ndarray


class State(NamedTuple):
    """What the steps advance in place: y and f = f(t, y), the last accepted step's start
    ``yold``, ``fold`` (dense output), and tt = [t, t of yold]."""

    y: np.ndarray
    f: np.ndarray
    yold: np.ndarray
    fold: np.ndarray
    tt: np.ndarray


class Control(NamedTuple):
    """The step controller: tolerances, Jacobian mode (system.JAC_*), ``counters`` (C_*;
    [5] the record's fill), ``ctrl`` (CTRL_SIZE: step sizes, error, Jacobian flag, event
    targets) and ``rec`` (4, capacity), the per-step record of (t, a, da/dt, edge
    porosity)."""

    rtol: float
    atol: float
    jac_mode: int
    counters: np.ndarray
    ctrl: np.ndarray
    rec: np.ndarray



@njit(cache=True)
def _combine(base, coef, row, scale, u, out):
    """out = base + scale * sum_{j < row} coef[row, j] U_j."""
    n = base.size
    for i in range(n):
        out[i] = base[i]
    for j in range(row):
        cj = coef[row, j] * scale
        if cj != 0.0:
            uj = u[j]
            for i in range(n):
                out[i] += cj * uj[i]


@njit(cache=True)
def rodas_try(grid, y, f0, t, h, par, heat, geo, band, buf, method, control):
    """One RODASP step of size h from (t, y, f0 = f(t, y)) with the Jacobian in ``band``
    into ``buf.ynew`` (its error estimate in ``buf.errv``); with a temperature program
    ``heat``, stage times t + alpha_i h and buf.u[stages] = df/dt.

    Returns (status, error norm): status 0 done, 1 singular iteration matrix,
    2 an unphysical stage state (the caller shrinks the step).
    """
    lower, upper = band.lower, band.upper
    jband, jc, jd, je = band.jband, band.jc, band.jd, band.je
    lu, ipiv, cm, dm, xm, em = band.lu, band.ipiv, band.cm, band.dm, band.xm, band.em
    spiv, zbuf = band.spiv, band.zbuf
    work, u, ytmp, ftmp = buf.work, buf.u, buf.ytmp, buf.ftmp
    ynew, errv = buf.ynew, buf.errv
    tableau, acoef, ccoef = method.tableau, method.a, method.c
    mcoef, ecoef = method.m, method.e
    gamma = tableau[0]
    m = jband.shape[1]
    p = je.shape[0]
    n = y.size
    hg = 1.0 / (h * gamma)
    stages = mcoef.size
    kv = lower + upper
    lu[:, :] = 0.0
    for j in range(m):
        for i in range(max(0, j - upper), min(m, j + lower + 1)):
            lu[kv + i - j, j] = -jband[upper + i - j, j]
        lu[kv, j] += hg
    for i in range(m):
        for k in range(p):
            cm[i, k] = -jc[i, k]
    for r in range(p):
        for i in range(m):
            dm[r, i] = -jd[r, i]
        for k in range(p):
            em[r, k] = -je[r, k]
        em[r, r] += hg
    if not bordered_factor(lu, lower, upper, ipiv, cm, dm, em, xm, spiv):
        return 1, np.inf
    for s in range(stages):
        if s == 0:
            for i in range(n):
                ftmp[i] = f0[i]
        else:
            _combine(y, acoef, s, 1.0, u, ytmp)
            par_s = par_at(par, heat, t + tableau[2 + s] * h)
            if not rhs(grid, ytmp, par_s, geo, ftmp, work):
                return 2, np.inf
        if heat.shape[0] > 0:
            gh = tableau[2 + stages + s] * h
            ft = u[stages]
            for i in range(n):
                ftmp[i] += gh * ft[i]
        _combine(ftmp, ccoef, s, 1.0 / h, u, u[s])
        bordered_solve(lu, lower, upper, ipiv, dm, xm, em, spiv, u[s], zbuf)
    for i in range(n):
        ynew[i] = y[i]
        errv[i] = 0.0
    for s in range(stages):
        ms, es = mcoef[s], ecoef[s]
        us = u[s]
        for i in range(n):
            ynew[i] += ms * us[i]
            errv[i] += es * us[i]
    return 0, error_norm(grid, y, ynew, errv, geo, control.rtol, control.atol, work)


# counters: rhs calls, Jacobians, accepted steps, rejected steps, merge events
C_RHS, C_JAC, C_STEPS, C_REJECTED, C_MERGES = 0, 1, 2, 3, 4
# run status
RUN_REACHED, RUN_RECORD_FULL, RUN_BUDGET, RUN_UNDERFLOW, RUN_BAD_STATE = 0, 1, 2, 3, 4
RUN_EVENT = 5
# PAUSE_ATTEMPTS step attempts (accepted or rejected) in one call: back to the driver, which
# checks its wall-clock budget and calls again with the same state (all of the loop's
# state is in ``state`` and ``control``: the steps are those of one uninterrupted call)
RUN_PAUSED = 6
PAUSE_ATTEMPTS = 4096
# [h, last h, last error, Jacobian valid, stop target, dir, step target, dir, no snap]
CTRL_SIZE = 9


@njit(cache=True)
def crossed(ctrl, a):
    """True if radius a has reached one of the event targets in ctrl[4:8]."""
    for k in (4, 6):
        d = ctrl[k + 1]
        if d != 0.0 and (a - ctrl[k]) * d >= 0.0:
            return True
    return False


SAFETY, FAC_MIN, FAC_MAX = 0.9, 0.2, 6.0


@njit(cache=True)
def rodas_run(grid, state, t_stop, t_seg, budget, par, heat, geo, band, buf, method,
              control):
    """Adaptive RODASP steps from tt[0] until tt[0] >= t_stop (never past t_seg), or until
    an accepted step reaches an event target (RUN_EVENT; ``crossed``), or ``budget``
    accepted steps in all.

    ``state`` (y, f = f(y), yold, fold, tt) advances in place; yold, fold and tt[1] keep
    the last step's start for dense output.  control.ctrl = [h, h of the last accepted
    step, its error, Jacobian valid flag] (Gustafsson's predictive controller, Hairer &
    Wanner IV.8), then the event targets.  ``heat``: the segment's temperature program row
    (empty: constant ``par``).  An accepted step is linearized at once (f and J at the new
    state; an unphysical new state rejects it).  control.rec = (4, capacity) record of
    (t, a, da/dt, edge-cell porosity) per accepted step, its count in counters[5].
    Returns a RUN_* status; RUN_PAUSED after PAUSE_ATTEMPTS attempts (call again: the
    steps are those of one call).

    A step that would end within 1e-12 of t_seg is stretched to end there ("snapped").  If
    such a step is rejected and the controller's smaller step would be snapped again, the
    retry would be the very same step, rejected for ever (issue 40, R2: a protocol step of
    1e-12 tau after a temperature jump spun at 100 % CPU).  Then, until the next accepted
    step (ctrl[8] = 1), steps are not snapped: the smaller step is taken as it is.  No run
    that ever finished took that branch, so this changes no step of any of them.
    """
    y, f, yold, fold, tt = state.y, state.f, state.yold, state.fold, state.tt
    lower, upper = band.lower, band.upper
    jband, jc, jd, je = band.jband, band.jc, band.jd, band.je
    work, u, ytmp, ftmp = buf.work, buf.u, buf.ytmp, buf.ftmp
    ynew, fnew, scale = buf.ynew, buf.fnew, buf.scale
    tableau, mcoef = method.tableau, method.m
    counters, ctrl, rec = control.counters, control.ctrl, control.rec
    jac_mode, max_steps = control.jac_mode, budget
    n = y.size
    ia = radius_index(grid, n)
    floor = underflow(grid)
    expo = tableau[1]
    attempts = 0
    while tt[0] < t_stop:
        if counters[C_STEPS] >= max_steps:
            return RUN_BUDGET
        if counters[5] >= rec.shape[1]:
            return RUN_RECORD_FULL
        if attempts >= PAUSE_ATTEMPTS:
            return RUN_PAUSED
        attempts += 1
        t = tt[0]
        if ctrl[3] == 0.0:
            calls = linearize(grid, y, f, par_at(par, heat, t), geo, work, lower, upper,
                              jband, jc, jd, je, ytmp, ftmp, scale, jac_mode)
            counters[C_JAC] += 1
            if calls < 0:
                return RUN_BAD_STATE
            calls += time_derivative(grid, y, par, heat, t, geo, work, u[mcoef.size], ftmp)
            counters[C_RHS] += calls
            ctrl[3] = 1.0
        h = ctrl[0]
        last = False
        if t + h >= t_seg - 1e-12 * max(1.0, abs(t_seg)) and not (
                ctrl[8] != 0.0 and h < t_seg - t):
            h = t_seg - t
            last = True
        if h < floor * max(1.0, abs(t)):
            return RUN_UNDERFLOW
        status, err = rodas_try(grid, y, f, t, h, par, heat, geo, band, buf, method,
                                control)
        counters[C_RHS] += mcoef.size - 1
        ok = status == 0 and err <= 1.0
        t_new = t_seg if last else t + h
        if ok:
            calls = linearize(grid, ynew, fnew, par_at(par, heat, t_new), geo, work, lower,
                              upper, jband, jc, jd, je, ytmp, ftmp, scale, jac_mode)
            counters[C_JAC] += 1
            ok = calls >= 0
            if ok:
                calls += time_derivative(grid, ynew, par, heat, t_new, geo, work,
                                         u[mcoef.size], ftmp)
                counters[C_RHS] += calls
            else:
                ctrl[3] = 0.0  # J now belongs to no state: recompute at y
        if not ok:
            counters[C_REJECTED] += 1
            if status != 0 or not np.isfinite(err) or err > 1e10 or err <= 1.0:
                ctrl[0] = 0.25 * h
            else:
                ctrl[0] = h * max(FAC_MIN, min(1.0, SAFETY * err**-expo))
            if last and t + ctrl[0] >= t_seg - 1e-12 * max(1.0, abs(t_seg)):
                ctrl[8] = 1.0  # the retry would be this step again: do not snap it
            continue
        ctrl[8] = 0.0
        quot = max(1.0 / FAC_MAX, min(1.0 / FAC_MIN, max(err, 1e-12) ** expo / SAFETY))
        if ctrl[1] > 0.0:
            gus = (ctrl[1] / h) * (max(err, 1e-12) ** 2 / ctrl[2]) ** expo / SAFETY
            quot = max(quot, max(1.0 / FAC_MAX, min(1.0 / FAC_MIN, gus)))
        ctrl[1] = h
        ctrl[2] = max(1e-2, err)
        tt[1] = t
        for i in range(n):
            yold[i] = y[i]
            fold[i] = f[i]
            y[i] = ynew[i]
            f[i] = fnew[i]
        tt[0] = t_new
        ctrl[0] = h / quot
        counters[C_STEPS] += 1
        if event(grid, y, geo) > 0:
            counters[C_MERGES] += 1
            ctrl[3] = 0.0
            ctrl[0] = min(ctrl[0], 1e-2 * h)
            ctrl[1] = 0.0
            if not rhs(grid, y, par_at(par, heat, t_new), geo, f, work):
                return RUN_BAD_STATE
            counters[C_RHS] += 1
        k = counters[5]
        rec[0, k] = tt[0]
        rec[1, k] = y[ia]
        rec[2, k] = f[ia]
        rec[3, k] = edge_porosity(grid, y, geo)
        counters[5] = k + 1
        if crossed(ctrl, y[ia]):
            return RUN_EVENT
    return RUN_REACHED
