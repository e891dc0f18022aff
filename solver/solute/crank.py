"""Analytic release from a uniform sphere (Crank, The Mathematics of Diffusion, 2nd ed.,
sec. 6.3): the tests' reference for the solute transport.

Perfect sink (eq. 6.20): M_t / M_inf = 1 - (6 / pi^2) sum_n exp(-D n^2 pi^2 t / a^2) / n^2,
and for small times the equivalent (eq. 6.21)
M_t / M_inf = 6 (Dt/a^2)^(1/2) (pi^(-1/2) + 2 sum_n ierfc(n a / sqrt(Dt))) - 3 Dt / a^2.
Well-stirred finite volume (eq. 6.30): with alpha = V / (K * 4 pi a^3 / 3),
M_t / M_inf = 1 - sum_n 6 alpha (1 + alpha) exp(-D q_n^2 t / a^2) / (9 + 9 alpha + q_n^2 alpha^2),
tan q_n = 3 q_n / (3 + alpha q_n^2); M_inf is the fraction alpha / (1 + alpha) of the load.
"""

from __future__ import annotations

import math

import numpy as np


def _ierfc(x: np.ndarray) -> np.ndarray:
    from scipy.special import erfc  # here: importing the package needs no scipy.special

    return np.exp(-x * x) / math.sqrt(math.pi) - x * erfc(x)


def crank_sphere(t: np.ndarray | float, diffusivity: float, radius: float,
                 terms: int = 400) -> np.ndarray:
    """Released fraction of a uniformly loaded sphere into a perfect sink (Crank 6.20/6.21)."""
    tau = np.maximum(np.asarray(t, dtype=float), 0.0) * diffusivity / radius**2
    out = np.empty_like(tau)
    short = tau < 0.05
    ts = tau[short]
    if ts.size:
        root = np.sqrt(ts)
        acc = np.full_like(ts, 1.0 / math.sqrt(math.pi))
        with np.errstate(divide="ignore"):
            for n in range(1, 4):
                acc += 2.0 * np.where(root > 0, _ierfc(n / np.where(root > 0, root, 1.0)), 0.0)
        out[short] = 6.0 * root * acc - 3.0 * ts
    tl = tau[~short]
    if tl.size:
        n = np.arange(1, terms + 1)[:, None]
        out[~short] = 1.0 - 6.0 / math.pi**2 * np.sum(
            np.exp(-(n * math.pi) ** 2 * tl[None, :]) / n**2, axis=0)
    return out


def crank_sphere_finite(t: np.ndarray | float, diffusivity: float, radius: float,
                        alpha: float, terms: int = 200) -> np.ndarray:
    """Released fraction of the load into a well-stirred volume (Crank 6.30)."""
    def g(x: float) -> float:
        return (3.0 + alpha * x * x) * math.sin(x) - 3.0 * x * math.cos(x)

    from scipy.optimize import brentq  # here: importing the package needs no scipy.optimize

    # one root in each (k pi, (k + 1) pi), k >= 1: g changes sign between the ends
    q = np.array([brentq(g, k * math.pi, (k + 1) * math.pi, xtol=1e-14)
                  for k in range(1, terms + 1)])
    tau = np.maximum(np.asarray(t, dtype=float), 0.0) * diffusivity / radius**2
    coef = 6.0 * alpha * (1.0 + alpha) / (9.0 + 9.0 * alpha + q**2 * alpha**2)
    frac = 1.0 - np.sum(coef[:, None] * np.exp(-(q[:, None] ** 2) * np.atleast_1d(tau)[None, :]),
                        axis=0)
    return frac * alpha / (1.0 + alpha)
