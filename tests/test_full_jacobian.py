"""The analytic Jacobians equal finite differences (the guard for new stress terms).

Measured: analytic vs central differences (step 1e-5 of a cell) agree to ~1e-8 relative
(row-scaled) on both grids and both permeability laws at a front state; the colored
one-sided differences used by jacobian='fd' (step 1e-8) agree to ~1e-4.
"""

from __future__ import annotations

import numpy as np
import pytest
from grid_support import every_grid, fixed_grids
from jacobian_support import dense_jacobian

from solver.equilibrium import equilibrium
from solver.full.grids import GRIDS
from solver.full.integrate import Segment, Stats, StepControl, Workspace, run_implicit
from solver.full.kernels import KernelParams
from solver.full.system import JAC_ANALYTIC, JAC_FD, linearize
from solver.gel import ANB

N = 40


@pytest.mark.parametrize("code", [0, 1])
@pytest.mark.parametrize("name", fixed_grids())
def test_analytic_jacobian_matches_finite_differences(name: str, code: int) -> None:
    """Grid-specific setup (uniform geometry, no time column): the moving grid's Jacobian,
    with its node velocities and time column, is
    tests/test_moving_mesh.py::test_moving_jacobian_matches_central_differences."""
    mod, grid = GRIDS[name].module, GRIDS[name].code
    eq = equilibrium(ANB, 302, "swollen")
    geo = mod.geometry(N)
    par = KernelParams(ANB.omega, ANB.chi0(308), ANB.chi1(308), code, 1.5 * code, 0.0)
    ws = Workspace(grid, geo)
    y0 = mod.state_from_profile(eq.stretch, np.full(N, eq.porosity))
    y = run_implicit(ws, y0, [Segment(0.0, 0.01, 308.0, par)], np.array([0.01]),
                     lambda t, y: None, StepControl(1e-7, 1e-10, 100000), None, Stats())
    mats = {}
    for mode in (JAC_ANALYTIC, JAC_FD):
        f = np.zeros(N)
        assert linearize(grid, y, f, par, geo, ws.work, ws.lower, ws.upper, ws.jband, ws.jc,
                         ws.jd, ws.je, ws.ytmp, ws.ftmp, ws.scale, mode) > 0
        np.testing.assert_allclose(f, ws.rhs(y, par), rtol=1e-12, atol=1e-12)
        mats[mode] = dense_jacobian(ws)
    central = np.zeros((N, N))
    for j in range(N):
        h = 1e-5 * (y[j] - (y[j - 1] if j else 0.0))
        yp, ym = y.copy(), y.copy()
        yp[j] += h
        ym[j] -= h
        central[:, j] = (ws.rhs(yp, par) - ws.rhs(ym, par)) / (2 * h)
    scale = np.abs(central).max(axis=1, keepdims=True)
    assert np.max(np.abs(mats[JAC_ANALYTIC] - central) / scale) < 1e-6
    assert np.max(np.abs(mats[JAC_FD] - central) / scale) < 5e-4


@pytest.mark.parametrize(("grid", "settings"), every_grid())
def test_fd_jacobian_option_gives_the_same_run(grid: str, settings: dict) -> None:
    from solver.full import simulate

    a = simulate(ANB, 302, 308, until=0.01, n=40, grid=grid, every=0.01, **settings)
    b = simulate(ANB, 302, 308, until=0.01, n=40, grid=grid, every=0.01, jacobian="fd",
                 **settings)
    assert a.radius[-1] == pytest.approx(b.radius[-1], rel=1e-5)
