"""Brent's bracketed root and bounded minimum, as scipy computes them, without its import.

The equilibria (eq. EqlEqn), the shrunken level P(phi) = 0 and the coexistence gap need a
bracketed root and a bounded scalar minimum a handful of times per answer.  Importing
``scipy.optimize`` for them (it imports scipy.linalg, scipy.sparse, linprog, ...) cost half
of a front-model ``thermogel dose``'s CPU: 1.1 of 2.2 s on the machine of issue 23
(docs/speed.md sec. 7.1).  These are line-for-line ports of scipy's own routines, the same
arithmetic in the same order, so every iterate and every answer is scipy's to the last bit
(``tests/test_roots.py`` checks them against ``scipy.optimize`` on the solver's functions
and on random ones):

* :func:`brentq`: Brent (1973), "Algorithms for Minimization without Derivatives", ch. 4,
  as scipy/optimize/Zeros/brentq.c (``scipy.optimize.brentq``);
* :func:`bounded_minimum`: Brent's golden-section and parabolic search, ch. 5, as
  ``scipy.optimize._optimize._minimize_scalar_bounded`` (``minimize_scalar(...,
  method="bounded")``).

scipy is BSD-licensed (Copyright (c) 2001-2002 Enthought, Inc., 2003-2024 SciPy
Developers); the routines' structure and names follow it.
"""

from __future__ import annotations

import math
from collections.abc import Callable

from .errors import SolverError

_RTOL_MIN = 4.0 * 2.220446049250313e-16  # scipy.optimize's smallest rtol (4 eps)


def brentq(f: Callable[[float], float], a: float, b: float, *, xtol: float = 2e-12,
           rtol: float = 8.881784197001252e-16, maxiter: int = 100) -> float:
    """A root of ``f`` in [a, b], f(a) f(b) <= 0, to |x - x*| <= xtol + rtol |x*|."""
    if xtol <= 0.0 or rtol < _RTOL_MIN or maxiter < 0:
        raise ValueError(f"brentq: xtol {xtol} > 0, rtol {rtol} >= 4 eps, maxiter {maxiter} "
                         ">= 0")
    xpre, xcur = float(a), float(b)
    xblk = fblk = spre = scur = 0.0
    fpre, fcur = float(f(xpre)), float(f(xcur))
    if math.isnan(fpre) or math.isnan(fcur):
        raise SolverError("brentq: the function is NaN at a bracket's end",
                          {"a": xpre, "b": xcur})
    if fpre == 0.0:
        return xpre
    if fcur == 0.0:
        return xcur
    if math.copysign(1.0, fpre) == math.copysign(1.0, fcur):
        raise SolverError("brentq: f(a) and f(b) must have different signs",
                          {"a": xpre, "b": xcur, "f(a)": fpre, "f(b)": fcur})
    for _ in range(maxiter):
        if fpre != 0.0 and fcur != 0.0 and (
                math.copysign(1.0, fpre) != math.copysign(1.0, fcur)):
            xblk, fblk = xpre, fpre
            spre = scur = xcur - xpre
        if abs(fblk) < abs(fcur):
            xpre, xcur, xblk = xcur, xblk, xcur
            fpre, fcur, fblk = fcur, fblk, fcur
        delta = (xtol + rtol * abs(xcur)) / 2.0
        sbis = (xblk - xcur) / 2.0
        if fcur == 0.0 or abs(sbis) < delta:
            return xcur
        if abs(spre) > delta and abs(fcur) < abs(fpre):
            if xpre == xblk:  # interpolate
                stry = _div(-fcur * (xcur - xpre), fcur - fpre)
            else:  # extrapolate
                dpre = _div(fpre - fcur, xpre - xcur)
                dblk = _div(fblk - fcur, xblk - xcur)
                stry = _div(-fcur * (fblk * dblk - fpre * dpre), dblk * dpre * (fblk - fpre))
            if 2.0 * abs(stry) < min(abs(spre), 3.0 * abs(sbis) - delta):
                spre, scur = scur, stry  # good short step
            else:
                spre = scur = sbis  # bisect
        else:
            spre = scur = sbis  # bisect
        xpre, fpre = xcur, fcur
        if abs(scur) > delta:
            xcur += scur
        else:
            xcur += delta if sbis > 0 else -delta
        fcur = float(f(xcur))
        if math.isnan(fcur):
            raise SolverError("brentq: the function is NaN inside the bracket", {"x": xcur})
    raise SolverError(f"brentq: no convergence in {maxiter} iterations", {"x": xcur})


def bounded_minimum(f: Callable[[float], float], lo: float, hi: float, *,
                    xatol: float = 1e-5, maxiter: int = 500) -> tuple[float, float, bool]:
    """(x, f(x), converged): a local minimum of ``f`` on [lo, hi] to ``xatol``."""
    if not (math.isfinite(lo) and math.isfinite(hi)) or lo > hi:
        raise ValueError(f"bounded_minimum: finite bounds lo <= hi, got ({lo}, {hi})")
    sqrt_eps = math.sqrt(2.2e-16)
    golden_mean = 0.5 * (3.0 - math.sqrt(5.0))
    a, b = float(lo), float(hi)
    fulc = a + golden_mean * (b - a)
    nfc = xf = fulc
    rat = e = 0.0
    fx = float(f(xf))
    num = 1
    fu = math.inf
    ffulc = fnfc = fx
    xm = 0.5 * (a + b)
    tol1 = sqrt_eps * abs(xf) + xatol / 3.0
    tol2 = 2.0 * tol1
    converged = True
    while abs(xf - xm) > (tol2 - 0.5 * (b - a)):
        golden = True
        if abs(e) > tol1:  # a parabolic fit
            golden = False
            r = (xf - nfc) * (fx - ffulc)
            q = (xf - fulc) * (fx - fnfc)
            p = (xf - fulc) * q - (xf - nfc) * r
            q = 2.0 * (q - r)
            if q > 0.0:
                p = -p
            q = abs(q)
            r = e
            e = rat
            if abs(p) < abs(0.5 * q * r) and p > q * (a - xf) and p < q * (b - xf):
                rat = (p + 0.0) / q
                x = xf + rat
                if (x - a) < tol2 or (b - x) < tol2:
                    rat = tol1 * (_sign(xm - xf) + ((xm - xf) == 0))
            else:
                golden = True
        if golden:  # a golden-section step
            e = a - xf if xf >= xm else b - xf
            rat = golden_mean * e
        x = xf + (_sign(rat) + (rat == 0)) * max(abs(rat), tol1)
        fu = float(f(x))
        num += 1
        if fu <= fx:
            if x >= xf:
                a = xf
            else:
                b = xf
            fulc, ffulc = nfc, fnfc
            nfc, fnfc = xf, fx
            xf, fx = x, fu
        else:
            if x < xf:
                a = x
            else:
                b = x
            if fu <= fnfc or nfc == xf:
                fulc, ffulc = nfc, fnfc
                nfc, fnfc = x, fu
            elif fu <= ffulc or fulc == xf or fulc == nfc:
                fulc, ffulc = x, fu
        xm = 0.5 * (a + b)
        tol1 = sqrt_eps * abs(xf) + xatol / 3.0
        tol2 = 2.0 * tol1
        if num >= maxiter:
            converged = False
            break
    if math.isnan(xf) or math.isnan(fx) or math.isnan(fu):
        converged = False
    return xf, fx, converged


def _div(a: float, b: float) -> float:
    """a / b as C's doubles divide (IEEE 754: +-inf or NaN for b = 0, no exception)."""
    if b != 0.0:
        return a / b
    if a == 0.0 or math.isnan(a):
        return math.nan
    return math.copysign(math.inf, a) * math.copysign(1.0, b)


def _sign(v: float) -> float:
    """numpy's sign of a float (0 at 0; NaN stays NaN)."""
    return (v > 0.0) - (v < 0.0) if not math.isnan(v) else v
