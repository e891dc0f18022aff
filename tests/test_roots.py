"""solver.roots: the bracketed root and minimum the front model uses in place of
scipy.optimize (issue 23), against scipy's brentq and bounded minimize_scalar."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.optimize import brentq, minimize_scalar

from solver.gel import preset
from solver.roots import bracketed_minimum, bracketed_root, bracketed_roots

CASES = [
    (lambda x: math.cos(x) - x, 0.0, 1.0),
    (lambda x: x**3 - 2.0, 0.0, 3.0),
    (lambda x: math.exp(x) - 10.0, 0.0, 5.0),
    (lambda x: (x - 1.5) ** 3 + 1e-3 * (x - 1.5), 0.0, 4.0),  # flat at the root
    (lambda x: math.tanh(50.0 * (x - 0.7)), 0.0, 1.0),  # a step
    (lambda x: 1e-300 * (x - 0.3), 0.0, 1.0),  # tiny values
]


@pytest.mark.parametrize("f, lo, hi", CASES)
def test_root_matches_brentq(f, lo, hi) -> None:
    want = brentq(f, lo, hi, xtol=1e-15, rtol=4 * np.finfo(float).eps)
    got = bracketed_root(f, lo, hi)
    assert abs(got - want) <= 2e-15 + 1e-14 * abs(want)
    assert bracketed_roots(f, np.array([lo]), np.array([hi]))[0] == got


def test_root_ends_and_bad_brackets() -> None:
    assert bracketed_root(lambda x: x - 1.0, 1.0, 2.0) == 1.0
    assert bracketed_root(lambda x: x - 2.0, 1.0, 2.0) == 2.0
    with pytest.raises(ValueError):
        bracketed_root(lambda x: x * x + 1.0, -1.0, 1.0)


@pytest.mark.parametrize("f, lo, hi", [
    (lambda x: (x - 0.3) ** 2, 0.0, 1.0),
    (lambda x: math.cos(3.0 * x), 0.5, 1.5),
    (lambda x: x**4 - x, 0.0, 2.0),
])
def test_minimum_matches_minimize_scalar(f, lo, hi) -> None:
    res = minimize_scalar(f, bounds=(lo, hi), method="bounded", options={"xatol": 1e-12})
    fun, x = bracketed_minimum(f, lo, hi)
    assert fun <= res.fun + 1e-15
    assert abs(x - res.x) < 1e-6


def test_equilibria_as_with_brentq() -> None:
    """The swollen and shrunken equilibria of both presets: each root of eq. EqlEqn to
    brentq's tolerance (the residual vanishes to rounding there)."""
    from solver.equilibrium import equilibria, residual

    for gel in ("ANB", "HHT"):
        g = preset(gel)
        for t in (290.0, 302.0, 305.5, 308.0, 320.0):
            for e in equilibria(g, t):
                lam = e.stretch
                want = brentq(lambda v, g=g, t=t: residual(g, t, v), lam * (1 - 1e-9),
                              lam * (1 + 1e-9),
                              xtol=1e-15, rtol=4 * np.finfo(float).eps)
                assert abs(lam - want) <= 4e-15 * lam
