"""Numba kernels of the moving grid's rezoning (solver/full/moving.py): the target mesh and
the monotone remap.  They run every few steps, so they stay in compiled code; the PCHIP
kernel is scipy.interpolate.PchipInterpolator's construction (Fritsch-Butland weighted
harmonic mean slopes, shape-preserving one-sided end slopes), checked against it in
tests/test_moving_mesh.py.
"""

from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True)
def _end_slope(h0, h1, m0, m1):
    """scipy's one-sided three-point end slope with the shape-preserving limits."""
    d = ((2.0 * h0 + h1) * m0 - h0 * m1) / (h0 + h1)
    if np.sign(d) != np.sign(m0):
        return 0.0
    if np.sign(m0) != np.sign(m1) and abs(d) > abs(3.0 * m0):
        return 3.0 * m0
    return d


@njit(cache=True)
def pchip(x, y, xi, out):
    """Monotone piecewise cubic Hermite interpolant of (x, y) at the sorted points xi."""
    n = x.size
    h = np.empty(n - 1)
    m = np.empty(n - 1)
    for k in range(n - 1):
        h[k] = x[k + 1] - x[k]
        m[k] = (y[k + 1] - y[k]) / h[k]
    d = np.zeros(n)
    for k in range(1, n - 1):
        if m[k - 1] * m[k] > 0.0:
            w1 = 2.0 * h[k] + h[k - 1]
            w2 = h[k] + 2.0 * h[k - 1]
            d[k] = (w1 + w2) / (w1 / m[k - 1] + w2 / m[k])
    if n == 2:
        d[0] = d[1] = m[0]
    else:
        d[0] = _end_slope(h[0], h[1], m[0], m[1])
        d[n - 1] = _end_slope(h[n - 2], h[n - 3], m[n - 2], m[n - 3])
    k = 0
    for i in range(xi.size):
        t = xi[i]
        while k < n - 2 and t > x[k + 1]:
            k += 1
        s = (t - x[k]) / h[k]
        s2 = s * s
        s3 = s2 * s
        out[i] = ((2.0 * s3 - 3.0 * s2 + 1.0) * y[k] + (s3 - 2.0 * s2 + s) * h[k] * d[k]
                  + (-2.0 * s3 + 3.0 * s2) * y[k + 1] + (s3 - s2) * h[k] * d[k + 1])


@njit(cache=True)
def remap(y, old, new, out):
    """Node radii on ``new`` from y on ``old`` (see moving.remap): PCHIP of the cumulative
    fluid volume W(s) = r^3 - s over s = rho^3; W(1) and the radius exact."""
    n = y.size
    s_old = np.empty(n + 1)
    w_old = np.empty(n + 1)
    s_old[0] = 0.0
    w_old[0] = 0.0
    for k in range(n):
        s_old[k + 1] = old[k + 1] ** 3
        w_old[k + 1] = y[k] ** 3 - s_old[k + 1]
    s_new = np.empty(n)
    for k in range(n):
        s_new[k] = new[k + 1] ** 3
    w_new = np.empty(n)
    pchip(s_old, w_old, s_new, w_new)
    for k in range(n - 1):
        out[k] = np.cbrt(w_new[k] + s_new[k])
    out[n - 1] = y[n - 1]


@njit(cache=True)
def target_nodes(y, nodes, resolution, h_bulk, h_edge, h_min, grading, out):
    """Nodes equidistributing 1/h* (moving.py module doc) into ``out``; h_edge <= 0: no
    edge refinement; h* >= h_min."""
    n = nodes.size - 1
    centre = np.empty(n)
    lj = np.empty(n)
    prev3 = 0.0
    for c in range(n):
        r3 = y[c] ** 3
        centre[c] = 0.5 * (nodes[c] + nodes[c + 1])
        lj[c] = np.log((r3 - prev3) / (nodes[c + 1] ** 3 - nodes[c] ** 3))
        prev3 = r3
    h = np.empty(n)
    for c in range(n):
        g = 0.0
        if c > 0:
            g = abs(lj[c] - lj[c - 1]) / (centre[c] - centre[c - 1])
        if c < n - 1:
            g = max(g, abs(lj[c + 1] - lj[c]) / (centre[c + 1] - centre[c]))
        hc = h_bulk
        if g * hc > resolution:
            hc = resolution / g
        if h_edge > 0.0:
            hc = min(hc, h_edge + grading * (1.0 - centre[c]))
        h[c] = max(hc, h_min)
    for c in range(1, n):
        h[c] = min(h[c], h[c - 1] + grading * (centre[c] - centre[c - 1]))
    for c in range(n - 2, -1, -1):
        h[c] = min(h[c], h[c + 1] + grading * (centre[c + 1] - centre[c]))
    # cumulative monitor, piecewise linear in 1/h between 0, the centres and 1
    xs = np.empty(n + 2)
    cum = np.empty(n + 2)
    xs[0] = 0.0
    cum[0] = 0.0
    xs[n + 1] = 1.0
    prev_x = 0.0
    prev_d = 1.0 / h[0]
    for c in range(n + 1):
        x = centre[c] if c < n else 1.0
        dens = 1.0 / h[c] if c < n else 1.0 / h[n - 1]
        xs[c + 1] = x
        cum[c + 1] = cum[c] + 0.5 * (dens + prev_d) * (x - prev_x)
        prev_x = x
        prev_d = dens
    total = cum[n + 1]
    j = 0
    out[0] = 0.0
    for k in range(1, n):
        target = total * k / n
        while cum[j + 1] < target:
            j += 1
        f = (target - cum[j]) / (cum[j + 1] - cum[j])
        out[k] = xs[j] + f * (xs[j + 1] - xs[j])
    out[n] = 1.0


@njit(cache=True)
def offset(nodes, new):
    """Largest |new - nodes| in units of the smaller adjacent cell."""
    n = nodes.size - 1
    worst = 0.0
    for k in range(1, n):
        cell = min(nodes[k] - nodes[k - 1], nodes[k + 1] - nodes[k])
        worst = max(worst, abs(new[k] - nodes[k]) / cell)
    return worst


@njit(cache=True)
def _agree(raw, prev, nodes, agreement):
    """moving._agree in compiled code: two velocity estimates agree, in cells per time."""
    n = nodes.size - 1
    big = 1e-300
    diff = 0.0
    for k in range(n + 1):
        if k == 0:
            cell = nodes[1] - nodes[0]
        elif k == n:
            cell = nodes[n] - nodes[n - 1]
        else:
            cell = min(nodes[k] - nodes[k - 1], nodes[k + 1] - nodes[k])
        big = max(big, abs(raw[k]) / cell)
        diff = max(diff, abs(raw[k] - prev[k]) / cell)
    return diff <= agreement * big


@njit(cache=True)
def mesh_check(y, nodes, resolution, h_bulk, h_edge, h_min, grading, iterations, tolerance,
               agreement, horizon, hist, scal, mesh, velocity):
    """One check of the moving grid (moving.Rezoner.__call__) in one compiled call.

    ``y`` the state (node radii, then t; remapped in place when the mesh is off),
    ``nodes`` the current nodes at t.  Writes the mesh to keep (the target when remapped,
    else ``nodes``) to ``mesh`` and its node velocity to ``velocity``; returns True when
    it remapped.  ``hist`` (2, n + 1): the last target and the last raw velocity; ``scal``:
    last check time, has a last target, has a raw velocity, its interval (all kept between
    calls; zeros: none yet).
    """
    n = nodes.size - 1
    t = y[n]
    radii = y[:n]
    new = np.empty(n + 1)
    nxt = np.empty(n + 1)
    tmp = np.empty(n)
    target_nodes(radii, nodes, resolution, h_bulk, h_edge, h_min, grading, new)
    for _ in range(iterations):  # towards the fixed point, independent of the mesh
        remap(radii, nodes, new, tmp)
        target_nodes(tmp, new, resolution, h_bulk, h_edge, h_min, grading, nxt)
        new[:] = nxt
    velocity[:] = 0.0
    off = offset(nodes, new) > tolerance
    if off:
        remap(radii, nodes, new, tmp)
        radii[:] = tmp
    if scal[1] > 0.0 and t > scal[0]:
        dt = t - scal[0]
        raw = (new - hist[0]) / dt
        # follow the target only while it translates steadily: two successive estimates
        # agree (a nucleating front makes the target jump, not move)
        if scal[2] > 0.0 and _agree(raw, hist[1], new, agreement):
            # the target's mean velocity over the next interval (as long as the last),
            # extrapolated linearly from the last two intervals' means
            velocity[:] = raw + (raw - hist[1]) * (2.0 * dt) / (dt + scal[3])
            base = new if off else nodes
            worst = -np.inf
            for k in range(n):
                worst = max(worst, -(velocity[k + 1] - velocity[k]) / (base[k + 1] - base[k]))
            worst *= horizon * dt
            if worst > 0.5:
                velocity *= 0.5 / worst
        hist[1] = raw
        scal[2] = 1.0
        scal[3] = dt
    hist[0] = new
    scal[0] = t
    scal[1] = 1.0
    mesh[:] = new if off else nodes
    return off
