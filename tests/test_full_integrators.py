"""The paper's forward Euler against the implicit integrator on the same grid.

Measured (ANB 308 -> 302 K, N = 50, t <= 0.005): forward Euler converges to the implicit
solution at first order in dt (porosity error 3.1e-4, 1.6e-4, 7.8e-5 at dt = 2e-6, 1e-6,
5e-7 on the Eulerian grid); the radius agrees to 6e-7 relative at dt = 5e-7.
"""

from __future__ import annotations

import numpy as np
import pytest
from grid_support import fixed_grids

from solver.errors import SolverError
from solver.full import simulate
from solver.gel import ANB


@pytest.fixture(scope="module")
def reference() -> dict[str, object]:
    return {g: simulate(ANB, 308, 302, until=0.005, n=50, grid=g, rtol=1e-10, atol=1e-13,
                        every=0.0005) for g in fixed_grids()}


@pytest.mark.parametrize("grid", fixed_grids())
def test_forward_euler_converges_at_first_order(grid: str, reference: dict) -> None:
    """Grid-specific: the explicit integrator runs on the grids that do not move (the
    moving grid is implicit only, SolverOptions)."""
    ref = reference[grid]
    errs = []
    for dt in (1e-6, 5e-7):
        res = simulate(ANB, 308, 302, until=0.005, n=50, grid=grid, integrator="explicit",
                       dt=dt, every=0.0005)
        assert res.diagnostics["steps"] == round(0.005 / dt)
        errs.append(np.max(np.abs(res.phi - ref.phi)))
    assert errs[0] / errs[1] == pytest.approx(2.0, rel=0.15)
    assert errs[1] < 2e-4


def test_explicit_and_implicit_radius_agree(reference: dict) -> None:
    res = simulate(ANB, 308, 302, until=0.005, n=50, integrator="explicit", dt=5e-7,
                   every=0.0005)
    ref = reference["eulerian"]
    np.testing.assert_allclose(res.radius, ref.radius, rtol=2e-6)


def test_default_explicit_step_is_stable() -> None:
    res = simulate(ANB, 302, 308, until=0.001, n=50, integrator="explicit", every=0.0005)
    assert np.all(np.isfinite(res.radius)) and res.radius[-1] < res.radius[0]


def test_default_explicit_step_follows_the_sharpening_front() -> None:
    """The stability limit falls as the front forms at the edge (N = 400): the default step
    is re-estimated every few dozen steps, so the run completes and agrees with the
    implicit one to the forward Euler O(dt) error (measured 5e-5 relative)."""
    res = simulate(ANB, 302, 308, until=0.002, n=400, integrator="explicit")
    ref = simulate(ANB, 302, 308, until=0.002, n=400)
    assert abs(res.radius[-1] - ref.radius[-1]) < 1e-4 * ref.radius[-1]


def test_unstable_explicit_step_fails_cleanly() -> None:
    with pytest.raises(SolverError, match="dt") as err:
        simulate(ANB, 308, 302, until=0.002, n=50, integrator="explicit", dt=1e-4,
                 every=0.001)
    assert err.value.diagnostics["dt"] == pytest.approx(1e-4)


def test_explicit_step_budget_is_checked_before_running() -> None:
    with pytest.raises(SolverError, match="budget"):
        simulate(ANB, 302, 308, until=0.3, n=400, integrator="explicit", dt=1e-8,
                 max_steps=1000)
