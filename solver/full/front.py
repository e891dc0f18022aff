"""Front tracking and spinodal-collapse detection on porosity profiles.

A *front* is reported where the steepest single-cell porosity step is sharp: the step
between neighbouring cells k, k+1 is at least SHARP_FRACTION of the porosity change
across WINDOW cells either side of it, and that change is at least MIN_JUMP.  Its
position is the sub-cell radius where the profile crosses the mid level between the two
plateaus (linear interpolation between the two cell centres), so it moves continuously
through the grid.  The steepest step must have OUTER_CELLS cells outside it, so the jump
between the edge value and the last cell is never counted.

With the interfacial energy the front is a resolved layer several cells wide: the caller
widens ``window`` to span it (the sharpness test scales with it) and the position is the
crossing of the mid level nearest the steepest step.
"""

from __future__ import annotations

import numpy as np
from numba import njit

MIN_JUMP = 0.05
SHARP_FRACTION = 0.4
WINDOW = 3
OUTER_CELLS = 1  # cells a front needs outside its steepest step
COLLAPSE_STEP = 0.15  # a single-cell porosity step this large is a grid-scale jump


def locate_front(radii: np.ndarray, phi: np.ndarray,
                 window: int = WINDOW) -> tuple[float, float]:
    """(R_f, jump) of the sharp front in a profile, or (nan, nan) without one.

    ``radii`` are the cell-centre radii r (increasing), ``phi`` the cell porosities; the
    jump is phi just inside minus phi just outside (> 0 for a swollen core).  ``window``
    (cells either side) > WINDOW looks for a resolved (diffuse) front of that half-width.
    """
    n = phi.size
    if n < 2 * window + 2:
        return np.nan, np.nan
    step = np.diff(phi)
    usable = step[: n - 1 - OUTER_CELLS]
    k = int(np.argmax(np.abs(usable)))
    inner = phi[max(0, k - window)]
    outer = phi[min(n - 1, k + 1 + window)]
    jump = inner - outer
    if abs(jump) < MIN_JUMP or abs(step[k]) < SHARP_FRACTION * WINDOW / window * abs(jump):
        return np.nan, np.nan
    mid = 0.5 * (inner + outer)
    if window > WINDOW:
        k = _nearest_crossing(phi, mid, k, window)
    frac = (mid - phi[k]) / step[k] if step[k] != 0.0 else 0.5
    frac = min(max(frac, 0.0), 1.0)
    return float(radii[k] + frac * (radii[k + 1] - radii[k])), float(jump)


def _nearest_crossing(phi: np.ndarray, level: float, k: int, window: int) -> int:
    """Index j nearest k (within window) with ``level`` between phi[j] and phi[j + 1]."""
    for d in range(window + 1):
        for j in (k - d, k + d):
            if 0 <= j < phi.size - 1 and (phi[j] - level) * (phi[j + 1] - level) <= 0.0:
                return j
    return k


def diffuse_window(interfacial_length: float, n: int) -> int:
    """Half-width in cells of a resolved interface (about 8 ell in the dry coordinate,
    docs/interfacial.md), at least WINDOW."""
    return max(WINDOW, WINDOW + int(np.ceil(8.0 * interfacial_length * n)))


def moving_window(nodes: np.ndarray, phi: np.ndarray, interfacial_length: float) -> int:
    """:func:`diffuse_window` on a non-uniform dry grid: the cells within 8 ell of the
    steepest porosity step, at least WINDOW."""
    if phi.size < 2 or interfacial_length <= 0.0:
        return WINDOW
    centre = 0.5 * (nodes[:-1] + nodes[1:])
    k = int(np.argmax(np.abs(np.diff(phi))))
    x = 0.5 * (centre[k] + centre[k + 1])
    inside = int(np.count_nonzero(np.abs(centre - x) <= 8.0 * interfacial_length))
    return max(WINDOW, WINDOW + (inside + 1) // 2)


@njit(cache=True)
def interfaces(phi):
    """Number of separate sharp interfaces: runs of grid-scale porosity steps
    (single-cell steps >= COLLAPSE_STEP), runs closer than WINDOW cells counting as one."""
    count = 0
    last = -(WINDOW + 2)
    for k in range(phi.size - 1):
        if abs(phi[k + 1] - phi[k]) >= COLLAPSE_STEP:
            if k - last > WINDOW:
                count += 1
            last = k
    return count


def spinodal_collapse(phi: np.ndarray) -> bool:
    """True when the profile holds two or more separate sharp interfaces: interior cells
    have collapsed at grid scale away from the invading front (concentric collapsed shells,
    appendix Other numerical simulations), i.e. spinodal decomposition."""
    return interfaces(phi) >= 2
