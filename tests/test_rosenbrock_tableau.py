"""RODASP's coefficients, checked directly: the Rosenbrock order conditions (Hairer & Wanner
1996, Table IV.7.1) for the method (order 4) and its embedded solution (order 3), and the
observed order of the transformed form the integrator uses, on a smooth nonlinear ODE."""

from __future__ import annotations

import numpy as np
import pytest

from solver.full import rosenbrock as rb

G = rb.GAMMA
ALPHA, BETA = rb._ALPHA, rb._BETA  # beta_ij = alpha_ij + gamma_ij (strictly lower part)
B = np.append(BETA[5, :5], G)                     # stiffly accurate: b_i = beta_6i
BHAT = np.append(np.append(BETA[4, :4], G), 0.0)  # embedded: b^_i = beta_5i
ALPHA_I = ALPHA.sum(axis=1)
BETA_I = BETA.sum(axis=1)  # beta'_i = sum_{j<i} beta_ij


def _conditions(b: np.ndarray) -> dict[str, tuple[float, float]]:
    """(value, target) of each order condition up to order 4 for weights b."""
    return {
        "1": (b.sum(), 1.0),
        "2": (b @ BETA_I, 0.5 - G),
        "3a": (b @ ALPHA_I**2, 1 / 3),
        "3b": (b @ BETA @ BETA_I, 1 / 6 - G + G**2),
        "4a": (b @ ALPHA_I**3, 0.25),
        "4b": (b @ (ALPHA_I[:, None] * ALPHA) @ BETA_I, 1 / 8 - G / 3),
        "4c": (b @ BETA @ ALPHA_I**2, 1 / 12 - G / 3),
        "4d": (b @ BETA @ BETA @ BETA_I, 1 / 24 - G / 2 + 1.5 * G**2 - G**3),
    }


@pytest.mark.parametrize("name", ["1", "2", "3a", "3b", "4a", "4b", "4c", "4d"])
def test_method_satisfies_order_four_conditions(name: str) -> None:
    value, target = _conditions(B)[name]
    assert value == pytest.approx(target, abs=1e-12)


@pytest.mark.parametrize("name", ["1", "2", "3a", "3b"])
def test_embedded_satisfies_order_three_conditions(name: str) -> None:
    value, target = _conditions(BHAT)[name]
    assert value == pytest.approx(target, abs=1e-12)


def test_embedded_is_not_order_four() -> None:
    """The error estimate is only meaningful if the embedded solution is a lower order."""
    misses = [abs(v - t) for k, (v, t) in _conditions(BHAT).items() if k.startswith("4")]
    assert max(misses) > 1e-4


def _f(y: np.ndarray) -> np.ndarray:
    """A smooth, mildly stiff autonomous test problem (Van der Pol, mu = 2)."""
    return np.array([y[1], 2.0 * (1 - y[0] ** 2) * y[1] - y[0]])


def _jac(y: np.ndarray) -> np.ndarray:
    return np.array([[0.0, 1.0], [-4.0 * y[0] * y[1] - 1.0, 2.0 * (1 - y[0] ** 2)]])


def _integrate(h: float, t_end: float, embedded: bool) -> np.ndarray:
    """Fixed-step transformed Rosenbrock as in rodas_try, in numpy."""
    a, c, m, e = rb.A_COEF, rb.C_COEF, rb.M_COEF, rb.E_COEF
    w = m - e if embedded else m
    y = np.array([2.0, 0.0])
    for _ in range(round(t_end / h)):
        lhs = np.eye(2) / (h * G) - _jac(y)
        u = []
        for s in range(w.size):
            ys = y + sum(a[s, j] * u[j] for j in range(s))
            rhs = _f(ys) + sum(c[s, j] / h * u[j] for j in range(s))
            u.append(np.linalg.solve(lhs, rhs))
        y = y + sum(w[s] * u[s] for s in range(w.size))
    return y


@pytest.mark.parametrize(("embedded", "order"), [(False, 4), (True, 3)])
def test_observed_order_of_transformed_form(embedded: bool, order: int) -> None:
    """Errors at h, h/2 against h/16: the observed order is the design order (+-0.3)."""
    ref = _integrate(0.5 / 64, 1.0, embedded)
    e1 = np.linalg.norm(_integrate(0.5 / 4, 1.0, embedded) - ref)
    e2 = np.linalg.norm(_integrate(0.5 / 8, 1.0, embedded) - ref)
    assert np.log2(e1 / e2) == pytest.approx(order, abs=0.3)
