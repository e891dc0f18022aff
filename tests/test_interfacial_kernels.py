"""The interfacial term in the full solver's kernels (docs/interfacial.md).

Measured: the Lagrangian analytic Jacobian with the term equals central differences to 4e-10
(constant permeability) and 2e-9 (power law), row-scaled; the colored finite-difference
Jacobian of the Eulerian grid, whose border grows to (s_{n-2}, s_{n-1}, a), to 1e-7.  The
Korteweg kernel reproduces ell^2 Lap_rho J of a smooth profile to O(h^2) in the interior.
"""

from __future__ import annotations

import numpy as np
import pytest
from jacobian_support import dense_jacobian

from solver.equilibrium import equilibrium
from solver.errors import ParameterError
from solver.full import eulerian, lagrangian, simulate
from solver.full.integrate import Segment, Stats, StepControl, Workspace, run_implicit
from solver.full.kernels import KernelParams, korteweg
from solver.full.system import JAC_ANALYTIC, JAC_FD, linearize
from solver.gel import ANB

N = 40
ELL = 0.05


def _front_state(mod: object, grid: int, code: int) -> tuple:
    eq = equilibrium(ANB, 302, "swollen")
    geo = mod.geometry(N)  # type: ignore[attr-defined]
    par = KernelParams(ANB.omega, ANB.chi0(308), ANB.chi1(308), code, 1.5 * code, ELL**2)
    ws = Workspace(grid, geo, interfacial=True)
    y0 = mod.state_from_profile(eq.stretch, np.full(N, eq.porosity))  # type: ignore[attr-defined]
    y = run_implicit(ws, y0, [Segment(0.0, 0.03, 308.0, par)], np.array([0.03]),
                     lambda t, y: None, StepControl(1e-7, 1e-10, 100000, JAC_FD), None,
                     Stats())
    return ws, geo, par, y


def _central(ws: Workspace, par: np.ndarray, y: np.ndarray, lagr: bool) -> np.ndarray:
    out = np.zeros((N, N))
    for j in range(N):
        h = 1e-5 * ((y[j] - (y[j - 1] if j else 0.0)) if lagr else abs(y[j]))
        yp, ym = y.copy(), y.copy()
        yp[j] += h
        ym[j] -= h
        out[:, j] = (ws.rhs(yp, par) - ws.rhs(ym, par)) / (2 * h)
    return out


@pytest.mark.parametrize("code", [0, 1])
def test_lagrangian_analytic_jacobian_with_term(code: int) -> None:
    ws, geo, par, y = _front_state(lagrangian, 1, code)
    assert (ws.lower, ws.upper) == (2, 2)
    central = _central(ws, par, y, True)
    scale = np.abs(central).max(axis=1, keepdims=True)
    f = np.zeros(N)
    assert linearize(1, y, f, par, geo, ws.work, ws.lower, ws.upper, ws.jband, ws.jc, ws.jd,
                     ws.je, ws.ytmp, ws.ftmp, ws.scale, JAC_ANALYTIC) > 0
    np.testing.assert_allclose(f, ws.rhs(y, par), rtol=1e-12, atol=1e-12)
    assert np.max(np.abs(dense_jacobian(ws) - central) / scale) < 1e-7


def test_eulerian_fd_jacobian_with_wider_border() -> None:
    ws, geo, par, y = _front_state(eulerian, 0, 0)
    assert (ws.lower, ws.upper, ws.je.shape[0]) == (2, 2, 3)
    central = _central(ws, par, y, False)
    scale = np.abs(central).max(axis=1, keepdims=True)
    f = np.zeros(N)
    assert linearize(0, y, f, par, geo, ws.work, ws.lower, ws.upper, ws.jband, ws.jc, ws.jd,
                     ws.je, ws.ytmp, ws.ftmp, ws.scale, JAC_FD) > 0
    assert np.max(np.abs(dense_jacobian(ws) - central) / scale) < 1e-5


def test_korteweg_kernel_is_the_dry_laplacian() -> None:
    n = 400
    nodes = np.arange(n + 1) / n
    mid = np.cbrt(0.5 * (nodes[:-1] ** 3 + nodes[1:] ** 3))
    jac = 5.0 + 3.0 * np.cos(np.pi * mid)  # dJ/drho = 0 at rho = 0 and 1
    exact = -3.0 * np.pi**2 * np.cos(np.pi * mid) - 6.0 * np.pi * np.sin(np.pi * mid) / mid
    q = np.zeros(n)
    korteweg(jac, nodes, mid, np.diff(nodes**3), 1.0, n, q)
    inner = slice(n // 10, n - 1)
    assert np.max(np.abs(q[inner] - exact[inner])) < 5e-3 * np.max(np.abs(exact))


def test_zero_length_is_the_papers_model() -> None:
    """ell = 0 (the default) runs the paper's kernels unchanged: identical results."""
    kw = dict(until=0.01, grid="lagrangian", n=60, rtol=1e-6)
    base = simulate("ANB", 302, 308, **kw)
    zero = simulate("ANB", 302, 308, interfacial_length=0.0, **kw)
    assert np.array_equal(base.radius, zero.radius) and np.array_equal(base.phi, zero.phi)
    eq = equilibrium(ANB, 302, "swollen")
    geo = lagrangian.geometry(N)
    y = lagrangian.state_from_profile(eq.stretch, np.full(N, eq.porosity)) * (
        1.0 - 0.01 * np.linspace(0, 1, N) ** 2)
    par0 = KernelParams(ANB.omega, ANB.chi0(308), ANB.chi1(308), 0, 0.0, 0.0)
    ws = Workspace(1, geo)
    # the kernels read ell^2 by name: a positive one changes dr/dt, zero is the paper's
    assert not np.array_equal(ws.rhs(y, par0), ws.rhs(y, par0._replace(ell2=1e-4)))


@pytest.mark.parametrize("bad", [-0.01, 0.5, float("nan"), True, "x"])
def test_invalid_length_is_refused(bad: object) -> None:
    with pytest.raises(ParameterError, match="interfacial_length"):
        simulate("ANB", 302, 308, until=0.01, interfacial_length=bad)  # type: ignore[arg-type]
