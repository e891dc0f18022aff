"""Test helper: the dense matrix of a workspace's structured Jacobian (band + borders)."""

from __future__ import annotations

import numpy as np

from solver.full.integrate import Workspace


def dense_jacobian(ws: Workspace) -> np.ndarray:
    """Assemble the banded block and its dense borders (jc, jd, je) into one matrix."""
    m, p = ws.jband.shape[1], ws.je.shape[0]
    out = np.zeros((m + p, m + p))
    for j in range(m):
        for i in range(max(0, j - ws.upper), min(m, j + ws.lower + 1)):
            out[i, j] = ws.jband[ws.upper + i - j, j]
    out[:m, m:], out[m:, :m], out[m:, m:] = ws.jc, ws.jd, ws.je
    return out
