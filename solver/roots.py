"""Roots and minima of a scalar function in a bracket, without scipy.optimize.

The front model's inputs (the equilibria of eq. EqlEqn, the shrunken level P(phi) = 0, the
coexistence test of eq. Coexistence) need a few bracketed roots and one bounded minimum per
temperature; importing scipy.optimize for brentq and minimize_scalar cost 0.3-0.7 s of CPU
of every front-model CLI call (issue 23).  The root is the Illinois variant of regula falsi
(superlinear), safeguarded by bisection whenever the bracket did not halve in two steps and
stopped by brentq's criterion (|error| <= xtol + 4 eps |x|); the minimum a golden-section
search.  Both are checked against scipy in tests/test_roots.py.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

EPS = float(np.finfo(float).eps)


def bracketed_root(f: Callable[[float], float], a: float, b: float, xtol: float = 1e-15,
                   max_iter: int = 400) -> float:
    """A root of ``f`` in [a, b], where f(a) f(b) <= 0 (ValueError otherwise)."""
    a, b = float(a), float(b)
    fa, fb = float(f(a)), float(f(b))
    if fa == 0.0:
        return a
    if fb == 0.0:
        return b
    if fa * fb > 0.0 or not (math.isfinite(fa) and math.isfinite(fb)):
        raise ValueError("bracketed_root: f has the same sign at both ends of the bracket")
    kept = 0  # the end kept by the last step: -1 a, +1 b
    w1 = w2 = abs(b - a)  # the bracket's width one and two steps ago
    for _ in range(max_iter):
        width = abs(b - a)
        if width <= 2.0 * (xtol + 4.0 * EPS * max(abs(a), abs(b))):
            break
        x = b - fb * (b - a) / (fb - fa) if fb != fa else math.nan
        if not (min(a, b) < x < max(a, b)) or width > 0.5 * w2:
            x = 0.5 * (a + b)  # bisect: regula falsi left the bracket or stalls
        w2, w1 = w1, width
        fx = float(f(x))
        if fx == 0.0:
            return x
        if (fx > 0.0) == (fb > 0.0):  # the root is in [a, x]
            if kept == -1:
                fa *= 0.5  # Illinois: a kept twice in a row
            b, fb, kept = x, fx, -1
        else:
            if kept == 1:
                fb *= 0.5
            a, fa, kept = x, fx, 1
    return 0.5 * (a + b)


def bracketed_roots(f: Callable[[float], float], lo: np.ndarray, hi: np.ndarray,
                    xtol: float = 1e-15) -> np.ndarray:
    """:func:`bracketed_root` in each bracket [lo_i, hi_i]."""
    return np.array([bracketed_root(f, a, b, xtol) for a, b in zip(np.ravel(lo), np.ravel(hi),
                                                                  strict=True)])


def bracketed_minimum(f: Callable[[float], float], a: float, b: float,
                      xatol: float = 1e-12) -> tuple[float, float]:
    """(f(x), x) at a local minimum of ``f`` in [a, b] by golden-section search to
    ``xatol`` (the bounded minimisation scipy's minimize_scalar(method='bounded') does,
    without its parabolic steps)."""
    inv = (math.sqrt(5.0) - 1.0) / 2.0
    a, b = float(a), float(b)
    c, d = b - inv * (b - a), a + inv * (b - a)
    fc, fd = float(f(c)), float(f(d))
    while abs(b - a) > 2.0 * xatol:
        if fc <= fd:
            b, d, fd = d, c, fc
            c = b - inv * (b - a)
            fc = float(f(c))
        else:
            a, c, fc = c, d, fd
            d = a + inv * (b - a)
            fd = float(f(d))
    return (fc, c) if fc <= fd else (fd, d)
