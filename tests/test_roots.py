"""solver.roots: Brent's root and bounded minimum are scipy's, iterate for iterate.

They stand in for ``scipy.optimize.brentq`` and ``minimize_scalar(method="bounded")`` on
the equilibria's path (a CLI dose does not import scipy.optimize); the answers must be
scipy's to the last bit, on the solver's own functions and on hard ones.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.optimize import brentq as scipy_brentq
from scipy.optimize import minimize_scalar

from solver import equilibrium
from solver.errors import SolverError
from solver.gel import PRESETS
from solver.phase import coexistence_gap, shrunken_level
from solver.roots import bounded_minimum, brentq
from solver.thermo import osmotic_p

ROOTS = [  # (f, a, b): smooth, flat, steep, a double root's neighbour, a pole's neighbour
    (lambda x: x**3 - 2.0 * x - 5.0, 2.0, 3.0),
    (lambda x: math.cos(x) - x, 0.0, 1.0),
    (lambda x: math.exp(x) - 1e6, 0.0, 20.0),
    (lambda x: (x - 1.0) ** 3, 0.0, 3.0),
    (lambda x: math.tanh(50.0 * (x - 0.3)), -1.0, 1.0),
    (lambda x: 1.0 / (x - 0.5) + 3.0, 0.0, 0.45),
    (lambda x: x**9, -1.0, 0.7),
    (lambda x: math.log(x) + 40.0, 1e-30, 1.0),
]


@pytest.mark.parametrize("k", range(len(ROOTS)))
@pytest.mark.parametrize("tol", [(2e-12, 8.881784197001252e-16, 100), (1e-15, 1e-15, 200),
                                 (1e-14, 8.881784197001252e-16, 100), (1e-3, 1e-6, 100)])
def test_brentq_is_scipys_to_the_last_bit(k: int, tol: tuple[float, float, int]) -> None:
    f, a, b = ROOTS[k]
    xtol, rtol, maxiter = tol
    try:
        theirs = scipy_brentq(f, a, b, xtol=xtol, rtol=rtol, maxiter=maxiter)
    except RuntimeError:  # no convergence in maxiter: the same here
        with pytest.raises(SolverError, match="no convergence"):
            brentq(f, a, b, xtol=xtol, rtol=rtol, maxiter=maxiter)
        return
    mine = brentq(f, a, b, xtol=xtol, rtol=rtol, maxiter=maxiter)
    assert mine == theirs, (mine, theirs)


def test_brentq_on_random_cubics() -> None:
    rng = np.random.default_rng(7)
    for _ in range(300):
        c = rng.normal(size=4)
        f = np.poly1d(c)
        grid = np.linspace(-5.0, 5.0, 41)
        v = f(grid)
        for i in np.nonzero(v[:-1] * v[1:] < 0)[0]:
            a, b = float(grid[i]), float(grid[i + 1])
            g = lambda x, f=f: float(f(x))  # noqa: E731
            assert brentq(g, a, b, xtol=1e-15, rtol=1e-15, maxiter=200) == scipy_brentq(
                g, a, b, xtol=1e-15, rtol=1e-15, maxiter=200)


def test_brentq_refuses_what_scipy_refuses() -> None:
    with pytest.raises(SolverError, match="different signs"):
        brentq(lambda x: x * x + 1.0, -1.0, 1.0)
    with pytest.raises(SolverError, match="no convergence"):
        brentq(lambda x: (x - 1.0) ** 3, 0.0, 3.0, maxiter=5)
    with pytest.raises(ValueError, match="rtol"):
        brentq(lambda x: x, -1.0, 1.0, rtol=1e-17)
    assert brentq(lambda x: x, 0.0, 1.0) == 0.0  # a root at the bracket's end


MINIMA = [
    (lambda x: (x - 0.3) ** 2, 0.0, 1.0),
    (lambda x: math.cos(x), 2.0, 4.0),
    (lambda x: x**4 - 3.0 * x**3 + 2.0, 0.0, 5.0),
    (lambda x: abs(x - 0.123), -1.0, 1.0),
    (lambda x: x, 0.0, 1.0),  # the minimum at the bound
    (lambda x: math.exp(-x) * math.sin(5.0 * x), 0.0, 1.5),
]


@pytest.mark.parametrize("k", range(len(MINIMA)))
@pytest.mark.parametrize("xatol", [1e-12, 1e-5])
def test_bounded_minimum_is_scipys_to_the_last_bit(k: int, xatol: float) -> None:
    f, lo, hi = MINIMA[k]
    x, fx, ok = bounded_minimum(f, lo, hi, xatol=xatol)
    res = minimize_scalar(f, bounds=(lo, hi), method="bounded", options={"xatol": xatol})
    assert (x, fx, ok) == (float(res.x), float(res.fun), bool(res.success))


def test_the_solvers_answers_are_scipys() -> None:
    """Every equilibrium, the shrunken level and the coexistence gap of both presets at
    several temperatures, as scipy.optimize found them (its functions patched in)."""
    import sys

    import solver.phase as phase_module

    eq_module = sys.modules["solver.equilibrium"]  # solver.equilibrium is the function

    def answers() -> list[float]:
        eq_module._equilibria.cache_clear()  # memoised: computed afresh each time
        out: list[float] = []
        for name in ("ANB", "HHT"):
            gel = PRESETS[name]
            for temp in (300.0, 304.0, 306.0, 308.0, 312.0):
                out += [e.stretch for e in eq_module.equilibria(gel, temp)]
                if temp >= 308.0:  # P(phi) = 0 has a root (the collapsed side)
                    out.append(shrunken_level(gel, temp))
                out += list(coexistence_gap(gel, temp, 1.5))
        return out

    ours = answers()

    def scipy_min(f, lo, hi, xatol):
        res = minimize_scalar(f, bounds=(lo, hi), method="bounded", options={"xatol": xatol})
        return float(res.x), float(res.fun), bool(res.success)

    saved = (eq_module.brentq, phase_module.brentq, phase_module.bounded_minimum)
    try:
        eq_module.brentq = phase_module.brentq = scipy_brentq
        phase_module.bounded_minimum = scipy_min
        theirs = answers()
    finally:
        eq_module.brentq, phase_module.brentq, phase_module.bounded_minimum = saved
    assert ours == theirs
    eq_module._equilibria.cache_clear()
    assert len(ours) > 20 and callable(equilibrium)
    phi = shrunken_level(PRESETS["ANB"], 308.0)
    assert abs(osmotic_p(phi, PRESETS["ANB"].chi0(308.0), PRESETS["ANB"].chi1(308.0))) < 1e-9
