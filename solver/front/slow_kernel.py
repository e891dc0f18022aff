"""The compiled integrator of the slow-heating front model (module slow): Dormand-Prince
5(4) with error control, steps that land on the program's kinks, a terminal condition and
dose radii located inside the accepted step by bisection on the step size.

Stage 0 (uniform): y = V = a^3, dV/dt = -m(T) (V - V_eq(T)) 15 D / a^2; it stops when
T(t) >= T_n(a) (the coexistence onset, tabulated).  Stage 1 (front): y = X = R_f^3,
dX/dt = 3 R_f^2 dR_f/dt (module slow's formula), a^3 = (1 + (s_+ - s_-) X) / s_+; it stops
when the core is gone (X <= CENTRE).  ``par`` = [Omega, A0, B0, A1, B1, permeability code,
beta, mobility code, T_ref, s_-, T_lo, T_hi] (T_lo, T_hi: the level tables' domain).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from ..full.kernels import permeability
from ..heating import mobility_factor, temperature_rate
from ..thermo import osmotic_dp as _osmotic_dp
from .evolve import _clenshaw as _clenshaw_kernel

# numba kernels call the dispatchers (solver.jit)
osmotic_dp = _osmotic_dp.compiled
_clenshaw = _clenshaw_kernel.compiled

LAG_MODES = 15.0  # 1 / sum_n 6 / (n pi)^4: a one-mode closure of the sphere's volume lag
CENTRE = 1e-12  # R_f^3 at which the core is gone
MAX_STEPS = 200_000

# Dormand-Prince 5(4)
C = np.array([0.0, 1 / 5, 3 / 10, 4 / 5, 8 / 9, 1.0, 1.0])
A = np.array([
    [0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
    [1 / 5, 0.0, 0.0, 0.0, 0.0, 0.0],
    [3 / 40, 9 / 40, 0.0, 0.0, 0.0, 0.0],
    [44 / 45, -56 / 15, 32 / 9, 0.0, 0.0, 0.0],
    [19372 / 6561, -25360 / 2187, 64448 / 6561, -212 / 729, 0.0, 0.0],
    [9017 / 3168, -355 / 33, 46732 / 5247, 49 / 176, -5103 / 18656, 0.0],
    [35 / 384, 0.0, 500 / 1113, 125 / 192, -2187 / 6784, 11 / 84],
])
B5 = np.array([35 / 384, 0.0, 500 / 1113, 125 / 192, -2187 / 6784, 11 / 84, 0.0])
B4 = np.array([5179 / 57600, 0.0, 7571 / 16695, 393 / 640, -92097 / 339200, 187 / 2100,
               1 / 40])


@njit(cache=True)
def _shell(par, cheb, temp):
    """(s_+, ds_+/dT, F) at T from the Chebyshev tables (rows 0, 1, 2 of ``cheb``)."""
    x = min(max(temp, par[10]), par[11])
    return (_clenshaw(cheb[0], par[10], par[11], x), _clenshaw(cheb[1], par[10], par[11], x),
            _clenshaw(cheb[2], par[10], par[11], x))


@njit(cache=True)
def radius(kind, t, y, heat, par, cheb):
    """The bead radius a for the state y at t."""
    if kind == 0:
        return max(y, 1.0) ** (1.0 / 3.0)
    temp, _ = temperature_rate(heat, t)
    sp, _, _ = _shell(par, cheb, temp)
    return ((1.0 + (sp - par[9]) * max(y, 0.0)) / sp) ** (1.0 / 3.0)


@njit(cache=True)
def rhs(kind, t, y, heat, par, cheb, tab):
    """dy/dt of stage ``kind`` (module doc); ``tab`` rows: branch T, branch V."""
    temp, rate = temperature_rate(heat, t)
    mob = mobility_factor(int(par[7]), temp, par[8])
    if kind == 0:
        v = max(y, 1.0 + 1e-12)
        a = v ** (1.0 / 3.0)
        chi0 = par[1] + par[2] * temp
        chi1 = par[3] + par[4] * temp
        phi = 1.0 - 1.0 / v
        stiff = 1.0 + 1.0 / (a * a) - par[0] * osmotic_dp(phi, chi0, chi1) / (a * a)
        diff = permeability(phi, int(par[5]), par[6]) * max(stiff, 1e-9) / a
        veq = np.interp(temp, tab[0], tab[1])
        return -mob * (v - veq) * LAG_MODES * diff / (a * a)
    sm = par[9]
    sp, dsp, front = _shell(par, cheb, temp)
    x = max(y, 0.0)
    jump = sp - sm
    rf = x ** (1.0 / 3.0)
    a = ((1.0 + jump * x) / sp) ** (1.0 / 3.0)
    fm = sm ** (1.0 / 3.0)
    edge = 1.0 / (a**4 * sp) - sp
    fa = 1.0 / a
    h = (2.0 * fa - fa**4 / (2.0 * sp)) - (2.0 * fm - fm**4 / (2.0 * sp))
    numer = front - edge - h
    integ = a * a / 2.0 - 1.5 * rf * rf + rf**3 / a
    core = sp * mob * permeability(1.0 - sp, int(par[5]), par[6]) * numer + dsp * rate * integ / 3.0
    if core > 0.0:
        core = 0.0
    return 3.0 * rf * a * core / (jump * max(a - rf, 1e-300))


@njit(cache=True)
def _stop(kind, t, y, heat, par, cheb, nuc):
    """>= 0 when the stage ends: the coexistence onset (0), the centre (1)."""
    if kind == 0:
        temp, _ = temperature_rate(heat, t)
        a = max(y, 1.0) ** (1.0 / 3.0)
        return temp - np.interp(a, nuc[0], nuc[1])
    return CENTRE - y


@njit(cache=True)
def _step(kind, t, y, h, heat, par, cheb, tab):
    """One Dormand-Prince step: (y5, error estimate)."""
    k = np.empty(7)
    for i in range(7):
        yi = y
        for j in range(i):
            yi += h * A[i, j] * k[j]
        k[i] = rhs(kind, t + C[i] * h, yi, heat, par, cheb, tab)
    y5 = y
    y4 = y
    for i in range(7):
        y5 += h * B5[i] * k[i]
        y4 += h * B4[i] * k[i]
    return y5, y5 - y4


@njit(cache=True)
def integrate(kind, t0, y0, t_end, breaks, targets, heat, par, cheb, tab, nuc, rtol, atol):
    """Integrate stage ``kind`` from (t0, y0) to t_end or its stop condition.

    Returns (times, radii) at the accepted steps, the crossing time of each target radius
    (nan: not reached; the last target also stops the run), the end time and state and a
    flag: 0 horizon, 1 stop condition, 2 last target."""
    ts = np.empty(MAX_STEPS + 2)
    rs = np.empty(MAX_STEPS + 2)
    hits = np.full(targets.size, np.nan)
    t, y = t0, y0
    ts[0], rs[0] = t, radius(kind, t, y, heat, par, cheb)
    n = 1
    h = min(1e-6, 1e-3 * max(t_end - t0, 1e-12))
    nxt = 0
    while nxt < targets.size and rs[0] <= targets[nxt]:
        hits[nxt] = t0
        nxt += 1
    if nxt == targets.size and targets.size > 0:
        return ts[:1], rs[:1], hits, t, y, 2
    if _stop(kind, t, y, heat, par, cheb, nuc) >= 0.0:
        return ts[:1], rs[:1], hits, t, y, 1
    for _ in range(MAX_STEPS):
        if t >= t_end:
            break
        bound = t_end
        for b in breaks:
            if b > t * (1.0 + 1e-15) + 1e-300:
                bound = min(bound, b)
                break
        hh = min(h, bound - t)
        y1, err = _step(kind, t, y, hh, heat, par, cheb, tab)
        sc = atol + rtol * max(abs(y), abs(y1))
        e = abs(err) / sc
        if not math.isfinite(y1) or e > 1.0:
            h = hh * max(0.2, 0.9 * e ** -0.2) if math.isfinite(e) else hh * 0.2
            if h < 1e-300:
                break
            continue
        # the step is accepted: the stop condition and the targets inside it
        g1 = _stop(kind, t + hh, y1, heat, par, cheb, nuc)
        a1 = radius(kind, t + hh, y1, heat, par, cheb)
        s_end = hh
        flag = 0
        if g1 >= 0.0:
            lo, hi = 0.0, hh
            for _ in range(80):
                mid = 0.5 * (lo + hi)
                ym, _ = _step(kind, t, y, mid, heat, par, cheb, tab)
                if _stop(kind, t + mid, ym, heat, par, cheb, nuc) >= 0.0:
                    hi = mid
                else:
                    lo = mid
            s_end = hi
            flag = 1
        while nxt < targets.size and a1 <= targets[nxt]:
            lo, hi = 0.0, hh
            for _ in range(80):
                mid = 0.5 * (lo + hi)
                ym, _ = _step(kind, t, y, mid, heat, par, cheb, tab)
                if radius(kind, t + mid, ym, heat, par, cheb) <= targets[nxt]:
                    hi = mid
                else:
                    lo = mid
            if hi > s_end:
                break
            hits[nxt] = t + hi
            nxt += 1
            if nxt == targets.size:
                s_end = hi
                flag = 2
        if s_end < hh:
            y1, _ = _step(kind, t, y, s_end, heat, par, cheb, tab)
        t += s_end
        y = y1
        ts[n], rs[n] = t, radius(kind, t, y, heat, par, cheb)
        n += 1
        if flag:
            return ts[:n], rs[:n], hits, t, y, flag
        h = hh * min(5.0, 0.9 * max(e, 1e-10) ** -0.2)
    return ts[:n], rs[:n], hits, t, y, 0


@njit(cache=True)
def _w_parts(omega, chi0, chi1, n, lt):
    """(W, dW/dn, d^2W/dn^2) at (n, lt, lt) (as solver.thermo's normal_* functions)."""
    jac = n * lt * lt
    x = 1.0 / jac
    w = 0.5 * (n * n + 2.0 * lt * lt - 3.0 - 2.0 * math.log(jac)) + omega * (
        (jac - 1.0) * math.log1p(-x) + (chi0 + chi1 * x) * (1.0 - x))
    phi = 1.0 - x
    s = 1.0 - phi
    p = -math.log1p(-s) - s - (chi0 - chi1) * s * s - 2.0 * chi1 * s * s * s
    stress = n - 1.0 / n - omega * p * lt * lt
    stiff = 1.0 + 1.0 / (n * n) - omega * osmotic_dp(phi, chi0, chi1) * lt**4 / (jac * jac)
    return w, stress, stiff


@njit(cache=True)
def level_values(par, temps, lt, phi0, n1, n2, sharp):
    """s_+ = 1 - phi_+ (P(phi_+) = 0) and the front condition F at each temperature, by
    Newton continuation from phi0 and the Maxwell pair (n1, n2) at lt (module slow)."""
    omega = par[0]
    sm = lt**-3.0
    sp = np.empty(temps.size)
    fr = np.empty(temps.size)
    phi = phi0
    ok = True
    for i in range(temps.size):
        temp = temps[i]
        chi0 = par[1] + par[2] * temp
        chi1 = par[3] + par[4] * temp
        for _ in range(60):
            s = 1.0 - phi
            p = -math.log1p(-s) - s - (chi0 - chi1) * s * s - 2.0 * chi1 * s * s * s
            step = p / osmotic_dp(phi, chi0, chi1)
            phi -= step
            if abs(step) <= 1e-15:
                break
        sp[i] = 1.0 - phi
        if sharp:
            conv = False
            for _ in range(60):
                w1, s1, k1 = _w_parts(omega, chi0, chi1, n1, lt)
                w2, s2, k2 = _w_parts(omega, chi0, chi1, n2, lt)
                r1 = s1 - s2
                r2 = (w2 - w1) - s1 * (n2 - n1)
                j11, j12 = k1, -k2
                j21, j22 = -k1 * (n2 - n1), s2 - s1
                det = j11 * j22 - j12 * j21
                d1 = (r1 * j22 - j12 * r2) / det
                d2 = (j11 * r2 - j21 * r1) / det
                n1 -= d1
                n2 -= d2
                if abs(d1) <= 1e-13 * n1 and abs(d2) <= 1e-13 * n2:
                    conv = True
                    break
            ok = ok and conv and n2 > n1 * (1.0 + 1e-6)
            phi_shell = 1.0 - 1.0 / (n1 * lt * lt)
            s = 1.0 - phi_shell
            fr[i] = omega * (-math.log1p(-s) - s - (chi0 - chi1) * s * s - 2.0 * chi1 * s**3)
        else:
            s_p = sp[i]
            s = sm
            p_m = -math.log1p(-s) - s - (chi0 - chi1) * s * s - 2.0 * chi1 * s**3
            fr[i] = sm ** (4.0 / 3.0) * (1.0 / s_p - 1.0 / sm) + (sm - s_p) + omega * p_m
    return sp, fr, ok
