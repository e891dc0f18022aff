"""The coexisting pair at a front of given tangential stretch (sharp-interface limit).

With an interfacial energy (ell^2/2)|grad_X J|^2 and ell -> 0, the two sides of a front are
in local equilibrium: the normal stretches n_- (shrunken) and n_+ (swollen) at the common
tangential stretch lambda_t take the common tangent of w(n) = W(n, lambda_t; T),

    dW/dn(n_-) = dW/dn(n_+) = (W(n_+) - W(n_-)) / (n_+ - n_-),

eq. Coexistence written at any lambda_t (docs/interfacial.md, sec. 5).  Found from the lower
convex hull of w on a log grid, then polished by Newton's method.
"""

from __future__ import annotations

import numpy as np

from ..errors import NotApplicableError
from ..gel import Gel
from ..jit import kernel
from ..thermo import normal_energy, normal_stiffness, normal_stress

J_MAX = 400.0  # largest volume ratio searched for the swollen side
GRID = 4001
NEWTON_STEPS = 50


@kernel
def _lower_hull(x: np.ndarray, y: np.ndarray) -> np.ndarray:  # pragma: no cover - numba
    """Indices of the lower convex hull of the points (x, y), x increasing (monotone chain;
    compiled: it runs once per front trajectory step, on 4001 points)."""
    hull = np.empty(x.size, dtype=np.int64)
    m = 0
    for i in range(x.size):
        while m >= 2:
            i0, i1 = hull[m - 2], hull[m - 1]
            if (x[i1] - x[i0]) * (y[i] - y[i0]) - (y[i1] - y[i0]) * (x[i] - x[i0]) <= 0.0:
                m -= 1
            else:
                break
        hull[m] = i
        m += 1
    return hull[:m].copy()


def maxwell_pair(gel: Gel, temperature: float, lambda_t: float) -> tuple[float, float]:
    """(n_-, n_+): the shrunken and swollen normal stretches that coexist across a front with
    tangential stretch ``lambda_t`` at ``temperature`` (module doc).

    NotApplicableError when w(n) is convex (no coexistence at this lambda_t).
    """
    lt = float(lambda_t)
    lo = lt**-2.0
    n = lo * (1.0 + np.geomspace(1e-9, J_MAX, GRID))
    w = normal_energy(gel, temperature, n, lt)
    hull = _lower_hull(n, w)
    gaps = np.diff(n[hull])
    k = int(np.argmax(gaps / n[hull[:-1]]))
    i, j = hull[k], hull[k + 1]
    if j - i < 3:
        raise NotApplicableError(
            f"no coexisting pair at lambda_t={lt:.6g}, T={temperature:g} K: W is convex in "
            "the normal stretch")
    x = np.array([n[i], n[j]])
    for _ in range(NEWTON_STEPS):
        s1, s2 = normal_stress(gel, temperature, x, lt)
        w1, w2 = normal_energy(gel, temperature, x, lt)
        k1, k2 = normal_stiffness(gel, temperature, x, lt)
        res = np.array([s1 - s2, (w2 - w1) - s1 * (x[1] - x[0])])
        jac = np.array([[k1, -k2], [-k1 * (x[1] - x[0]), s2 - s1]])
        step = np.linalg.solve(jac, res)
        x = x - step
        if np.all(np.abs(step) <= 1e-14 * x):
            break
    return float(x[0]), float(x[1])


def maxwell_porosities(gel: Gel, temperature: float, lambda_t: float) -> tuple[float, float]:
    """(phi_shell, phi_core) of the coexisting pair: phi = 1 - 1/(n lambda_t^2)."""
    n1, n2 = maxwell_pair(gel, temperature, lambda_t)
    lt2 = float(lambda_t) ** 2
    return 1.0 - 1.0 / (n1 * lt2), 1.0 - 1.0 / (n2 * lt2)
