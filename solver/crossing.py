"""Crossing times of sampled curves: first fall below a level (NaN when never: a numeric
primitive; the run record turns it into None), the root of the cubic
Hermite interpolant between two accepted steps, and the root with a^3 linear between outputs
(used by the one run record, solver.full.result.FullResult)."""

from __future__ import annotations

import math

import numpy as np


def first_fall(t: np.ndarray, values: np.ndarray, level: float) -> float:
    """First time ``values`` (sampled at ``t``) falls to ``level`` (linear in between), or
    NaN if it never does."""
    below = np.nonzero(values <= level)[0]
    if below.size == 0:
        return math.nan
    j = int(below[0])
    if j == 0 or values[j - 1] == values[j]:
        return float(t[j])
    return float(t[j - 1] + (values[j - 1] - level) / (values[j - 1] - values[j])
                 * (t[j] - t[j - 1]))


def hermite_root(t0: float, t1: float, a0: float, a1: float, d0: float, d1: float,
                 target: float) -> float:
    """Crossing time of the cubic Hermite a(t) through ``target`` on [t0, t1] (bisection)."""
    h = t1 - t0

    def a(s: float) -> float:
        return ((1 + 2 * s) * (1 - s) ** 2 * a0 + s * (1 - s) ** 2 * h * d0
                + s * s * (3 - 2 * s) * a1 + s * s * (s - 1) * h * d1)

    lo, hi = 0.0, 1.0
    sign_lo = a(lo) - target
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        v = a(mid) - target
        if (v > 0) == (sign_lo > 0) and v != 0.0:
            lo, sign_lo = mid, v
        else:
            hi = mid
    return t0 + 0.5 * (lo + hi) * h


def linear_cube_root(t0: float, a0: float, t1: float, a1: float, target: float) -> float:
    """Crossing time of ``target`` on [t0, t1] with a^3 linear in t (the expelled volume of
    eq. FluidVolExpelled linear between two samples)."""
    y0, y1, y = a0**3, a1**3, target**3
    return t1 if y0 == y1 else t0 + (y0 - y) / (y0 - y1) * (t1 - t0)
