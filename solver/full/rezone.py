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
def log_stretch(y, nodes, centre, lj):
    """Each cell's centre and ln J (its volume over its dry volume, eq. Jeqn) into
    ``centre`` and ``lj``: the node radii ``y`` over the dry nodes ``nodes``."""
    prev3 = 0.0
    for c in range(nodes.size - 1):
        r3 = y[c] ** 3
        centre[c] = 0.5 * (nodes[c] + nodes[c + 1])
        lj[c] = np.log((r3 - prev3) / (nodes[c + 1] ** 3 - nodes[c] ** 3))
        prev3 = r3


@njit(cache=True)
def target_nodes(y, nodes, resolution, h_bulk, h_edge, h_min, grading, out):
    """Nodes equidistributing 1/h* (moving.py module doc) into ``out``; h_edge <= 0: no
    edge refinement; h* >= h_min."""
    n = nodes.size - 1
    centre = np.empty(n)
    lj = np.empty(n)
    log_stretch(y, nodes, centre, lj)
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


# the front's history in ``scal`` (after the target's four entries): the level, its last
# position (after the check's remap) and time, its mean velocities over the last two
# intervals (newest first) and their lengths, and how long the band accelerates
S_LEVEL, S_HAS_LEVEL, S_X, S_T, S_HAS_X = 4, 5, 6, 7, 8
S_U, S_DT, S_HAS_U, S_U2, S_DT2, S_HAS_U2 = 9, 10, 11, 12, 13, 14
S_SPAN = 15
S_PV, S_PA, S_PB, S_PSPAN, S_HAS_P = 16, 17, 18, 19, 20  # the band's motion since the last
SCAL_SIZE = 21
SPAN = 2.0  # the band accelerates for this many of the last check intervals
FRONT_PLATEAU = 5.0  # interfacial lengths either side of the front moved at its velocity
FRONT_TAPER = 20.0  # then the correction falls linearly to zero over this many
FRONT_STEEP = 0.1  # a front: |d ln J / d rho| ell at least this between two cells
FRONT_AGREEMENT = 0.25  # largest relative change of the front's velocity between checks
FRONT_QUADRATIC = True  # a quadratic through three interval means (True), else a line
FRONT_DRIFT = 0.25  # cells the front may move against the band in an interval (else restart)


@njit(cache=True)
def front_position(y, nodes, level, ell):
    """(x, level, steepness): where ln J, linear between the cell centres, crosses ``level``
    (NaN: the midpoint of the steepest pair of cells) nearest that pair; x = -1 without a
    crossing.  Steepness: the largest |d ln J / d rho| between neighbours, times ell."""
    n = nodes.size - 1
    lj = np.empty(n)
    centre = np.empty(n)
    log_stretch(y, nodes, centre, lj)
    best = -1.0
    cs = 0
    for c in range(n - 1):
        g = abs(lj[c + 1] - lj[c]) / (centre[c + 1] - centre[c])
        if g > best:
            best = g
            cs = c
    if np.isnan(level):
        level = 0.5 * (lj[cs] + lj[cs + 1])
    x = -1.0
    dist = n + 1
    for c in range(n - 1):
        a = lj[c] - level
        b = lj[c + 1] - level
        if (a <= 0.0 < b or b <= 0.0 < a) and abs(c - cs) < dist:
            dist = abs(c - cs)
            f = a / (a - b)
            x = centre[c] + f * (centre[c + 1] - centre[c])
    return x, level, best * ell




@njit(cache=True)
def _interval_row(s0, s1):
    """The mean of 1, s, s^2 over [s0, s1]."""
    return 1.0, 0.5 * (s0 + s1), (s0 * s0 + s0 * s1 + s1 * s1) / 3.0


@njit(cache=True)
def front_motion(u, d1, u1, d2, u2, d3, quadratic):
    """(velocity, acceleration, its rate) now (s = 0) of the front from its mean velocities
    u, u1, u2 over the last three intervals [-d1, 0], [-d1 - d2, -d1], [-d1 - d2 - d3,
    -d1 - d2]: the quadratic with those means, or (``quadratic`` False) the line through
    the last two."""
    if not quadratic:
        return u + (u - u1) * d1 / (d1 + d2), (u - u1) * 2.0 / (d1 + d2), 0.0
    # in units of d1 (conditioning), Cramer's rule on the 3 x 3 system of the means
    a0, b0, c0 = _interval_row(-1.0, 0.0)
    a1, b1, c1 = _interval_row(-1.0 - d2 / d1, -1.0)
    a2, b2, c2 = _interval_row(-1.0 - (d2 + d3) / d1, -1.0 - d2 / d1)
    det = a0 * (b1 * c2 - b2 * c1) - b0 * (a1 * c2 - a2 * c1) + c0 * (a1 * b2 - a2 * b1)
    p = (u * (b1 * c2 - b2 * c1) - b0 * (u1 * c2 - u2 * c1) + c0 * (u1 * b2 - u2 * b1)) / det
    q = (a0 * (u1 * c2 - u2 * c1) - u * (a1 * c2 - a2 * c1) + c0 * (a1 * u2 - a2 * u1)) / det
    r = (a0 * (b1 * u2 - b2 * u1) - b0 * (a1 * u2 - a2 * u1) + u * (a1 * b2 - a2 * b1)) / det
    return p, q / d1, 2.0 * r / (d1 * d1)


@njit(cache=True)
def follow_front(before, after, nodes, mesh, t, ell, agreement, velocity, accel, jerk, scal):
    """Move the band within FRONT_PLATEAU ell of the front with the front
    (docs/moving_mesh.md sec. 7.2).

    The front is the level set of ln J through the steepest pair of cells (the level kept
    from its first detection), located on the state ``before`` the check's remap (on
    ``nodes``) and again ``after`` it (on ``mesh``, the reference for the next interval).
    From its mean velocities over the last three intervals (two at first) it gets its
    velocity, acceleration and the acceleration's rate now, which replace the nodes' at the
    front; the change falls linearly to zero over FRONT_TAPER ell.  Only while the front is
    inside the bead by the band's width and successive velocities agree within
    ``agreement``; when the front moved more than FRONT_DRIFT of a cell against the band
    over the last interval (a coarse mesh's level crossing is biased by where it sits in
    its cell, and the extrapolation can amplify that into an oscillation: HHT, ell = 3e-5,
    200 cells), the history restarts.  Returns True when it moved the band.
    """
    if not ell > 0.0:
        return False
    reach = (FRONT_PLATEAU + FRONT_TAPER) * ell
    level = scal[S_LEVEL] if scal[S_HAS_LEVEL] > 0.0 else np.nan
    x, level, steep = front_position(before, nodes, level, ell)
    if not (steep >= FRONT_STEEP and reach <= x <= 1.0 - reach):
        scal[S_HAS_P] = 0.0
        scal[S_HAS_X] = 0.0
        scal[S_HAS_U] = 0.0
        scal[S_HAS_U2] = 0.0
        scal[S_HAS_LEVEL] = 0.0
        return False
    scal[S_LEVEL] = level
    scal[S_HAS_LEVEL] = 1.0
    done = False
    if scal[S_HAS_X] > 0.0 and t > scal[S_T]:
        dt = t - scal[S_T]
        u = (x - scal[S_X]) / dt
        if scal[S_HAS_P] > 0.0:  # how far the front moved against the band, in cells
            sa = min(dt, scal[S_PSPAN])
            moved = (scal[S_PV] * dt + scal[S_PA] * sa * (dt - 0.5 * sa)
                     + scal[S_PB] * sa * sa * (dt / 2.0 - sa / 3.0))
            k = 0
            while k < nodes.size - 2 and nodes[k + 1] < x:
                k += 1
            if abs(u * dt - moved) > FRONT_DRIFT * (nodes[k + 1] - nodes[k]):
                scal[S_HAS_U] = 0.0
        scal[S_HAS_P] = 0.0
        u1, u2 = scal[S_U], scal[S_U2]
        if scal[S_HAS_U] > 0.0 and abs(u - u1) <= agreement * max(abs(u), abs(u1)):
            quadratic = (FRONT_QUADRATIC and scal[S_HAS_U2] > 0.0
                         and abs(u1 - u2) <= agreement * max(abs(u1), abs(u2)))
            v0, a0, b0 = front_motion(u, dt, u1, scal[S_DT], u2, scal[S_DT2], quadratic)
            n = mesh.size - 1
            k = 0
            while k < n - 1 and mesh[k + 1] < x:
                k += 1
            f = (x - mesh[k]) / (mesh[k + 1] - mesh[k])
            cv = v0 - (velocity[k] + f * (velocity[k + 1] - velocity[k]))
            ca = a0 - (accel[k] + f * (accel[k + 1] - accel[k]))
            cb = b0 - (jerk[k] + f * (jerk[k + 1] - jerk[k]))
            for j in range(1, n):
                d = abs(mesh[j] - x) / ell
                w = 0.0
                if d <= FRONT_PLATEAU:
                    w = 1.0
                elif d < FRONT_PLATEAU + FRONT_TAPER:
                    w = (FRONT_PLATEAU + FRONT_TAPER - d) / FRONT_TAPER
                velocity[j] += cv * w
                accel[j] += ca * w
                jerk[j] += cb * w
            done = True
            scal[S_PV], scal[S_PA], scal[S_PB] = v0, a0, b0
            scal[S_PSPAN] = SPAN * dt
            scal[S_HAS_P] = 1.0
        scal[S_U2] = u1
        scal[S_DT2] = scal[S_DT]
        scal[S_HAS_U2] = scal[S_HAS_U]
        scal[S_U] = u
        scal[S_DT] = dt
        scal[S_HAS_U] = 1.0
    xa, _, _ = front_position(after, mesh, level, ell)
    scal[S_X] = xa if xa > 0.0 else x
    scal[S_T] = t
    scal[S_HAS_X] = 1.0
    return done


@njit(cache=True)
def shrink(velocity, accel, jerk, base, horizon, span):
    """Scale the node motion (velocity; acceleration and its rate for a time ``span``) down
    so that no cell of ``base`` halves within ``horizon``."""
    n = base.size - 1
    sa = min(horizon, span)
    travel = sa * (horizon - 0.5 * sa)
    travel3 = sa * sa * (horizon / 2.0 - sa / 3.0)
    worst = -np.inf
    for k in range(n):  # (the mean rate over the horizon: with A = B = 0 that of V exactly)
        worst = max(worst, -((velocity[k + 1] - velocity[k])
                             + (accel[k + 1] - accel[k]) * (travel / horizon)
                             + (jerk[k + 1] - jerk[k]) * (travel3 / horizon))
                    / (base[k + 1] - base[k]))
    worst *= horizon
    if worst > 0.5:
        for k in range(n + 1):
            velocity[k] *= 0.5 / worst
            accel[k] *= 0.5 / worst
            jerk[k] *= 0.5 / worst


# the mesh check's settings, one float array (mesh_params): MeshOptions and the rezoner's
P_RESOLUTION, P_H_BULK, P_H_EDGE, P_H_MIN, P_GRADING, P_ITERATIONS = 0, 1, 2, 3, 4, 5
P_TOLERANCE, P_AGREEMENT, P_HORIZON, P_ELL = 6, 7, 8, 9
PARAMS_SIZE = 10


def mesh_params(resolution: float, h_bulk: float, h_edge: float, h_min: float,
                grading: float, iterations: int, tolerance: float, agreement: float,
                horizon: float, ell: float) -> np.ndarray:
    """The settings of :func:`mesh_check` as one array (indices P_*), built once per check."""
    return np.array([resolution, h_bulk, h_edge, h_min, grading, iterations, tolerance,
                     agreement, horizon, ell], dtype=np.float64)


@njit(cache=True)
def mesh_check(y, nodes, params, hist, scal, mesh, velocity, accel, jerk):
    """One check of the moving grid (moving.Rezoner.__call__) in one compiled call.

    ``y`` the state (node radii, then t; remapped in place when the mesh is off),
    ``nodes`` the current nodes at t, ``params`` the settings (:func:`mesh_params`).
    Writes the mesh to keep (the target when remapped, else ``nodes``) to ``mesh``, its
    node velocity to ``velocity`` and the band's acceleration and its rate to ``accel``
    and ``jerk`` (for the time scal[S_SPAN]); returns True when it remapped.  ``hist``
    (2, n + 1): the last target and the last raw velocity; ``scal`` (SCAL_SIZE): last
    check time, has a last target, has a raw velocity, its interval, then the front's
    history (``follow_front``; all kept between calls; zeros: none yet).
    """
    resolution, h_bulk, h_edge = params[P_RESOLUTION], params[P_H_BULK], params[P_H_EDGE]
    h_min, grading, iterations = params[P_H_MIN], params[P_GRADING], int(params[P_ITERATIONS])
    tolerance, agreement = params[P_TOLERANCE], params[P_AGREEMENT]
    horizon, ell = params[P_HORIZON], params[P_ELL]
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
    accel[:] = 0.0
    jerk[:] = 0.0
    off = offset(nodes, new) > tolerance
    before = radii.copy()
    if off:
        remap(radii, nodes, new, tmp)
        radii[:] = tmp
    base = new if off else nodes
    if scal[1] > 0.0 and t > scal[0]:
        dt = t - scal[0]
        raw = (new - hist[0]) / dt
        # follow the target only while it translates steadily: two successive estimates
        # agree (a nucleating front makes the target jump, not move)
        if scal[2] > 0.0 and _agree(raw, hist[1], new, agreement):
            # the target's mean velocity over the next interval (as long as the last),
            # extrapolated linearly from the last two intervals' means
            velocity[:] = raw + (raw - hist[1]) * (2.0 * dt) / (dt + scal[3])
        hist[1] = raw
        scal[2] = 1.0
        scal[3] = dt
    follow_front(before, radii, nodes, base, t, ell, FRONT_AGREEMENT, velocity, accel, jerk,
                 scal)
    scal[S_SPAN] = 0.0
    if scal[1] > 0.0 and t > scal[0]:
        scal[S_SPAN] = SPAN * (t - scal[0])
        shrink(velocity, accel, jerk, base, horizon * (t - scal[0]), scal[S_SPAN])
    hist[0] = new
    scal[0] = t
    scal[1] = 1.0
    mesh[:] = new if off else nodes
    return off
