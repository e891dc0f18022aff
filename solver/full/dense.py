"""RODASP's continuous output from the stages of an accepted step (the moving grid's outputs).

Steinebach's RODASP carries a dense output of order 3 built from the step's own stages k_i
(G. Steinebach, "Improvement of Rosenbrock-Wanner method RODASP", 2020, and its MATLAB
``rodasp2.m``, coefficients c, d of ``coeff_rodasp``):

    y(t0 + s h) = y0 + s sum_i (b_i + (s - 1) (c_i + s d_i)) k_i,

with b the method's weights.  rosenbrock.py stores the transformed stages U = Gamma k
(Hairer & Wanner IV.7), so the weights become (b, c, d) Gamma^-1.  Unlike the cubic Hermite
of the step's end values and slopes f(y0), f(y1), it never evaluates f off the step: on the
moving grid's thin cells f is stiff (the Korteweg term), and the slopes' O(rtol) state errors,
amplified by the stiffness, gave the Hermite interpolant porosity errors up to 0.35 between
steps (docs/moving_mesh.md sec. 8), which is why outputs used to land on steps there.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from .rosenbrock import _ALPHA, _BETA, GAMMA
from .system import porosity

_C = np.array([-40.98639964388325, -10.36668980524365, 44.66751816647147, 4.13001572709988,
               2.55555555555556, 0.0])
_D = np.array([73.75018659483291, 18.54063799119389, -81.66902074619779, -6.84402606205123,
               -3.77777777777778, 0.0])


def _transformed_weights() -> tuple[np.ndarray, np.ndarray]:
    """(c, d) Gamma^-1: the dense output's weights on the transformed stages."""
    gam = _BETA - _ALPHA
    np.fill_diagonal(gam, GAMMA)
    ginv = np.linalg.inv(gam)
    return _C @ ginv, _D @ ginv


DENSE_C, DENSE_D = _transformed_weights()


@njit(cache=True)
def stage_output(grid, geo, y0, y1, u, mcoef, cw, dw, s, t, out, phi):
    """Moving-grid state at t = t0 + s h of the accepted step y0 -> y1 (transformed stages
    in rows 0..stages-1 of ``u``, weights ``mcoef`` = b Gamma^-1, ``cw``, ``dw``) into
    ``out`` (its last entry, the time, exactly t), its porosities into ``phi``; linear in s
    where the polynomial leaves the physical range.  Returns True if the polynomial was
    used."""
    n = out.size
    for i in range(n):
        out[i] = y0[i]
    for j in range(mcoef.size):
        w = s * (mcoef[j] + (s - 1.0) * (cw[j] + s * dw[j]))
        if w != 0.0:
            uj = u[j]
            for i in range(n):
                out[i] += w * uj[i]
    out[n - 1] = t
    porosity(grid, out, geo, phi)
    for i in range(phi.size):
        if not (0.0 < phi[i] < 1.0):
            for j in range(n):
                out[j] = (1.0 - s) * y0[j] + s * y1[j]
            out[n - 1] = t
            porosity(grid, out, geo, phi)
            return False
    return True

