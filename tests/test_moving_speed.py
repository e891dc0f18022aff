"""The moving grid's speed at a thin running front (issue 12: a custom gel, Omega = 300 with
ANB's chi, 302 -> 308 K, 50 % dose, validated in under 10 s).

Measured (benchmarks/moving_mesh.py --section speed, docs/moving_mesh.md sec. 7): the ALE
Jacobian's time column by a forward difference that moved the fastest node 1e-7 of the
smallest cell was rounding noise, up to 100x its size, at the front's cells (0.04 ell wide);
with it RODASP lost its order and took ~1e-6 steps (41,900 steps to t = 0.02 at ell = 1e-4,
400 cells; 141,600 to t = 0.1).  Now: a central difference at 0.1 of a cell, 860 steps
(1,520 attempts) to t = 0.02 at 200 cells, and the 50 % dose at 200 and 400 cells 0.06 % apart.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
from moving_support import running_state

from solver.equilibrium import equilibrium
from solver.front.result import fraction_radius
from solver.full import moving, simulate
from solver.full.system import JAC_ANALYTIC, MOVING, linearize
from solver.gel import ANB

CUSTOM = replace(ANB, omega=300.0, name="custom")
ELL = 1e-4


def test_time_column_at_a_running_thin_front() -> None:
    """The analytic Jacobian's time column (df/dt at fixed radii) against central
    differences at 0.03 of a cell, at t = 0.005 (the front's cells 0.04 ell): their own
    rounding noise is ~1e-3 of the column there (it falls as 1/step: 4e-2 at 3e-4 of a
    cell, 1e-3 at 3e-2); the old column was off by up to 145x."""
    n = 200
    ws, y, par = running_state(CUSTOM, n, ELL, 0.005, 1e-5, 1e-9)
    vel = ws.geo[moving.ale.R_VEL]
    h = np.diff(ws.geo[0])
    assert np.abs(vel).max() > 0.0 and h.min() < 0.1 * ELL  # a running front, thin cells
    f = np.zeros(n + 1)
    assert linearize(MOVING, y, f, par, ws.geo, ws.work, ws.lower, ws.upper, ws.jband, ws.jc,
                     ws.jd, ws.je, ws.ytmp, ws.ftmp, ws.scale, JAC_ANALYTIC) > 0
    d = 0.03 * h.min() / np.abs(vel).max()
    yp, ym = y.copy(), y.copy()
    yp[n] += d
    ym[n] -= d
    ref = (ws.rhs(yp, par) - ws.rhs(ym, par))[:n] / (2 * d)
    assert np.abs(ws.jc[:, 0] - ref).max() < 1e-2 * np.abs(ref).max()


def test_custom_gel_direct_run_is_fast_and_converged() -> None:
    """The Omega = 300 gel at ell = 1e-4 to past its 50 % dose (0.0142): the attempted
    steps (measured 1,520 at 200 cells, 1,380 at 400; 53,000 before at 400) and the gap
    between 200 and 400 cells (the planner's numerical bound; measured 0.06 %, the issue
    asks for at most 5 %; 0.5 % allowed here)."""
    a50 = fraction_radius(equilibrium(CUSTOM, 302.0).stretch, 0.5)
    times = []
    for n in (200, 400):
        res = simulate(CUSTOM, 302.0, 308.0, until=0.02, grid="moving", n=n,
                       interfacial_length=ELL, rtol=1e-5, every=0.001)
        assert res.diagnostics["steps"] + res.diagnostics["rejected"] < 4000  # attempts
        assert np.max(res.solid_error) < 1e-12
        times.append(res.time_to_radius(a50))
    assert abs(times[0] / times[1] - 1.0) < 5e-3
    assert abs(times[1] / 0.014184 - 1.0) < 2e-3  # benchmarked at 400 cells
